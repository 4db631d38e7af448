"""`reproduce`: the source thesis claim by claim, into a report folder (`fingertip.jobs.reproduce`)."""
from __future__ import annotations

from fingertip.jobs.reproduce import run_reproduce


def add_reproduce(p):
    """The `reproduce` command's arguments on its parser `p`."""
    p.add_argument("--out", required=True, help="report folder (new, empty, or an earlier reproduce run "
                                                "of the same kind to resume)")
    p.add_argument("--quick", action="store_true", help="coarse meshes (0.25 mm in the top 1 mm instead "
                                                        "of the thesis's 0.125 mm)")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_reproduce)


def _run_reproduce(args):
    text = run_reproduce(args.out, quick=args.quick, progress=not args.quiet)
    if not args.quiet:
        print(text)
