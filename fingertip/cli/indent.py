"""`indent` (a scene file, or one experiment from the flags, on a model folder) and `prepare` (a
stored response model). The experiment, receptor, material and output flags are derived from the
scene schema (`fem.experiments.scene`: Experiment, Receptors, Scene, Output)."""
from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from fem.core.materials import DEFAULT_CODE, DEFAULT_NU, Material
from fem.experiments.scene import Experiment, Output, Receptors, Scene, load_scene
from fingertip.cli.options import add_declared, declared_values, scheduler_option
from fingertip.errors import InputError
from fingertip.jobs.indent import RUN_MARKER, indent_folder, prepare_folder
from fingertip.resources import scene_names
from fingertip.staging import check_output_dir

EXPERIMENT_FLAGS = ("indentor", "orientation", "position_mm", "incline_deg", "equal_force", "max_depth_mm", "sweep")
"""Experiment fields the indent flags set (besides depth_mm and force_N, one of which is given)."""
RECEPTOR_FLAGS = ("depths_mm", "spacing_mm", "line")
MATERIAL_FLAGS = ("material", "nu")
OUTPUT_FLAGS = ("pvd", "plots")

MODEL_HELP = "model folder with mesh.vtu (+ model.json) from `pipeline.py mesh`"


def add_material_and_receptors(p) -> None:
    """--material, --nu and the receptor grid: the same for `indent` and `prepare`, so a prepared
    response model matches the indent command given the same values."""
    add_declared(p, Scene, MATERIAL_FLAGS)
    add_declared(p, Receptors, RECEPTOR_FLAGS)


def add_prepare(p):
    """The `prepare` command's arguments on its parser `p`."""
    p.add_argument("model", help=MODEL_HELP)
    p.add_argument("--approach", help="approach direction x,y,z (default: the model's support; -y in 2D)")
    add_material_and_receptors(p)
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_prepare)


def _approach(text):
    """--approach 'x,y,z' -> three numbers, not all zero (None -> None)."""
    if text is None:
        return None
    try:
        a = [float(v) for v in str(text).split(",")]
        if len(a) != 3 or not all(abs(v) < float("inf") for v in a) or not any(a):
            raise ValueError
    except ValueError:
        raise InputError(f"--approach {text}: give three numbers x,y,z (e.g. 0,-1,0), not all zero") from None
    return a


def _run_prepare(args):
    material = declared_values(args, Scene, MATERIAL_FLAGS)
    receptors = Receptors.from_dict(declared_values(args, Receptors, RECEPTOR_FLAGS))
    text = prepare_folder(args.model, material.get("material"), material.get("nu"), _approach(args.approach),
                          receptors, progress=not args.quiet)
    if not args.quiet:
        print(text)


def add_indent(p):
    """The `indent` command's arguments on its parser `p`."""
    p.add_argument("model", help=MODEL_HELP)
    p.add_argument("--scene", help="TOML scene file, or the name of a shipped scene (" + ", ".join(scene_names())
                   + "); without it the flags below describe one experiment")
    load = p.add_mutually_exclusive_group()
    add_declared(load, Experiment, ("depth_mm", "force_N"))
    add_declared(p, Experiment, EXPERIMENT_FLAGS)
    add_material_and_receptors(p)
    add_declared(p, Output, OUTPUT_FLAGS, defaults={"plots": "the scene's, on", "pvd": "the scene's, off"},
                 pvd={"action": argparse.BooleanOptionalAction})       # --no-pvd overrides a scene's pvd = true
    add_declared(p, Scene, ("max_indentations",), defaults={"max_indentations": "the scene's, 10000"})
    add_declared(p, Scene, ("kinematics",), defaults={"kinematics": "the scene's, linear"})
    p.add_argument("--out", help="output folder (default: <model>/indent_<indentor or scene file stem>)")
    scheduler_option(p, "experiment of the scene")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_indent, check=indent_scene, from_scene=FROM_SCENE)


FROM_SCENE = ("depth_mm", "force_N") + EXPERIMENT_FLAGS + RECEPTOR_FLAGS + MATERIAL_FLAGS + OUTPUT_FLAGS \
    + ("max_indentations", "kinematics")
"""Fields a --scene file sets unless their flag is given: an error about one names the scene's key,
not the flag (`fingertip.cli.user_words`)."""


def scene_of_flags(args) -> Scene:
    """The one-experiment Scene the indent flags describe (named after the indentor code)."""
    exp = declared_values(args, Experiment, ("depth_mm", "force_N") + EXPERIMENT_FLAGS)
    if not exp.get("indentor") or ("depth_mm" not in exp and "force_N" not in exp):
        raise InputError("indent needs --scene, or --indentor with --depth or --force")
    exp["name"] = exp["indentor"].replace(":", "_").replace(",", "_")
    return Scene.from_dict({"experiment": [exp], "receptors": declared_values(args, Receptors, RECEPTOR_FLAGS)},
                           max_indentations=_max_indentations(args))


def _max_indentations(args) -> int | None:
    """--max-indentations, None when not given (the scene's own bound holds)."""
    return declared_values(args, Scene, ("max_indentations",)).get("max_indentations")


def indent_scene(args) -> tuple[Scene, str]:
    """(validated Scene, output folder) of the indent arguments: the --scene file, or the
    experiment of the flags, with --material, --nu, --pvd and --plots overriding the scene's. Reads
    the scene file only, not the model."""
    if args.scene:
        scene, name = load_scene(args.scene, _max_indentations(args)), Path(args.scene).stem
    else:
        scene = scene_of_flags(args)
        name = scene.experiments[0].name
    overrides = declared_values(args, Scene, MATERIAL_FLAGS + ("kinematics",))
    if overrides:                                                       # the code's form, nu's range
        Material(overrides.get("material") or scene.material or DEFAULT_CODE, overrides.get("nu", DEFAULT_NU))
    output = declared_values(args, Output, OUTPUT_FLAGS)
    if output:
        overrides["output"] = dataclasses.replace(scene.output, **output)
    out = args.out if args.out is not None else str(Path(args.model) / f"indent_{name}")
    check_output_dir(out, marker=RUN_MARKER, what="indent run")
    scene = dataclasses.replace(scene, **overrides)
    scene.check_kinematics()                       # --kinematics finite on a scene it cannot run
    return scene, out


def _run_indent(args):
    scene, out = indent_scene(args)
    text = indent_folder(args.model, out, scene, progress=not args.quiet, scheduler=args.scheduler)
    if not args.quiet:
        print(text)
