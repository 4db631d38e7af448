"""`reconstruct`: turntable images -> sections.json, surface.stl, report.png; and the `run` chain."""
from __future__ import annotations

from fingertip.staging import check_output_dir
from reconstruct.pipeline import reconstruct_folder


def run_reconstruct(images, out_dir, spacing_mm=(0.5, 2.0), tol_mm: float = 0.02, tip_fraction: float = 0.5,
                    force: bool = False, progress: bool = False) -> str:
    """Reconstruct the turntable folder `images` into out_dir; returns the summary text (a one-line
    note instead when out_dir already holds the outputs of these images and options)."""
    check_output_dir(out_dir)
    result = reconstruct_folder(images, out_dir, spacing_mm=tuple(spacing_mm), tol_mm=tol_mm,
                                tip_fraction=tip_fraction, progress=progress, force=force)
    if result is None:
        return f"{out_dir}: outputs are current for these images and options (use --force to redo)"
    return result.summary() + f"\nwritten to      {out_dir}/ (sections.json, surface.stl, report.png)"


def chain_steps(images, out_dir, size_mm: float, scene: str | None = None, force: bool = False,
                quiet: bool = False) -> list[list[str]]:
    """The command lines of `run`, in order: reconstruct -> mesh [-> indent the scene], all in out_dir.

    Each stage runs as its own subcommand would (its defaults, its check for current outputs);
    --force and --quiet go to reconstruct and mesh, --quiet also to indent.
    """
    flags = [f for f, on in (("--force", force), ("--quiet", quiet)) if on]
    steps = [["reconstruct", str(images), "--out", str(out_dir), *flags],
             ["mesh", str(out_dir), "--out", str(out_dir), "--size", str(size_mm), *flags]]
    if scene:
        steps.append(["indent", str(out_dir), "--scene", str(scene), *(["--quiet"] if quiet else [])])
    return steps
