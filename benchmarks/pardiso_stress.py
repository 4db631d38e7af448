"""PARDISO under load: the 2D cylinder models' contact factorisations (each a Schur complement onto
the contact candidates) repeated in a fresh process per trial, counting the trials that end by a
signal (a crash inside MKL) next to the time per factorisation. A check to run after an MKL or
pypardiso upgrade, or a change to how `fem.core.linalg` sets PARDISO's threads: with MKL's local
thread count set to one in a thread other than the main one (the code before this check existed),
15 of 21 trials of 700 rounds crashed in PARDISO's analysis (docs/indentation.md); with the
count set on the main thread only, none of 13. Writes benchmarks/results/pardiso_stress.md.

    python benchmarks/pardiso_stress.py --trials 4 --rounds 700
"""
from __future__ import annotations

import argparse
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
OUT = ROOT / "benchmarks" / "results" / "pardiso_stress.md"
MODELS = (("cylinder8_bone", True), ("cylinder8_bone", False), ("cylinder8_fluid", False))
"""(2D model, bone held) factorised in each round: three Schur factorisations of 2,138-5,057 unknowns."""


def workshop(folder: Path):
    """The thesis models' Workshop at 0.25 mm in 2D (the test suite's level), meshed once in folder."""
    from fem.thesis.findings import MeshLevel, Workshop

    return Workshop(folder, quick=True, level=MeshLevel("0.25 mm 2D", 0.25, 1.5))


def child(folder: Path, rounds: int) -> None:
    """Factorise the MODELS `rounds` times; print the count and the seconds."""
    shop = workshop(folder)
    t0 = time.perf_counter()
    for _ in range(rounds):
        for name, held in MODELS:
            shop.contact_model(name, rigid_bone=held)
    print(rounds * len(MODELS), time.perf_counter() - t0, flush=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", type=int, default=4)
    ap.add_argument("--rounds", type=int, default=700)
    ap.add_argument("--child", type=Path, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child is not None:
        child(args.child, args.rounds)
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        for name in {name for name, _ in MODELS}:        # meshed once, before any trial
            workshop(Path(tmp)).folder(name)
        rows = []
        for trial in range(1, args.trials + 1):
            run = subprocess.run([sys.executable, __file__, "--child", tmp, "--rounds", str(args.rounds)],
                                 capture_output=True, text=True)
            if run.returncode == 0:
                count, seconds = run.stdout.split()
                rows.append((trial, int(count), float(seconds), "finished"))
            else:
                why = (f"crashed ({signal.Signals(-run.returncode).name})" if run.returncode < 0
                       else f"failed (exit {run.returncode})")
                rows.append((trial, None, None, why))
            print(*rows[-1], flush=True)
    crashed = sum(r[3] != "finished" for r in rows)
    lines = ["# PARDISO under load", "", f"`python benchmarks/pardiso_stress.py --trials {args.trials} "
             f"--rounds {args.rounds}`: each trial a fresh process factorising the 2D cylinder models "
             f"{args.rounds} times (three Schur factorisations per round).", "",
             "| trial | factorisations | seconds | ms per factorisation | outcome |", "|---:|---:|---:|---:|---|"]
    for trial, count, seconds, outcome in rows:
        lines.append(f"| {trial} | {count or '-'} | {'-' if seconds is None else f'{seconds:.1f}'} | "
                     f"{'-' if seconds is None else f'{1000 * seconds / count:.1f}'} | {outcome} |")
    lines += ["", f"{crashed} of {len(rows)} trials crashed."]
    OUT.write_text("\n".join(lines) + "\n")
    print(f"{crashed} of {len(rows)} trials crashed; written to {OUT.relative_to(ROOT)}")
    return 1 if crashed else 0


if __name__ == "__main__":
    sys.exit(main())
