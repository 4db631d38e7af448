"""The `reconstruct` job (turntable images -> sections.json, surface.stl, report.png) and the
`run` chain (reconstruct -> mesh [-> indent a scene] in one folder), each returning the summary
text the command line prints."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from fem.experiments.scene import load_scene
from fem.geometry.build import MeshSpec
from fingertip.jobs.indent import RUN_MARKER, indent_folder
from fingertip.jobs.mesh import check_mesh, mesh_folder
from fingertip.staging import check_output_dir, claimed
from reconstruct.pipeline import reconstruct_folder


def run_reconstruct(images, out_dir, spacing_mm=(0.5, 2.0), tol_mm: float = 0.02, tip_fraction: float = 0.5,
                    force: bool = False, progress: bool = False) -> str:
    """Reconstruct the turntable folder `images` into out_dir; returns the summary text (a one-line
    note instead when out_dir already holds the outputs of these images and options)."""
    check_output_dir(out_dir)
    with claimed(out_dir):
        result = reconstruct_folder(images, out_dir, spacing_mm=tuple(spacing_mm), tol_mm=tol_mm,
                                    tip_fraction=tip_fraction, progress=progress, force=force)
    if result is None:
        return f"{out_dir}: outputs are current for these images and options (use --force to redo)"
    return result.summary() + f"\nwritten to      {out_dir}/ (sections.json, surface.stl, report.png)"


@dataclass
class Stage:
    """One stage of a chain: its command name and the call that runs it (-> summary text)."""
    name: str
    run: Callable[[], str]


def chain_stages(images, out_dir, size_mm: float, scene_path=None, force: bool = False,
                 progress: bool = True) -> list[Stage]:
    """The stages of `run` in order, every one checked before any runs: reconstruct `images`
    into out_dir, mesh its sections there with volar edge length size_mm, and run the scene file
    (if any) into <out_dir>/indent_<scene stem>. Each stage runs as its own command would (its
    defaults, its check for current outputs); force redoes reconstruct and mesh."""
    out = check_output_dir(out_dir)
    spec = MeshSpec(source=str(out), sizes={"size_mm": size_mm})
    check_mesh(out, spec)
    stages = [Stage("reconstruct", lambda: run_reconstruct(images, out, force=force, progress=progress)),
              Stage("mesh", lambda: mesh_folder(out, spec, force=force, progress=progress))]
    if scene_path:
        scene = load_scene(scene_path)
        run_dir = out / f"indent_{Path(scene_path).stem}"
        check_output_dir(run_dir, marker=RUN_MARKER, what="indent run")
        stages.append(Stage("indent", lambda: indent_folder(out, run_dir, scene, progress=progress)))
    return stages
