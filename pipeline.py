#!/usr/bin/env python
"""Command line for the fingertip toolkit. CLI only: parse arguments, call the library, print a summary.

    python pipeline.py reconstruct sample_images/ --out out/sample
    python pipeline.py render fingertip --out my_images/
    python pipeline.py <command> --help
    fingertip <command> ...            (the same, once installed with `pip install -e .`)

Bad input ends with one line `error: ...` on stderr and exit code 2, and writes nothing.
"""
from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import traceback
from pathlib import Path

from fingertip.errors import InputError

HERE = Path(__file__).resolve().parent


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (exit code 2)."""

    def error(self, message):
        raise InputError(f"{self.prog}: {message} (see --help)")


def _number(low: float | None = None, strict: bool = True, high: float | None = None):
    """argparse type: a finite float, above `low` (strict: > low, else >=) and <= high if given."""
    def number(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"'{text}' is not a number") from None
        ok = math.isfinite(value) and (low is None or (value > low if strict else value >= low))
        if not ok or (high is not None and value > high):
            want = ["finite"] + ([f"{'>' if strict else '>='} {low:g}"] if low is not None else []) \
                + ([f"<= {high:g}"] if high is not None else [])
            raise argparse.ArgumentTypeError(f"must be {' and '.join(want)}, got {text}")
        return value
    return number


FINITE, POSITIVE, NONNEGATIVE = _number(), _number(0.0), _number(0.0, strict=False)


def _scheduler_option(p, task: str):
    p.add_argument("--scheduler", default="none",
                   help=f"none (default: this process), local:N (N worker processes on this machine) or "
                        f"tcp://HOST:PORT (a running Dask cluster), one task per {task}; Dask needs "
                        f"pip install -e \".[dask]\"")


# --------------------------------------------------------------------------- reconstruct
def _add_reconstruct(sub):
    p = sub.add_parser("reconstruct", help="turntable images -> sections.json, surface.stl, report.png")
    p.add_argument("images", nargs="?", default=str(HERE / "sample_images"),
                   help="turntable folder (default: the bundled sample_images/)")
    p.add_argument("--out", default="out/sample", help="output folder (default out/sample)")
    p.add_argument("--spacing-mm", type=float, nargs=2, default=(0.5, 2.0), metavar=("MIN", "MAX"),
                   help="axial section spacing range in mm (default 0.5 2.0)")
    p.add_argument("--tol-mm", type=float, default=0.02,
                   help="allowed interpolation error between sections in mm (default 0.02)")
    p.add_argument("--tip-fraction", type=float, default=0.5,
                   help="trim the distal tip where the section is narrower than this fraction "
                        "of the widest section (default 0.5; 0 keeps all)")
    p.add_argument("--force", action="store_true", help="recompute even if the outputs are current")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    p.set_defaults(run=_run_reconstruct, check=_check_reconstruct)


def _check_reconstruct(args):
    from fingertip.staging import check_output_dir

    check_output_dir(args.out)


def _run_reconstruct(args):
    from fingertip.jobs.reconstruct import run_reconstruct

    text = run_reconstruct(args.images, args.out, spacing_mm=args.spacing_mm, tol_mm=args.tol_mm,
                           tip_fraction=args.tip_fraction, force=args.force, progress=not args.quiet)
    if not args.quiet:
        print(text)


# --------------------------------------------------------------------------- render
def _add_render(sub):
    from fem.geometry.presets import SHAPES

    p = sub.add_parser("render", help="render a synthetic turntable set of a known shape (+ ground truth)")
    p.add_argument("shape", choices=sorted(SHAPES), help="shape to render")
    p.add_argument("--out", required=True, help="output folder (a turntable folder)")
    p.add_argument("--views", type=int, default=100, help="number of views (default 100)")
    p.add_argument("--span-deg", type=float, default=360.0, help="rotation covered (default 360)")
    p.add_argument("--size", type=int, nargs=2, default=(700, 900), metavar=("W", "H"),
                   help="image size in px (default 700 900)")
    p.add_argument("--mm-per-px", type=float, default=0.04, help="scale (default 0.04)")
    p.add_argument("--aspect", type=float, default=1.0, help="pixel aspect ratio h/w (default 1)")
    p.add_argument("--blur-px", type=float, default=0.8, help="Gaussian PSF sigma in px (default 0.8)")
    p.add_argument("--noise", type=float, default=2.0, help="noise sigma in grey levels (default 2)")
    p.add_argument("--vignetting", type=float, default=0.25,
                   help="relative brightness drop at the corners (default 0.25)")
    p.add_argument("--axis-offset-px", type=float, default=0.0, help="axis offset from the centre column")
    p.add_argument("--tilt-deg", type=float, default=0.0, help="in-plane tilt of the rotation axis")
    p.add_argument("--no-rod", action="store_true", help="leave out the mounting rod")
    p.add_argument("--groove", action="store_true", help="fingertip: add a concave dorsal groove")
    p.add_argument("--seed", type=int, default=0, help="noise seed (default 0)")
    p.add_argument("--camera-distance-mm", type=float, default=None,
                   help="pinhole camera this far from the rotation axis (default: parallel projection)")
    p.add_argument("--write-camera", action="store_true",
                   help="also write camera_distance_mm into the set's turntable.toml")
    p.add_argument("--distortion", default=None, metavar="K1[,K2]",
                   help="radial lens distortion (Brown k1, k2) of the pinhole camera (default none)")
    p.add_argument("--checkerboard", type=int, default=0, metavar="N",
                   help="also render N photos of a 9 x 6 checkerboard (3 mm squares) into checkerboard/")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    p.set_defaults(run=_run_render)


def _run_render(args):
    from fingertip.jobs.render import run_render

    text = run_render(args.shape, args.out, views=args.views, span_deg=args.span_deg, size_px=args.size,
                      mm_per_px=args.mm_per_px, aspect=args.aspect, blur_px=args.blur_px, noise=args.noise,
                      vignetting=args.vignetting, axis_offset_px=args.axis_offset_px, tilt_deg=args.tilt_deg,
                      rod=not args.no_rod, groove=args.groove, seed=args.seed, progress=not args.quiet,
                      camera_distance_mm=args.camera_distance_mm, write_camera=args.write_camera,
                      distortion=args.distortion, checkerboard=args.checkerboard)
    if not args.quiet:
        print(text)


# --------------------------------------------------------------------------- mesh
def _add_mesh(sub):
    p = sub.add_parser("mesh", help="layered model + tetrahedral mesh (or a 2D plane-strain mesh) -> "
                                    "mesh.vtu, model.json")
    p.add_argument("source", nargs="?", help="folder with sections.json (or the file itself)")
    p.add_argument("--preset", help="3D: human, monkey (parametric fingertip, no images); 2D (thesis ch. 4): "
                                    "block (40 x 18), square (8 x 8), cylinder8, cylinder16")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--section-z", type=FINITE, metavar="Z",
                   help="2D: mesh the five-layer cross-section of the 3D model at this z (mm) instead")
    p.add_argument("--bone", action="store_true", help="2D cylinders: add the central 2 mm bone (layer 5)")
    p.add_argument("--solid-fluid", action="store_true", help="2D cylinders: a 1 mm solid layer around an "
                   "incompressible fluid core (layer 6; thesis 4.6)")
    p.add_argument("--size", type=POSITIVE, help="target edge length on the volar skin / top surface in mm "
                                               "(default 0.5 in 3D, 0.125 in 2D)")
    p.add_argument("--coarse", type=POSITIVE, help="largest edge length in mm (default 3.0 in 3D, 1.0 in 2D)")
    p.add_argument("--growth", type=POSITIVE, help="edge length growth per mm away from the fine zone (default 0.5)")
    p.add_argument("--fine-depth", type=POSITIVE, help="depth of the fine zone below the volar surface in mm "
                                                     "(default 1.5 in 3D, 1.0 in 2D)")
    p.add_argument("--epidermis", type=POSITIVE, help="epidermis thickness in mm (default 0.5)")
    p.add_argument("--dermis", type=POSITIVE, help="dermis thickness in mm (default 1.0)")
    p.add_argument("--layer3", type=POSITIVE, help="layer 3 volar thickness at the reference sections in mm; "
                                                 "sets the thesis scale factor (default: presets human 1.5, monkey 0.55; "
                                                 "sections.json by section width, see model.json size_defaults)")
    p.add_argument("--layer3-scale", type=POSITIVE, help="give the layer-3 scale factor f3 directly (0-1; "
                                                       "overrides --layer3)")
    p.add_argument("--bone-diameter", type=POSITIVE, help="bone width at the middle reference section in mm "
                                                        "(default 2.0)")
    p.add_argument("--bone-profile", help="bone width / section width along the length, 's:ratio,...' with "
                                          "s in [0, 1] from proximal to distal, e.g. 0:0.25,1:0.18")
    p.add_argument("--bone-offset", type=NONNEGATIVE, help="bone shift towards the nail (-y) in mm "
                                                      "(default: presets human 1.0, monkey 0.15; sections.json by width)")
    p.add_argument("--nail-span", type=POSITIVE, help="nail region angular span in deg (default 120)")
    p.add_argument("--nail-z", type=FINITE, nargs=2, metavar=("LO", "HI"),
                   help="nail region as fractions of the length (default 0.3 1.0)")
    p.add_argument("--support-span", type=POSITIVE, help="support region angular span in deg (default 90)")
    p.add_argument("--support-z", type=FINITE, nargs=2, metavar=("LO", "HI"),
                   help="support region as fractions of the length (default 0 0.3)")
    p.add_argument("--support-incline", type=FINITE,
                   help="support plane angle to the horizontal in deg, positive with the distal end lower "
                        "(-30: the thesis platform, distal end up; default 0)")
    p.add_argument("--z-range", type=FINITE, nargs=2, metavar=("Z0", "Z1"),
                   help="use only the sections in this z range (mm)")
    p.add_argument("--tip-width-frac", type=_number(0.0, high=1.0), default=0.9,
                   help="sections.json: end the model distally where the section width drops below this "
                        "fraction of the widest (then a flat cut, or domes with --tip rounded; default 0.9)")
    p.add_argument("--tip", default="flat",
                   help="distal end: flat (a cut, as the thesis; default), rounded (every layer wraps round a "
                        "dome as long as the data's tip: the preset's cap, the sections beyond the body), or "
                        "the dome length in mm")
    p.add_argument("--force", action="store_true", help="rebuild the mesh, ignoring the cache")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_mesh, check=_check_mesh)


def _mesh_options(args) -> dict:
    """The options of `fingertip.jobs.mesh.check_options` from the parsed mesh arguments."""
    from fingertip.jobs.mesh import ModelOptions

    options = ModelOptions(epidermis_mm=args.epidermis, dermis_mm=args.dermis, layer3_mm=args.layer3,
                           layer3_scale=args.layer3_scale, bone_diameter_mm=args.bone_diameter,
                           bone_profile=args.bone_profile, bone_offset_mm=args.bone_offset,
                           nail_span_deg=args.nail_span, nail_z_frac=args.nail_z, support_span_deg=args.support_span,
                           support_z_frac=args.support_z, support_incline_deg=args.support_incline, tip=args.tip)
    return dict(out=args.out, source=args.source, preset=args.preset, section_z_mm=args.section_z, bone=args.bone, solid_fluid=args.solid_fluid,
                size_mm=args.size, coarse_mm=args.coarse, growth=args.growth, fine_depth_mm=args.fine_depth,
                options=options)


def _check_mesh(args):
    from fingertip.jobs.mesh import check_options

    check_options(**_mesh_options(args))


def _run_mesh(args):
    from fingertip.jobs.mesh import run_mesh

    text = run_mesh(**_mesh_options(args), z_range_mm=args.z_range, tip_width_frac=args.tip_width_frac,
                    force=args.force, progress=not args.quiet)
    if not args.quiet:
        print(text)


def _material_and_receptor_options(p):
    """--material, --nu and the receptor grid: the same for `indent` and `prepare`, so a prepared
    response model matches the indent command given the same values."""
    p.add_argument("--material", help="material code or moduli (default: the model's)")
    p.add_argument("--nu", type=NONNEGATIVE, help="Poisson ratio (default: the model's)")
    p.add_argument("--receptor-depths", default="0.5,0.75,1.0", help="receptor depths in mm (default 0.5,0.75,1.0)")
    p.add_argument("--receptor-spacing", type=POSITIVE, default=1.0, help="receptor spacing in mm (default 1)")
    p.add_argument("--line", help="receptors only along a line: z=<mm>, z=middle or x=<mm> (default: the "
                                  "whole pad)")


# --------------------------------------------------------------------------- indent
def _add_indent(sub):
    p = sub.add_parser("indent", help="rigid indentors on a meshed model: depth or force control, sweeps "
                                      "-> CSV, PNG, PVD")
    p.add_argument("model", help="model folder with mesh.vtu (+ model.json) from `pipeline.py mesh`")
    p.add_argument("--scene", help="TOML scene file (scenes/*.toml); the flags below describe one experiment")
    p.add_argument("--indentor", help="indentor code: C1-C8, R1-R2, cylinder:<d>, step:0-5, bar:<w>, "
                                      "grating:<bar>[:<gaps>], wedge, cone, punch, plate, sphere:<r>, "
                                      "ellipsoid:<a,b,c>, two-point:<separation>")
    p.add_argument("--axis", "--orientation", dest="orientation", default="parallel",
                   help="indentor length axis: parallel or perpendicular to the finger axis, or an "
                        "angle in degrees (default parallel; 2D models need parallel)")
    p.add_argument("--position", nargs="+", metavar="X Z | top",
                   help="indentor position on the pad in mm, or top: the pad point highest against the "
                        "approach (default: x = 0 at the middle of the pad)")
    p.add_argument("--incline", type=FINITE, help="finger incline in degrees (default: the model's support)")
    load = p.add_mutually_exclusive_group()
    load.add_argument("--depth", help="depths in mm beyond first touch: start:stop:step or list (e.g. 0:3:0.5)")
    load.add_argument("--force", type=POSITIVE, help="total force in N (N/mm in 2D); the depth is solved for")
    p.add_argument("--equal-force", action="store_true", help="with --force: every part of a two-point "
                                                              "indentor carries the force")
    p.add_argument("--max-depth", type=POSITIVE, default=5.0, help="depth limit for --force in mm (default 5)")
    p.add_argument("--sweep", help="move the indentor: x=start:stop:step or z=start:stop:step (mm)")
    _material_and_receptor_options(p)
    p.add_argument("--pvd", action=argparse.BooleanOptionalAction, default=None,
                   help="full fields per indentation as a PVD series (default: on up to 20 indentations)")
    p.add_argument("--plots", action=argparse.BooleanOptionalAction, default=None,
                   help="PNG figures per experiment (default: the scene's, on)")
    p.add_argument("--out", help="output folder (default: <model>/indent_<indentor>)")
    _scheduler_option(p, "experiment of the scene")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_indent, check=_check_indent)


def _indent_options(args) -> dict:
    """The options of `fingertip.jobs.indent.indent_scene` from the parsed indent arguments."""
    return dict(model=args.model, scene=args.scene, indentor=args.indentor, orientation=args.orientation,
                position=args.position, incline=args.incline, depth=args.depth, force=args.force,
                equal_force=args.equal_force, max_depth=args.max_depth, sweep=args.sweep,
                material=args.material, nu=args.nu, receptor_depths=args.receptor_depths,
                receptor_spacing=args.receptor_spacing, line=args.line, pvd=args.pvd, out=args.out,
                plots=args.plots)


def _check_indent(args):
    from fingertip.jobs.indent import indent_scene

    indent_scene(**_indent_options(args))


def _run_indent(args):
    from fingertip.jobs.indent import run_indent

    text = run_indent(**_indent_options(args), progress=not args.quiet, scheduler=args.scheduler)
    if not args.quiet:
        print(text)


def _add_prepare(sub):
    p = sub.add_parser("prepare", help="store a model's response model (compliance of the pad and receptor "
                                       "response) so later indent commands answer without factorising")
    p.add_argument("model", help="model folder with mesh.vtu (+ model.json) from `pipeline.py mesh`")
    p.add_argument("--approach", help="approach direction x,y,z (default: the model's support; -y in 2D)")
    _material_and_receptor_options(p)
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_prepare)


def _run_prepare(args):
    from fingertip.jobs.prepare import prepare_folder

    text = prepare_folder(args.model, material=args.material, nu=args.nu, approach=args.approach,
                          receptor_depths=args.receptor_depths, receptor_spacing=args.receptor_spacing,
                          line=args.line, progress=not args.quiet)
    if not args.quiet:
        print(text)


# --------------------------------------------------------------------------- biomechanical verification
def _biomech_common(p, indentor_help):
    p.add_argument("model", help="model folder with mesh.vtu (+ model.json) from `pipeline.py mesh`")
    p.add_argument("--indentor", default="wedge", help=indentor_help)
    p.add_argument("--axis", "--orientation", dest="orientation",
                   help="indentor length axis (default: parallel in 2D, perpendicular to the finger in 3D)")
    p.add_argument("--position", type=FINITE, nargs=2, metavar=("X", "Z"),
                   help="load position on the pad in mm (default: the middle of the pad)")
    p.add_argument("--nu", type=NONNEGATIVE, help="Poisson ratio (default: the model's)")
    p.add_argument("--side", default="mean", choices=("mean", "positive", "negative"),
                   help="profile side of the load: mean of both (default), or one side")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")


def _add_study_layers(sub):
    p = sub.add_parser("study-layers", help="layer-stiffness study (thesis fig. 6-10): deflection profiles under "
                                            "a line load with each layer's modulus varied by powers of ten")
    _biomech_common(p, "indentor code (default wedge, the line load)")
    p.add_argument("--base", help="base material code mABCDE (default: the model's, e.g. m43338)")
    p.add_argument("--layers", default="1,2,3,4", help="layers to vary (default 1,2,3,4)")
    p.add_argument("--offsets", default="-1,0,1", help="digit offsets, i.e. powers of ten (default -1,0,1)")
    p.add_argument("--depth", default="2.0", help="depth(s) in mm: value, list or start:stop:step (default 2.0)")
    p.add_argument("--deflection", help="measured profiles to plot alongside: CSV distance_mm, deflection_mm, "
                                        "depth_mm")
    p.add_argument("--out", help="output folder (default: <model>/study_layers)")
    _scheduler_option(p, "trial material")
    p.set_defaults(run=_run_study_layers)


def _run_study_layers(args):
    from fingertip.jobs.biomech import run_study_layers

    text = run_study_layers(args.model, args.out or str(Path(args.model) / "study_layers"), base=args.base,
                            layers=args.layers, offsets=args.offsets, depths=args.depth, indentor=args.indentor,
                            orientation=args.orientation, position_mm=args.position, nu=args.nu,
                            side=args.side, data_csv=args.deflection, progress=not args.quiet,
                            scheduler=args.scheduler)
    if not args.quiet:
        print(text)


def _add_fit_material(sub):
    p = sub.add_parser("fit-material", help="fit layer moduli to measured deflection profiles (ratios) and "
                                            "force-depth data (absolute scale)")
    _biomech_common(p, "indentor of the deflection data (default wedge)")
    p.add_argument("--deflection", help="CSV distance_mm, deflection_mm, depth_mm (one or more depths)")
    p.add_argument("--force", help="CSV depth_mm, force_N (N/mm for 2D models): fits the common modulus scale")
    p.add_argument("--force-indentor", default="plate", help="indentor of the force data (default plate)")
    p.add_argument("--keep-ratios", action="store_true",
                   help="scale the --material ratios to the forces instead of the deflection fit's")
    p.add_argument("--match", default="least-squares", choices=("least-squares", "deepest"),
                   help="force scale by least squares over all depths, or equal at the deepest (thesis)")
    p.add_argument("--material", dest="base", help="base / start material code (default: the model's)")
    p.add_argument("--free-layers", default="2,3,4",
                   help="layers whose moduli are fitted (default 2,3,4; the others stay at the base)")
    p.add_argument("--bounds", type=FINITE, nargs=2, default=(1.0, 7.0), metavar=("LO", "HI"),
                   help="bounds on log10 modulus in Pa (default 1 7)")
    p.add_argument("--noise", type=POSITIVE, help="measurement noise in mm (default: from the residuals)")
    p.add_argument("--out", help="output folder (default: <model>/fit_material)")
    _scheduler_option(p, "trial material")
    p.set_defaults(run=_run_fit_material)


def _run_fit_material(args):
    from fingertip.jobs.biomech import run_fit_material

    text = run_fit_material(args.model, args.out or str(Path(args.model) / "fit_material"),
                            deflection_csv=args.deflection, force_csv=args.force, keep_ratios=args.keep_ratios,
                            base=args.base, free_layers=args.free_layers, bounds=tuple(args.bounds),
                            indentor=args.indentor, orientation=args.orientation, position_mm=args.position,
                            force_indentor=args.force_indentor, match=args.match, nu=args.nu, side=args.side,
                            noise_mm=args.noise, progress=not args.quiet, scheduler=args.scheduler)
    if not args.quiet:
        print(text)


def _add_line_load(sub):
    p = sub.add_parser("line-load", help="surface deflection and force under a prescribed line load (thesis "
                                         "6.2.1); --large-deformation adds the neo-Hookean solve and compares")
    p.add_argument("model", help="model folder with mesh.vtu (+ model.json) from `pipeline.py mesh` (2D or 3D)")
    p.add_argument("--depth", default="0.05,0.5,1,2", help="depth(s) in mm: value, list or start:stop:step "
                                                          "(default 0.05,0.5,1,2)")
    p.add_argument("--material", help="material code mABCDE (default: the model's)")
    p.add_argument("--nu", type=NONNEGATIVE, help="Poisson ratio (default: the model's)")
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
    from fingertip.jobs.biomech import run_line_load

    text = run_line_load(args.model, args.out or str(Path(args.model) / "line_load"), depths=args.depth,
                         material=args.material, nu=args.nu, large_deformation=args.large_deformation,
                         slip=args.slip, half_width_mm=args.half_width, half_length_mm=args.half_length,
                         step_mm=args.step, position_mm=args.position, progress=not args.quiet)
    if not args.quiet:
        print(text)


def _add_contact_series(sub):
    p = sub.add_parser("contact-series", help="cylinders C1-C8 at constant force or depth: contact area (2D: "
                                              "width) and max pressure vs diameter (thesis figs. 4-25, 5-14)")
    p.add_argument("model", help="model folder with mesh.vtu (+ model.json) from `pipeline.py mesh` (2D or 3D)")
    p.add_argument("--force", help="constant force(s) in N (N/mm for 2D models): value, list or start:stop:step")
    p.add_argument("--depth", help="or constant depth(s) in mm")
    p.add_argument("--cylinders", help="cylinder codes, e.g. C1,C3,C5 (default C1-C8)")
    p.add_argument("--material", help="material code mABCDE (default: the model's)")
    p.add_argument("--axis", "--orientation", dest="orientation",
                   help="cylinder axis (default: parallel in 2D, perpendicular to the finger in 3D)")
    p.add_argument("--position", type=FINITE, nargs=2, metavar=("X", "Z"),
                   help="load position on the pad in mm (default: the middle of the pad)")
    p.add_argument("--nu", type=NONNEGATIVE, help="Poisson ratio (default: the model's)")
    p.add_argument("--out", help="output folder (default: <model>/contact_series)")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_contact_series)


def _run_contact_series(args):
    from fingertip.jobs.biomech import run_contact_series

    text = run_contact_series(args.model, args.out or str(Path(args.model) / "contact_series"),
                              material=args.material, cylinders=args.cylinders, forces=args.force,
                              depths=args.depth, orientation=args.orientation, position_mm=args.position, nu=args.nu,
                              progress=not args.quiet)
    if not args.quiet:
        print(text)


# --------------------------------------------------------------------------- analyze
def _add_analyze(sub):
    p = sub.add_parser("analyze", help="fit the linear receptor model d = a S + b to recorded rates: "
                                       "ranked candidate table, profile and scatter plots")
    p.add_argument("results", nargs="+", help="indentation results folder(s) from `pipeline.py indent`; two "
                                              "2D runs of different model diameters make the diameter free")
    p.add_argument("--neural", required=True, help="neural CSV: stimulus,position_mm,rate_ips[,unit,orientation]")
    p.add_argument("--diameters", type=POSITIVE, nargs=2, metavar=("D1", "D2"),
                   help="model diameters of the two runs in mm (default: from each run's ../model.json)")
    p.add_argument("--measures", help="comma-separated candidates: fem.core.measures names or abs:<name> "
                                      "(default: the thesis candidates the runs computed)")
    p.add_argument("--fit-on", help="comma-separated stimuli to fit on; the others are predicted with "
                                    "the same a, b, depth (default: fit all together)")
    p.add_argument("--orientation", help="use only rows with this bar orientation")
    p.add_argument("--receptor-x", type=FINITE, default=0.0, help="lateral receptor position in mm (default 0: "
                                                                  "the central receptor)")
    p.add_argument("--out", help="output folder (default: <first results folder>/analysis)")
    p.add_argument("--quiet", action="store_true", help="no summary")
    p.set_defaults(run=_run_analyze)


def _run_analyze(args):
    from fingertip.jobs.analyze import run_analyze

    text = run_analyze(args.results, args.neural, out_dir=args.out, diameters_mm=args.diameters,
                       measures=args.measures, fit_on=args.fit_on, orientation=args.orientation,
                       receptor_x_mm=args.receptor_x)
    if not args.quiet:
        print(text)


# --------------------------------------------------------------------------- run
def _add_run(sub):
    p = sub.add_parser("run", help="the chain: reconstruct -> mesh [-> indent a scene]; current stages are skipped")
    p.add_argument("images", nargs="?", default=str(HERE / "sample_images"),
                   help="turntable folder (default: the bundled sample_images/)")
    p.add_argument("--out", default="out/sample", help="output folder for every stage (default out/sample)")
    p.add_argument("--size", type=POSITIVE, default=0.5, help="mesh: target edge length on the volar skin in mm")
    p.add_argument("--scene", help="indent: a TOML scene file to run on the model (optional)")
    p.add_argument("--force", action="store_true", help="recompute every stage")
    p.add_argument("--quiet", action="store_true", help="no progress and no summaries")
    p.set_defaults(run=_run_run)


def _run_run(args):
    from fingertip.jobs.reconstruct import chain_steps

    parser = build_parser()
    steps = chain_steps(args.images, args.out, args.size, args.scene, force=args.force, quiet=args.quiet)
    stages = [parser.parse_args(step) for step in steps]          # every stage's options, before any runs
    for stage in stages:
        stage.check(stage)
    for step, stage in zip(steps, stages):
        if not args.quiet:
            print(f"== {step[0]}")
        stage.run(stage)


# --------------------------------------------------------------------------- batch
def _add_batch(sub):
    p = sub.add_parser("batch", help="a cohort: each subject reconstruct -> mesh -> scene, then summary.csv "
                                     "and cohort.png comparing them; in this process or on Dask")
    p.add_argument("subjects", nargs="+", metavar="SUBJECT",
                   help="turntable folder, folder with sections.json, or preset:NAME (human, monkey, block, "
                        "square, cylinder8, cylinder16; preset:cylinder8:bone adds the 2D bone)")
    p.add_argument("--scene", required=True, help="TOML scene file every subject runs (scenes/*.toml)")
    p.add_argument("--out", required=True, help="output folder: <out>/<subject>/ and <out>/summary.csv")
    p.add_argument("--size", type=POSITIVE, help="mesh: target edge length on the volar skin / top surface in mm "
                                               "(default 0.5 in 3D, 0.125 in 2D)")
    p.add_argument("--coarse", type=POSITIVE, help="mesh: largest edge length in mm (default 3.0 in 3D, 1.0 in 2D)")
    p.add_argument("--growth", type=POSITIVE, help="mesh: edge length growth per mm (default 0.5)")
    p.add_argument("--fine-depth", type=POSITIVE, help="mesh: depth of the fine zone in mm (default 1.5 3D, 1.0 2D)")
    p.add_argument("--tip", default="flat", help="3D distal end: flat (default), rounded or a dome length in mm")
    _scheduler_option(p, "subject")
    p.add_argument("--force", action="store_true", help="recompute reconstruct and 3D mesh stages")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_batch, check=_check_batch)


def _batch_options(args) -> dict:
    from fingertip.jobs.batch import MeshOptions, parse_subjects

    return dict(subjects=parse_subjects(args.subjects), scene_path=args.scene, out_dir=args.out,
                mesh=MeshOptions(size_mm=args.size, coarse_mm=args.coarse, growth=args.growth,
                                 fine_depth_mm=args.fine_depth, tip=args.tip), scheduler=args.scheduler)


def _check_batch(args):
    from fingertip.jobs.batch import check_batch

    check_batch(**_batch_options(args))


def _run_batch(args):
    from fingertip.jobs.batch import run_batch

    text = run_batch(**_batch_options(args), force=args.force, progress=not args.quiet)
    if not args.quiet:
        print(text)


# --------------------------------------------------------------------------- thesis reproduction
def _add_reproduce(sub):
    p = sub.add_parser("reproduce", help="run the thesis's experiments (chapters 4-7) and write a report: "
                                         "what the thesis states, the project's number, a verdict")
    p.add_argument("--out", required=True, help="report folder (new, empty, or an earlier reproduce run "
                                                "of the same kind to resume)")
    p.add_argument("--quick", action="store_true", help="coarse meshes (0.25 mm in the top 1 mm instead "
                                                        "of the thesis's 0.125 mm)")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_reproduce)


def _run_reproduce(args):
    from fingertip.jobs.reproduce import run_reproduce

    text = run_reproduce(args.out, quick=args.quick, progress=not args.quiet)
    if not args.quiet:
        print(text)


# --------------------------------------------------------------------------- main
COMMANDS = [_add_reconstruct, _add_render, _add_mesh, _add_prepare, _add_indent, _add_study_layers, _add_fit_material,
            _add_line_load, _add_contact_series, _add_analyze, _add_run, _add_batch,
            _add_reproduce]


def build_parser(prog: str = "pipeline.py") -> argparse.ArgumentParser:
    parser = _Parser(prog=prog, description=__doc__.split("\n\n")[0],
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in COMMANDS:
        add(sub)
    return parser


DEBUG_ENV = "FINGERTIP_DEBUG"
"""Environment variable: when set (non-empty), an internal error also prints its traceback."""


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread like Ctrl-C, so the same cleanups run."""


def _terminate(signum, frame):
    raise Terminated()


def _one_line(text) -> str:
    return " ".join(str(text).split())


def main(argv: list[str] | None = None) -> int:
    """Run one command (argv: its words, default sys.argv[1:]); returns the exit code: 0 done,
    2 bad input (one `error:` line), 130 Ctrl-C, 143 SIGTERM, 1 an internal error (a bug)."""
    installed = argv is None and Path(sys.argv[0]).stem == "fingertip"      # the console script
    try:
        previous = signal.signal(signal.SIGTERM, _terminate)
    except ValueError:                                    # not the main thread: leave signals alone
        previous = None
    try:
        args = build_parser("fingertip" if installed else "pipeline.py").parse_args(argv)
        args.run(args)
    except InputError as exc:
        print(f"error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        print("error: interrupted; nothing was written", file=sys.stderr)
        return 143 if isinstance(exc, Terminated) else 130
    except Exception as exc:  # noqa: BLE001 - the last resort: one line, not a traceback
        if os.environ.get(DEBUG_ENV):
            traceback.print_exc()
        print(f"error: internal error {type(exc).__name__}: {_one_line(exc)} (a bug; set {DEBUG_ENV}=1 "
              "for the traceback and report it)", file=sys.stderr)
        return 1
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
    return 0


if __name__ == "__main__":
    sys.exit(main())
