"""Back end of `pipeline.py indent`: a scene (a TOML file, or one experiment from the flags) on a
model folder, written atomically as a run folder (fem.runfolder); returns the summary text.

    indent_folder("out/cyl8", "out/cyl8/bars", load_scene("scenes/bars.toml"))   # model -> run folder
"""
from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

from common.errors import InputError
from common.staging import staged_output
from fem import plots
from fem.experiments import run_experiments
from fem.modelfolder import read_model
from fem.runfolder import write_run
from fem.scene import Scene, load_scene


def parse_position(words: list[str]):
    """--position: 'top' or X Z in mm."""
    if words == ["top"]:
        return "top"
    try:
        x, z = (float(w) for w in words)
    except ValueError:
        raise InputError(f"--position {' '.join(words)}: give X Z in mm or top") from None
    return [x, z]


def scene_of_flags(indentor, orientation="parallel", position=None, incline=None, depth=None, force=None,
                   equal_force=False, max_depth=5.0, sweep=None, receptor_depths="0.5,0.75,1.0",
                   receptor_spacing=1.0, line=None) -> Scene:
    """The one-experiment Scene the `indent` flags describe (named after the indentor code)."""
    if not indentor or (depth is None and force is None):
        raise InputError("indent needs --scene, or --indentor with --depth or --force")
    exp = {"name": indentor.replace(":", "_").replace(",", "_"), "indentor": indentor, "orientation": orientation}
    if position is not None:
        exp["position_mm"] = parse_position(position)
    if depth is not None:
        exp["depth_mm"] = depth
    else:
        exp.update(force_N=force, equal_force=equal_force, max_depth_mm=max_depth)
    if sweep:
        exp["sweep"] = sweep
    if incline is not None:
        exp["incline_deg"] = incline
    receptors = {"depths_mm": receptor_depths, "spacing_mm": receptor_spacing}
    if line:
        axis, _, value = line.partition("=")
        receptors["line"] = [axis, value]
    return Scene.from_dict({"experiment": [exp], "receptors": receptors})


def indent_folder(model_dir, out_dir, scene: Scene, progress: bool = True) -> str:
    """Run every experiment of a scene on a model folder and write the run folder atomically into
    out_dir (CSV, run.json, and PNG and PVD as the scene says). Placement warnings go to stderr;
    progress: report the factorisation and each experiment on stderr. Returns the summary text."""
    t_start = time.perf_counter()
    model, info = read_model(model_dir, scene.material, scene.nu)
    say = (lambda text: print(text, file=sys.stderr, flush=True)) if progress else None
    run = run_experiments(model, info, scene, progress=say)
    for warning in run.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    with staged_output(out_dir) as tmp:
        tables = write_run(tmp, model_dir, run)
        if scene.output.plots:
            for e in run.experiments:
                for name, fig in plots.indent_figures(e, run, tables[e.name]).items():
                    plots.save(fig, tmp / name)
    total = time.perf_counter() - t_start
    lines = [(f"indentation results in {out_dir} ({total:.1f} s; model {model.ndof} DOFs, "
              f"{len(run.surface.nodes)} contact candidates, {len(run.grid.points_mm)} receptor points)")]
    for e in run.experiments:
        forces = [r.total_force_N for _, r in e.steps]
        worst = max(r.kkt["penetration_mm"] for _, r in e.steps)
        lines.append(f"  {e.name}: {len(e.steps)} indentations, {e.seconds:.2f} s, force "
                     f"{min(forces):.4g}-{max(forces):.4g} N, max penetration {worst:.1e} mm")
    return "\n".join(lines)


def run_indent(model, scene=None, indentor=None, orientation="parallel", position=None, incline=None,
               depth=None, force=None, equal_force=False, max_depth=5.0, sweep=None, material=None, nu=None,
               receptor_depths="0.5,0.75,1.0", receptor_spacing=1.0, line=None, pvd=None, out=None,
               progress: bool = True) -> str:
    """`pipeline.py indent` from its option values: the --scene file, or the experiment of the
    flags; --material, --nu and --pvd override the scene's. Output folder default:
    <model>/indent_<scene file stem or experiment name>."""
    if scene:
        spec = load_scene(scene)
        name = Path(scene).stem
    else:
        spec = scene_of_flags(indentor, orientation, position, incline, depth, force, equal_force, max_depth,
                              sweep, receptor_depths, receptor_spacing, line)
        name = spec.experiments[0].name
    overrides = {k: v for k, v in (("material", material), ("nu", nu)) if v is not None}
    if pvd is not None:
        overrides["output"] = dataclasses.replace(spec.output, pvd=pvd)
    spec = dataclasses.replace(spec, **overrides)
    return indent_folder(model, out or str(Path(model) / f"indent_{name}"), spec, progress=progress)
