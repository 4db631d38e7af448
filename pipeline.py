#!/usr/bin/env python
"""Command line for the fingertip toolkit (`fingertip.cli`): parse arguments, run a job, print
its summary.

    python pipeline.py reconstruct sample_images/ --out out/sample
    python pipeline.py render fingertip --out my_images/
    python pipeline.py <command> --help
    fingertip <command> ...            (the same, once installed with `pip install -e .`)

Bad input ends with one line `error: ...` on stderr and exit code 2, and writes nothing.
"""
import sys

from fingertip.cli import DEBUG_ENV, build_parser, main

__all__ = ["DEBUG_ENV", "build_parser", "main"]

if __name__ == "__main__":
    sys.exit(main())
