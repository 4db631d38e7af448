"""`analyze`: the linear receptor model fitted to recorded rates (`fingertip.jobs.analyze`)."""
from __future__ import annotations

from fingertip.cli.biomech import words
from fingertip.cli.options import FINITE, POSITIVE
from fingertip.jobs.analyze import run_analyze


def add_analyze(p):
    """The `analyze` command's arguments on its parser `p`."""
    p.add_argument("results", nargs="+", help="indentation results folder(s) from `pipeline.py indent`; two "
                                              "2D runs of different model diameters make the diameter free")
    p.add_argument("--neural", required=True, help="neural CSV: stimulus,position_mm,rate_ips[,unit,orientation]")
    p.add_argument("--diameters", type=POSITIVE, nargs=2, metavar=("D1", "D2"),
                   help="model diameters of the two runs in mm (default: from each run's ../model.json)")
    p.add_argument("--measures", type=words, help="comma-separated candidates: fem.core.measures names or abs:<name> "
                                      "(default: the thesis candidates the runs computed)")
    p.add_argument("--fit-on", type=words, help="comma-separated stimuli to fit on; the others are predicted with "
                                    "the same a, b, depth (default: fit all together)")
    p.add_argument("--orientation", help="use only rows with this bar orientation")
    p.add_argument("--receptor-x", type=FINITE, default=0.0, help="lateral receptor position in mm (default 0: "
                                                                  "the central receptor)")
    p.add_argument("--out", help="output folder (default: <first results folder>/analysis)")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_analyze)


def _run_analyze(args):
    text = run_analyze(args.results, args.neural, out_dir=args.out, diameters_mm=args.diameters,
                       measures=args.measures, fit_on=args.fit_on, orientation=args.orientation,
                       receptor_x_mm=args.receptor_x, progress=not args.quiet)
    if not args.quiet:
        print(text)
