"""The command line: one subcommand per job (`fingertip.jobs`), its flags derived from the
declared parameters (`fingertip.cli.options`). It parses words into objects, runs the job and
prints the summary; nothing else.

    fingertip <command> ...        python pipeline.py <command> ...        main(["mesh", "--help"])

Bad input ends with one line `error: ...` on stderr and exit code 2, and writes nothing.

Only the module of the command given is imported (`COMMANDS`): all of them with the science
behind them take 1.3 s to import, one 0.1-0.7 s, and `--help` alone 0.1 s.
"""
from __future__ import annotations

import importlib
import logging
import os
import re
import signal
import sys
import traceback
from pathlib import Path

from fem.core.longcalls import end_interrupted
from fingertip.cli.options import UNSET, Parser
from fingertip.errors import InputError

COMMANDS = {
    "reconstruct": ("reconstruct", "add_reconstruct", "turntable images -> sections.json, surface.stl, report.png"),
    "render": ("reconstruct", "add_render", "render a synthetic turntable set of a known shape (+ ground truth)"),
    "mesh": ("mesh", "add_mesh", "layered model + tetrahedral mesh (or a 2D plane-strain mesh) -> mesh.vtu, "
             "model.json"),
    "prepare": ("indent", "add_prepare", "store a model's response model (compliance of the pad and receptor "
                "response) so later indent commands answer without factorising"),
    "indent": ("indent", "add_indent", "rigid indentors on a meshed model: depth or force control, sweeps -> CSV, "
               "PNG, PVD"),
    "explore": ("explore", "add_explore", "the live explorer in the browser: move an indentor over the pad and see "
                "pressure, deflection and receptor measures follow (optional extra 'explore')"),
    "study-layers": ("biomech", "add_study_layers", "layer-stiffness study (thesis fig. 6-10): deflection profiles "
                     "under a line load with each layer's modulus varied by powers of ten"),
    "fit-material": ("biomech", "add_fit_material", "fit layer moduli to measured deflection profiles (ratios) and "
                     "force-depth data (absolute scale)"),
    "line-load": ("biomech", "add_line_load", "surface deflection and force under a prescribed line load (thesis "
                  "6.2.1); --large-deformation adds the neo-Hookean solve and compares"),
    "contact-series": ("biomech", "add_contact_series", "cylinders C1-C8 at constant force or depth: contact area "
                       "(2D: width) and max pressure vs diameter (thesis figs. 4-25, 5-14)"),
    "analyze": ("analyze", "add_analyze", "fit the linear receptor model d = a S + b to recorded rates: ranked "
                "candidate table, profile and scatter plots"),
    "run": ("reconstruct", "add_run", "the chain: reconstruct -> mesh [-> indent a scene]; current stages are "
            "skipped"),
    "batch": ("batch", "add_batch", "a cohort: each subject reconstruct -> mesh -> scene, then summary.csv and "
              "cohort.png comparing them; in this process or on Dask"),
    "reproduce": ("reproduce", "add_reproduce", "run the thesis's experiments (chapters 4-7) and write a report: "
                  "what the thesis states, the project's number, a verdict"),
}
"""Every subcommand: (module of fingertip.cli, the function adding its arguments, help), in the
order `--help` lists them."""
DESCRIPTION = "Command line for the fingertip toolkit: turntable photographs -> layered finite-element model -> " \
              "tactile indentation experiments."
DEBUG_ENV = "FINGERTIP_DEBUG"
"""Environment variable: when set (non-empty), an internal error also prints its traceback."""
LOGGERS = ("fem", "fingertip", "reconstruct")
"""The packages whose log warnings the command line prints as `warning: ...` lines on stderr."""
WORD_FLAGS = ("material",)
"""Parameters named by a plain word in messages ("material m433310 has 6 digits ..."): rewritten
into their flag (--material) only when the flag was given, since the word has other uses."""


def build_parser(prog: str = "pipeline.py", command: str | None = None) -> Parser:
    """The command line's parser with the arguments of `command` (each subcommand sets `run` and,
    where it checks its options before any work, `check`); the other subcommands are listed with
    their help only (None: all of them; every one with "all")."""
    parser = Parser(prog=prog, description=DESCRIPTION)
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    parser.commands = {}
    for name, (module, add, help_text) in COMMANDS.items():
        p = parser.commands[name] = sub.add_parser(name, help=help_text)
        if command in (name, "all"):
            getattr(importlib.import_module(f"fingertip.cli.{module}"), add)(p)
    return parser


def flag_table(parser, args=None) -> dict[str, str]:
    """{field name: flag} of a subcommand's parser: the parameter names (argparse dests with an
    underscore, e.g. size_mm) whose values its flags give (--size). With args (the parsed
    namespace), a field the command reads from its --scene file (`from_scene`) counts only when
    its flag was given; a word of WORD_FLAGS counts only when its flag was given."""
    from_scene = set(getattr(args, "from_scene", ())) if getattr(args, "scene", None) else set()
    table = {}
    for action in parser._actions:
        given = action.dest in WORD_FLAGS and getattr(args, action.dest, None) not in (None, UNSET)
        if not action.option_strings or ("_" not in action.dest and not given):
            continue
        if action.dest in from_scene and getattr(args, action.dest, UNSET) is UNSET:
            continue
        table[action.dest] = next((o for o in action.option_strings if o.startswith("--")), action.option_strings[0])
    return table


def user_words(message: str, table: dict[str, str]) -> str:
    """A message in the command line's words: each parameter name of `table` (a whole word, e.g.
    size_mm, not fine_size_mm) replaced by its flag (--size)."""
    if not table:
        return message
    names = "|".join(re.escape(n) for n in sorted(table, key=len, reverse=True))
    return re.sub(rf"(?<![\w-])({names})(?!\w)", lambda m: table[m.group(1)], message)


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread like Ctrl-C, so the same cleanups run."""


def _terminate(signum, frame):
    raise Terminated()


def _one_line(text) -> str:
    return " ".join(str(text).split())


class _WarningLines(logging.Handler):
    """Log records of WARNING and above as one `warning: ...` line each on stderr."""

    def emit(self, record):
        print(f"warning: {_one_line(record.getMessage())}", file=sys.stderr, flush=True)


def _kept(args) -> str:
    """What an interrupted command keeps: its `kept(args)` (a subcommand that keeps finished
    parts says which, e.g. `reproduce` its claims), else that nothing was written."""
    try:
        text = args.kept(args) if args is not None and getattr(args, "kept", None) else None
    except Exception:  # noqa: BLE001 - the message of an interrupt must not fail
        text = None
    return text or "nothing was written"


def main(argv: list[str] | None = None) -> int:
    """Run one command (argv: its words, default sys.argv[1:]); returns the exit code: 0 done,
    2 bad input (one `error:` line), 130 Ctrl-C, 143 SIGTERM, 1 an internal error (a bug)."""
    installed = argv is None and Path(sys.argv[0]).stem == "fingertip"      # the console script
    try:
        previous = signal.signal(signal.SIGTERM, _terminate)
    except ValueError:                                    # not the main thread: leave signals alone
        previous = None
    handler = _WarningLines(logging.WARNING)
    loggers = [logging.getLogger(name) for name in LOGGERS]
    for logger in loggers:
        logger.addHandler(handler)
    parser = args = command = None
    try:
        words = sys.argv[1:] if argv is None else [str(w) for w in argv]
        command = words[0] if words and words[0] in COMMANDS else None
        parser = build_parser("fingertip" if installed else "pipeline.py", command)
        args = parser.parse_args(words)
        args.run(args)
    except InputError as exc:
        table = flag_table(parser.commands[command], args) if command is not None and parser is not None else {}
        print(f"error: {_one_line(user_words(str(exc), table))}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        print(f"error: interrupted; {_kept(args)}", file=sys.stderr)
        return end_interrupted(143 if isinstance(exc, Terminated) else 130)
    except Exception as exc:  # noqa: BLE001 - the last resort: one line, not a traceback
        if os.environ.get(DEBUG_ENV):
            traceback.print_exc()
        print(f"error: internal error {type(exc).__name__}: {_one_line(exc)} (a bug; set {DEBUG_ENV}=1 "
              "for the traceback and report it)", file=sys.stderr)
        return 1
    finally:
        for logger in loggers:
            logger.removeHandler(handler)
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
    return 0
