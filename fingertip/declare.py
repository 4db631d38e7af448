"""Parameters declared once. A dataclass field made with `declared` carries, besides its default,
its unit and meaning and how it is read from the words a user writes; the scene schema, the
command line's flags and their help are all derived from it (`fingertip.cli.options`).

    @dataclass(frozen=True)
    class Sizing:
        size_mm: float = declared(0.5, "mm", "target edge length on the volar skin")

    meaning(fields(Sizing)[0])    # {"unit": "mm", "doc": "target edge length ...", ...}

Keys of the metadata: unit (a display string, "" for none), doc (what the value means, one
phrase), parse (value, key, where) -> value for TOML values (fem.experiments.scene), text
(str) -> value for a command-line word (ValueError with a message for a bad word; `finite`,
`positive`, `nonnegative` for numbers), nargs (words the command line takes, when not one; text
then reads each word), words (list of words) -> value, for a value read from its words together,
flag (the command-line flag, or flags, when not derived from the name), default_text (the
default as the help shows it, when the default is not the value itself, e.g. "the model's").
"""
from __future__ import annotations

import dataclasses
import math
from typing import Any, Callable

UNIT_SUFFIXES = ("_mm", "_N", "_MPa", "_deg", "_frac", "_s", "_hz", "_per_cm2")
"""Suffixes a field name carries for its unit; a derived flag leaves them out (depth_mm -> --depth)."""


def declared(default: Any = dataclasses.MISSING, unit: str = "", doc: str = "", *,
             factory: Callable | None = None, parse: Callable | None = None, text: Callable | None = None,
             flag: str | tuple | None = None, default_text: str | None = None, toml: str | None = None,
             nargs: int | str | None = None, words: Callable | None = None):
    """A dataclass field with its unit, meaning and readers (see the module docstring). factory:
    a zero-argument callable giving the default (for mutable or computed defaults)."""
    kw = {"default_factory": factory} if factory is not None else {"default": default}
    meta = {"unit": unit, "doc": doc, "parse": parse, "text": text, "flag": flag,
            "default_text": default_text, "toml": toml, "nargs": nargs, "words": words}
    return dataclasses.field(**kw, metadata=meta)


def meaning(f: dataclasses.Field) -> dict:
    """The declared metadata of a dataclass field ({} for a plain field)."""
    return dict(f.metadata)


def field_of(cls, name: str) -> dataclasses.Field:
    """The dataclass field `name` of cls (KeyError names the class's fields)."""
    for f in dataclasses.fields(cls):
        if f.name == name:
            return f
    raise KeyError(f"{cls.__name__} has no field {name!r}")


def default_of(f: dataclasses.Field):
    """The default value of a dataclass field (MISSING when it has none)."""
    if f.default is not dataclasses.MISSING:
        return f.default
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return dataclasses.MISSING


def bare_name(name: str) -> str:
    """A field name without its unit suffix (depth_mm -> depth, nail_z_frac -> nail_z)."""
    for suffix in UNIT_SUFFIXES:
        if name.endswith(suffix):
            return name[:-len(suffix)]
    return name


def _number(word: str, low: float | None = None, strict: bool = True) -> float:
    value = float(word)                       # ValueError: "could not convert string to float"
    if not math.isfinite(value) or (low is not None and not (value > low if strict else value >= low)):
        want = "finite" + ("" if low is None else f" and {'>' if strict else '>='} {low:g}")
        raise ValueError(f"must be {want}, got {word}")
    return value


def finite(word: str) -> float:
    """A finite number from a word (ValueError otherwise)."""
    return _number(word)


def positive(word: str) -> float:
    """A finite number > 0 from a word."""
    return _number(word, 0.0)


def nonnegative(word: str) -> float:
    """A finite number >= 0 from a word."""
    return _number(word, 0.0, strict=False)
