"""`explore`: the live explorer in the browser over a model folder's stored response model
(`fingertip.jobs.explore`)."""
from __future__ import annotations

from fem.experiments.scene import Receptors, Scene
from fingertip.cli.indent import MATERIAL_FLAGS, MODEL_HELP, RECEPTOR_FLAGS, add_material_and_receptors
from fingertip.cli.options import declared_values
from fingertip.jobs.explore import check_explore, explore


def add_explore(p):
    """The `explore` command's arguments on its parser `p`."""
    p.add_argument("model", help=MODEL_HELP)
    p.add_argument("--port", type=int, default=8080,
                   help="port on 127.0.0.1 (default 8080)")
    p.add_argument("--scenes", default=".", help="folder 'save as scene' writes into (default: the current folder)")
    p.add_argument("--open", action="store_true", help="also open the system's web browser at the URL")
    add_material_and_receptors(p)
    p.add_argument("--quiet", action="store_true", help="no progress while the response model is built")
    p.set_defaults(run=_run_explore, check=lambda args: check_explore(args.model, *_material(args), args.port,
                                                                      args.scenes))


def _material(args) -> tuple:
    material = declared_values(args, Scene, MATERIAL_FLAGS)
    return material.get("material"), material.get("nu")


def _run_explore(args):
    receptors = declared_values(args, Receptors, RECEPTOR_FLAGS)
    explore(args.model, *_material(args), receptors, args.port, args.scenes, args.open, progress=not args.quiet)
