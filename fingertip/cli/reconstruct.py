"""`reconstruct` (turntable images -> sections), `render` (a synthetic turntable set of a known
shape) and `run` (the chain reconstruct -> mesh [-> indent a scene])."""
from __future__ import annotations

from fem.geometry.presets import SHAPES
from fingertip.cli.options import POSITIVE
from fingertip.jobs.reconstruct import chain_stages, run_reconstruct
from fingertip.jobs.render import run_render
from fingertip.resources import shipped
from fingertip.staging import check_output_dir


def add_reconstruct(p):
    """The `reconstruct` command's arguments on its parser `p`."""
    p.add_argument("images", nargs="?", default=str(shipped("sample_images")),
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
    p.set_defaults(run=_run_reconstruct, check=lambda args: check_output_dir(args.out))


def _run_reconstruct(args):
    text = run_reconstruct(args.images, args.out, spacing_mm=args.spacing_mm, tol_mm=args.tol_mm,
                           tip_fraction=args.tip_fraction, force=args.force, progress=not args.quiet)
    if not args.quiet:
        print(text)


def add_render(p):
    """The `render` command's arguments on its parser `p`."""
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
    text = run_render(args.shape, args.out, views=args.views, span_deg=args.span_deg, size_px=args.size,
                      mm_per_px=args.mm_per_px, aspect=args.aspect, blur_px=args.blur_px, noise=args.noise,
                      vignetting=args.vignetting, axis_offset_px=args.axis_offset_px, tilt_deg=args.tilt_deg,
                      rod=not args.no_rod, groove=args.groove, seed=args.seed, progress=not args.quiet,
                      camera_distance_mm=args.camera_distance_mm, write_camera=args.write_camera,
                      distortion=args.distortion, checkerboard=args.checkerboard)
    if not args.quiet:
        print(text)


def add_run(p):
    """The `run` command's arguments on its parser `p`."""
    p.add_argument("images", nargs="?", default=str(shipped("sample_images")),
                   help="turntable folder (default: the bundled sample_images/)")
    p.add_argument("--out", default="out/sample", help="output folder for every stage (default out/sample)")
    p.add_argument("--size", type=POSITIVE, default=0.5, help="mesh: target edge length on the volar skin in mm")
    p.add_argument("--scene", help="indent: a TOML scene file to run on the model (optional)")
    p.add_argument("--force", action="store_true", help="recompute every stage")
    p.add_argument("--quiet", action="store_true", help="no progress and no summaries")
    p.set_defaults(run=_run_run, kept=_run_kept)


def _run_kept(args) -> str | None:
    """What an interrupted chain keeps: the outputs of the stages it finished (None: none)."""
    done = getattr(args, "stages_done", [])
    if not done:
        return None
    return f"the {' and '.join(done)} outputs are kept in {args.out} and a rerun skips them"


def _run_run(args):
    stages = chain_stages(args.images, args.out, args.size, args.scene, force=args.force, progress=not args.quiet)
    args.stages_done = []
    for stage in stages:
        if not args.quiet:
            print(f"== {stage.name}")
        text = stage.run()
        args.stages_done.append(stage.name)
        if not args.quiet:
            print(text)
