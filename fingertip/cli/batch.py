"""`batch`: a cohort of subjects through one scene (`fingertip.jobs.batch`). The mesh size flags
are the `mesh` command's (`fingertip.cli.mesh.add_sizes`)."""
from __future__ import annotations

from pathlib import Path

from fem.geometry.build import SIZE_FIELDS
from fem.geometry.layered import ModelParams
from fem.geometry.mesh3d import Sizing
from fingertip.cli.mesh import add_sizes
from fingertip.cli.options import add_declared, declared_values, scheduler_option
from fingertip.resources import scene_names
from fingertip.jobs.batch import MeshOptions, check_batch, parse_subjects, run_batch


def add_batch(p):
    """The `batch` command's arguments on its parser `p`."""
    p.add_argument("subjects", nargs="+", metavar="SUBJECT",
                   help="turntable folder, folder with sections.json, or preset:NAME (human, monkey, block, "
                        "square, cylinder8, cylinder16; preset:cylinder8:bone adds the 2D bone)")
    p.add_argument("--scene", required=True, help="TOML scene file every subject runs, or the name of a shipped "
                   "scene (" + ", ".join(scene_names()) + ")")
    p.add_argument("--out", required=True, help="output folder: <out>/<subject>/ and <out>/summary.csv")
    add_sizes(p)
    add_declared(p, ModelParams, ("tip_mm",))
    scheduler_option(p, "subject")
    p.add_argument("--force", action="store_true", help="recompute reconstruct and 3D mesh stages")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_batch, check=lambda args: check_batch(**batch_options(args)), kept=_kept)


def _kept(args) -> str | None:
    """What an interrupted batch keeps: each subject's folder (its model, and its run folder
    once its scene ran), which a rerun skips where current (None: no subject folder yet)."""
    out = Path(args.out)
    folders = [f for f in out.iterdir() if f.is_dir() and not f.name.startswith(".")] if out.is_dir() else []
    if not folders:
        return None
    ran = sum((f / Path(args.scene).stem / "run.json").is_file() for f in folders)
    return (f"the subject folders in {out} are kept ({ran} of them with their scene run) and a rerun "
            f"skips what is current")


def batch_options(args) -> dict:
    """The keyword arguments of `check_batch` and `run_batch` from the parsed batch arguments."""
    mesh = MeshOptions(sizes=declared_values(args, Sizing, SIZE_FIELDS), **declared_values(args, ModelParams, ("tip_mm",)))
    return dict(subjects=parse_subjects(args.subjects), scene_path=args.scene, out_dir=args.out, mesh=mesh,
                scheduler=args.scheduler)


def _run_batch(args):
    text = run_batch(**batch_options(args), force=args.force, progress=not args.quiet)
    if not args.quiet:
        print(text)
