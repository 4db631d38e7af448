#!/usr/bin/env python
"""Command line for the fingertip toolkit. CLI only: parse arguments, call the library, print a summary.

    python pipeline.py reconstruct sample_images/ --out out/sample
    python pipeline.py render fingertip --out my_images/
    python pipeline.py <command> --help

Bad input ends with one line `error: ...` on stderr and exit code 2, and writes nothing.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from reconstruct.errors import InputError

HERE = Path(__file__).resolve().parent


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (exit code 2)."""

    def error(self, message):
        raise InputError(f"{self.prog}: {message} (see --help)")


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
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    p.set_defaults(run=_run_reconstruct)


def _run_reconstruct(args):
    from reconstruct.pipeline import reconstruct_folder

    result = reconstruct_folder(args.images, args.out, spacing_mm=tuple(args.spacing_mm),
                                tol_mm=args.tol_mm, tip_fraction=args.tip_fraction,
                                progress=not args.quiet)
    if not args.quiet:
        print(result.summary())


# --------------------------------------------------------------------------- render
def _add_render(sub):
    from reconstruct.synthetic import SHAPES

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
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    p.set_defaults(run=_run_render)


def _run_render(args):
    from reconstruct.synthetic import render_turntable, make_shape

    shape = make_shape(args.shape, groove=args.groove)
    info = render_turntable(shape, args.out, n_views=args.views, span_deg=args.span_deg,
                            size_px=tuple(args.size), mm_per_px=args.mm_per_px, aspect=args.aspect,
                            blur_px=args.blur_px, noise=args.noise, vignetting=args.vignetting,
                            axis_offset_px=args.axis_offset_px, tilt_deg=args.tilt_deg,
                            rod=not args.no_rod, seed=args.seed, progress=not args.quiet)
    if not args.quiet:
        print(f"rendered {info['views']} views of '{args.shape}' to {args.out} "
              f"({info['size_px'][0]} x {info['size_px'][1]} px, {info['mm_per_px']} mm/px); "
              f"ground truth in {args.out}/truth.json")


# --------------------------------------------------------------------------- main
COMMANDS = [_add_reconstruct, _add_render]


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="pipeline.py", description=__doc__.split("\n\n")[0],
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in COMMANDS:
        add(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    try:
        args = build_parser().parse_args(argv)
        args.run(args)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("error: interrupted; nothing was written", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
