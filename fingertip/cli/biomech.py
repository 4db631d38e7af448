"""`study-layers`, `fit-material`, `line-load` and `contact-series` (thesis 4.7, 6.2): the command
line of the biomechanics jobs (`fingertip.jobs.biomech`). Lists of layers, offsets, depths and
forces are read from their words here."""
from __future__ import annotations

import argparse
from pathlib import Path

from fem.experiments.scene import Scene
from fem.experiments.values import parse_values
from fingertip.cli.options import (
    FINITE,
    POSITIVE,
    UNSET,
    add_declared,
    scheduler_option,
)
from fingertip.errors import InputError
from fingertip.jobs.biomech import (
    run_contact_series,
    run_fit_material,
    run_line_load,
    run_study_layers,
)


def integers(what: str):
    """argparse type: integers separated by commas ("1,2,3")."""
    def read(text):
        try:
            return [int(t) for t in str(text).replace(" ", "").split(",") if t]
        except ValueError:
            raise argparse.ArgumentTypeError(f"bad {what} '{text}': give integers separated by commas, "
                                             f"e.g. 1,2,3") from None
    return read


def positive_values(what: str):
    """argparse type: positive values in mm (or N): a value, a list or start:stop:step."""
    def read(text):
        try:
            values = parse_values(text)
        except InputError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        if not len(values) or (values <= 0).any():
            raise argparse.ArgumentTypeError(f"bad {what} '{text}': give positive values in mm, e.g. 2.0 or 0.5:2:0.5")
        return [float(v) for v in values]
    return read


def words(text) -> list[str]:
    """Comma-separated words ("C1, C3,C5" -> ["C1", "C3", "C5"])."""
    return [w for w in str(text).replace(" ", "").split(",") if w]


def _given(value):
    """A declared flag's value, None when not given."""
    return None if value is UNSET else value


def _out(out, default) -> str:
    """--out as given (an empty word is refused by the job), else the default folder."""
    return str(default) if out is None else out


def _common(p, indentor_help):
    p.add_argument("model", help="model folder with mesh.vtu (+ model.json) from `pipeline.py mesh`")
    p.add_argument("--indentor", default="wedge", help=indentor_help)
    p.add_argument("--axis", "--orientation", dest="orientation",
                   help="indentor length axis (default: parallel in 2D, perpendicular to the finger in 3D)")
    p.add_argument("--position", type=FINITE, nargs=2, metavar=("X", "Z"),
                   help="load position on the pad in mm (default: the middle of the pad)")
    add_declared(p, Scene, ("nu",))
    p.add_argument("--side", default="mean", choices=("mean", "positive", "negative"),
                   help="profile side of the load: mean of both (default), or one side")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")


def add_study_layers(p):
    """The `study-layers` command's arguments on its parser `p`."""
    _common(p, "indentor code (default wedge, the line load)")
    p.add_argument("--base", help="base material code mABCDE (default: the model's, e.g. m43338)")
    p.add_argument("--layers", type=integers("layers"), default=[1, 2, 3, 4], help="layers to vary (default 1,2,3,4)")
    p.add_argument("--offsets", type=integers("offsets"), default=[-1, 0, 1],
                   help="digit offsets, i.e. powers of ten (default -1,0,1)")
    p.add_argument("--depth", type=positive_values("depths"), default=[2.0],
                   help="depth(s) in mm: value, list or start:stop:step (default 2.0)")
    p.add_argument("--deflection", help="measured profiles to plot alongside: CSV distance_mm, deflection_mm, "
                                        "depth_mm")
    p.add_argument("--out", help="output folder (default: <model>/study_layers)")
    scheduler_option(p, "trial material")
    p.set_defaults(run=_run_study_layers)


def _run_study_layers(args):
    text = run_study_layers(args.model, _out(args.out, Path(args.model) / "study_layers"), base=args.base,
                            layers=args.layers, offsets=args.offsets, depths=args.depth, indentor=args.indentor,
                            orientation=args.orientation, position_mm=args.position, nu=_given(args.nu),
                            side=args.side, data_csv=args.deflection, progress=not args.quiet,
                            scheduler=args.scheduler)
    if not args.quiet:
        print(text)


def add_fit_material(p):
    """The `fit-material` command's arguments on its parser `p`."""
    _common(p, "indentor of the deflection data (default wedge)")
    p.add_argument("--deflection", help="CSV distance_mm, deflection_mm, depth_mm (one or more depths)")
    p.add_argument("--force", help="CSV depth_mm, force_N (N/mm for 2D models): fits the common modulus scale")
    p.add_argument("--force-indentor", default="plate", help="indentor of the force data (default plate)")
    p.add_argument("--keep-ratios", action="store_true",
                   help="scale the --material ratios to the forces instead of the deflection fit's")
    p.add_argument("--match", default="least-squares", choices=("least-squares", "deepest"),
                   help="force scale by least squares over all depths, or equal at the deepest (thesis)")
    p.add_argument("--material", dest="base", help="base / start material code (default: the model's)")
    p.add_argument("--free-layers", type=integers("free layers"), default=[2, 3, 4],
                   help="layers whose moduli are fitted (default 2,3,4; the others stay at the base)")
    p.add_argument("--bounds", type=FINITE, nargs=2, default=(1.0, 7.0), metavar=("LO", "HI"),
                   help="bounds on log10 modulus in Pa (default 1 7)")
    p.add_argument("--noise", type=POSITIVE, help="measurement noise in mm (default: from the residuals)")
    p.add_argument("--out", help="output folder (default: <model>/fit_material)")
    scheduler_option(p, "trial material")
    p.set_defaults(run=_run_fit_material)


def _run_fit_material(args):
    text = run_fit_material(args.model, _out(args.out, Path(args.model) / "fit_material"),
                            deflection_csv=args.deflection, force_csv=args.force, keep_ratios=args.keep_ratios,
                            base=args.base, free_layers=args.free_layers, bounds=tuple(args.bounds),
                            indentor=args.indentor, orientation=args.orientation, position_mm=args.position,
                            force_indentor=args.force_indentor, match=args.match, nu=_given(args.nu), side=args.side,
                            noise_mm=args.noise, progress=not args.quiet, scheduler=args.scheduler)
    if not args.quiet:
        print(text)


def add_line_load(p):
    """The `line-load` command's arguments on its parser `p`."""
    p.add_argument("model", help="model folder with mesh.vtu (+ model.json) from `pipeline.py mesh` (2D or 3D)")
    p.add_argument("--depth", type=positive_values("depths"), default=[0.05, 0.5, 1.0, 2.0],
                   help="depth(s) in mm: value, list or start:stop:step (default 0.05,0.5,1,2)")
    add_declared(p, Scene, ("material", "nu"))
    p.add_argument("--large-deformation", action="store_true",
                   help="also solve the nearly incompressible neo-Hookean model (Newton, load steps)")
    p.add_argument("--slip", action="store_true", help="loaded nodes free sideways (default: they move with the wedge)")
    p.add_argument("--half-width", type=POSITIVE, default=0.25,
                   help="loaded patch: surface nodes within this distance of the load line, mm (default 0.25)")
    p.add_argument("--half-length", type=POSITIVE, default=1.0,
                   help="3D: loaded strip half length across the finger, mm (default 1)")
    p.add_argument("--step", type=POSITIVE, default=0.1, help="load step of the nonlinear solve, mm (default 0.1)")
    p.add_argument("--position", type=FINITE, nargs=2, metavar=("X", "Z"),
                   help="load position in mm (2D: X; default the middle of the pad)")
    p.add_argument("--out", help="output folder (default: <model>/line_load)")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_line_load)


def _run_line_load(args):
    text = run_line_load(args.model, _out(args.out, Path(args.model) / "line_load"), depths=args.depth,
                         material=_given(args.material), nu=_given(args.nu), large_deformation=args.large_deformation,
                         slip=args.slip, half_width_mm=args.half_width, half_length_mm=args.half_length,
                         step_mm=args.step, position_mm=args.position, progress=not args.quiet)
    if not args.quiet:
        print(text)


def add_contact_series(p):
    """The `contact-series` command's arguments on its parser `p`."""
    p.add_argument("model", help="model folder with mesh.vtu (+ model.json) from `pipeline.py mesh` (2D or 3D)")
    p.add_argument("--force", dest="forces_N", type=positive_values("forces"),
                   help="constant force(s) in N (N/mm for 2D models): value, list or start:stop:step")
    p.add_argument("--depth", dest="depths_mm", type=positive_values("depths"), help="or constant depth(s) in mm")
    p.add_argument("--cylinders", type=words, help="cylinder codes, e.g. C1,C3,C5 (default C1-C8)")
    add_declared(p, Scene, ("material",))
    p.add_argument("--axis", "--orientation", dest="orientation",
                   help="cylinder axis (default: parallel in 2D, perpendicular to the finger in 3D)")
    p.add_argument("--position", type=FINITE, nargs=2, metavar=("X", "Z"),
                   help="load position on the pad in mm (default: the middle of the pad)")
    add_declared(p, Scene, ("nu",))
    p.add_argument("--out", help="output folder (default: <model>/contact_series)")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_contact_series)


def _run_contact_series(args):
    text = run_contact_series(args.model, _out(args.out, Path(args.model) / "contact_series"),
                              material=_given(args.material), codes=args.cylinders, forces=args.forces_N,
                              depths=args.depths_mm, orientation=args.orientation, position_mm=args.position, nu=_given(args.nu),
                              progress=not args.quiet)
    if not args.quiet:
        print(text)
