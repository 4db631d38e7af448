"""`reproduce`: the source thesis claim by claim, into a report folder (`fingertip.jobs.reproduce`)."""
from __future__ import annotations

from pathlib import Path

from fingertip.jobs.reproduce import run_reproduce
from fingertip.staging import claimed


def add_reproduce(p):
    """The `reproduce` command's arguments on its parser `p`."""
    p.add_argument("--out", required=True, help="report folder (new, empty, or an earlier reproduce run "
                                                "of the same kind to resume)")
    p.add_argument("--quick", action="store_true", help="the two coarsest mesh levels (2D 0.25 and 0.125 mm, 3D "
                                                        "1.5 and 1 mm) instead of the two finest (0.125 and "
                                                        "0.0625 mm, 1 and 0.5 mm)")
    p.add_argument("--quiet", action="store_true", help="no progress and no summary")
    p.set_defaults(run=_run_reproduce, kept=kept)


def kept(args) -> str | None:
    """What an interrupted reproduce keeps: the claims done (claims/<name>.json), which a rerun
    resumes, and the meshes made (None: nothing, the folder does not exist)."""
    out = Path(args.out)
    if not out.is_dir() or not any(out.iterdir()):
        return None
    done = len(list((out / "claims").glob("*.json")))
    if done:
        return (f"the {done} claim{'s' if done != 1 else ''} done {'are' if done != 1 else 'is'} kept in {out} "
                f"and a rerun resumes {'them' if done != 1 else 'it'}")
    return f"no claim was done yet; what was made in {out} (the meshes) is kept and a rerun reuses it"


def _run_reproduce(args):
    with claimed(args.out):
        text = run_reproduce(args.out, quick=args.quick, progress=not args.quiet)
    if not args.quiet:
        print(text)
