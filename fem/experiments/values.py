"""Value lists of scenes and command lines: "start:stop:step" ranges, comma lists and sweeps
("x=-3:3:0.1"), in mm unless a key says otherwise.

    parse_values("0:1:0.25")        # array([0., 0.25, 0.5, 0.75, 1.])
    parse_sweep("z=-2:2:1")         # (2, array([-2., -1., 0., 1., 2.]))
"""
from __future__ import annotations

import numpy as np

from fingertip.errors import InputError

MAX_VALUES = 100_000
"""Most values a value list ('a:b:step' or 'v1,v2,...') may hold."""


def _list_error(text, why: str) -> InputError:
    return InputError(f"bad value list '{text}': {why}")


def parse_values(text) -> np.ndarray:
    """'a:b:step' (inclusive), 'v1,v2,...', a number or a list -> (n,) finite floats; InputError
    for other words, non-finite numbers or more than MAX_VALUES values."""
    if isinstance(text, (int, float)):
        values = np.array([float(text)])
    elif isinstance(text, (list, tuple)):
        if len(text) > MAX_VALUES:
            raise _list_error(f"[{len(text)} values]", f"more than the {MAX_VALUES} values a list may hold")
        values = np.asarray(text, float).ravel()
    else:
        values = _parse_words(str(text))
    if not np.all(np.isfinite(values)):
        raise _list_error(text, "every value must be a finite number (no nan or inf)")
    return values


def _parse_words(text: str) -> np.ndarray:
    """The values of a value list in words (`parse_values`)."""
    usage = "use start:stop:step (e.g. 0.5:3:0.5) or v1,v2,..."
    try:
        if ":" in text:
            a, b, step = (float(t) for t in text.split(":"))
            if not all(np.isfinite((a, b, step))):
                raise _list_error(text, "start, stop and step must be finite numbers (no nan or inf)")
            if not step > 0 or b < a:
                raise ValueError
            with np.errstate(over="ignore", invalid="ignore"):
                count = np.floor((b - a) / step + 1e-9) + 1
            if not count <= MAX_VALUES:
                shown = f"{count:.0f}" if np.isfinite(count) else "too many"
                raise _list_error(text, f"{shown} values, more than the {MAX_VALUES} a list may hold: "
                                        f"use a larger step or a shorter range")
            return a + step * np.arange(int(count))
        words = text.split(",")
        if len(words) > MAX_VALUES:
            raise _list_error(text[:40] + "...", f"more than the {MAX_VALUES} values a list may hold")
        return np.array([float(t) for t in words])
    except ValueError as exc:
        if isinstance(exc, InputError):
            raise
        raise _list_error(text, usage) from None


def parse_sweep(text) -> tuple[int, np.ndarray]:
    """'x=-3:3:0.1' or 'z=...' -> (axis index, (k,) offsets in mm)."""
    axis, eq, values = str(text).partition("=")
    if not eq or axis.strip() not in ("x", "z"):
        raise InputError(f"bad sweep '{text}': use x=start:stop:step or z=start:stop:step (mm)")
    return {"x": 0, "z": 2}[axis.strip()], parse_values(values)
