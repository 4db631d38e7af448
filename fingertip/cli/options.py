"""Command-line options: the one-line-error parser, number types, and flags derived from the
declared parameters (`fingertip.declare`): a field's flag is `--` + its name without the unit
suffix (depth_mm -> --depth), its help its meaning, unit and default, its type its word reader.

    add_declared(p, Receptors, ("depths_mm", "spacing_mm", "line"))   # --receptor-depths, ...
    given = declared_values(args, Receptors, ("depths_mm", "spacing_mm", "line"))   # {name: value}
"""
from __future__ import annotations

import argparse
import dataclasses

from fingertip.declare import (
    bare_name,
    default_of,
    field_of,
    finite,
    nonnegative,
    positive,
)
from fingertip.distribute import INSTALL_HINT
from fingertip.errors import InputError


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors (InputError; exit code 2)."""

    def error(self, message):
        raise InputError(f"{self.prog}: {message} (see --help)")


def word_type(read, name: str = "value"):
    """An argparse type from a word reader (ValueError -> argparse's one-line error)."""
    def convert(word):
        try:
            return read(word)
        except ValueError as exc:
            text = str(exc)
            raise argparse.ArgumentTypeError(f"'{word}' is not a number" if "convert" in text else text) from None
    convert.__name__ = name
    return convert


FINITE, POSITIVE, NONNEGATIVE = word_type(finite, "finite"), word_type(positive, "positive"), \
    word_type(nonnegative, "nonnegative")


def number(low: float | None = None, strict: bool = True, high: float | None = None):
    """argparse type: a finite number above `low` (strict: > low, else >=) and <= high if given."""
    def read(word):
        value = finite(word)
        ok = (low is None or (value > low if strict else value >= low)) and (high is None or value <= high)
        if not ok:
            want = ["finite"] + ([f"{'>' if strict else '>='} {low:g}"] if low is not None else []) \
                + ([f"<= {high:g}"] if high is not None else [])
            raise ValueError(f"must be {' and '.join(want)}, got {word}")
        return value
    return word_type(read, "number")


def flags_of(f: dataclasses.Field, prefix: str = "") -> tuple[str, ...]:
    """The command-line flags of a declared field."""
    flag = f.metadata.get("flag")
    if flag:
        return (flag,) if isinstance(flag, str) else tuple(flag)
    return ("--" + prefix + bare_name(f.name).replace("_", "-"),)


def help_of(f: dataclasses.Field, default_text: str | None = None) -> str:
    """Help text of a declared field: its meaning, unit and default ('default_text' overrides)."""
    meta = f.metadata
    unit = meta.get("unit") or ""
    text = meta.get("doc") or f.name
    if unit and unit not in text:
        text += f" in {unit}"
    default = default_text or meta.get("default_text")
    if default is None:
        value = default_of(f)
        if value is not dataclasses.MISSING and value is not None and not isinstance(value, bool):
            default = " ".join(f"{v:g}" for v in value) if isinstance(value, tuple) else (
                f"{value:g}" if isinstance(value, float) else str(value))
    return text + (f" (default {default})" if default else "")


UNSET = type("Unset", (), {"__repr__": lambda self: "UNSET"})()
"""The value of a declared flag the user did not give (a given value may be None: --tip rounded)."""


def add_declared(parser, cls, names, prefix: str = "", defaults: dict | None = None, **extra) -> None:
    """Add the flags of fields `names` of dataclass `cls` to `parser`, each with dest = the field
    name and default UNSET (what a user does not give keeps the declaration's default).
    defaults: {name: help text of the default} where it depends on more than the field (e.g. the
    model's dimension); extra: {name: dict of add_argument keywords} that replace the derived."""
    for name in names:
        f = field_of(cls, name)
        meta = f.metadata
        kw = {"dest": name, "default": UNSET, "help": help_of(f, (defaults or {}).get(name))}
        if str(f.type).replace(" ", "") in ("bool", "bool|None"):
            switch = default_of(f) is False             # a switch; else --x / --no-x
            kw.update(action="store_true", default=UNSET) if switch else kw.update(action=argparse.BooleanOptionalAction)
        else:
            if meta.get("text") is not None:
                kw["type"] = word_type(meta["text"], bare_name(name))
            if meta.get("nargs") is not None:
                kw["nargs"] = meta["nargs"]
            kw["metavar"] = bare_name(name).upper()
        kw.update(extra.get(name, {}))
        parser.add_argument(*flags_of(f, prefix), **kw)


def declared_values(args, cls, names) -> dict:
    """{field name: value} of the fields `names` of `cls` the user gave, read from the argparse
    namespace (dest = field name)."""
    out = {}
    for name in names:
        value = getattr(args, name)
        if value is UNSET:
            continue
        words = field_of(cls, name).metadata.get("words")
        out[name] = words(value) if words else tuple(value) if isinstance(value, list) else value
    return out


def scheduler_option(p, task: str) -> None:
    """--scheduler: where the tasks (one per `task`) run."""
    p.add_argument("--scheduler", default="none",
                   help=f"none (default: this process), local:N (N worker processes on this machine) or "
                        f"tcp://HOST:PORT (a running Dask cluster), one task per {task}; Dask needs {INSTALL_HINT}")
