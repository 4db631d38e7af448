"""Neural recordings for receptor analysis: recorded discharge rates, their validation, and the
CSV file they are kept in (`read_neural_csv`, `write_neural_csv`).

A spatial response profile is the discharge rate of one afferent plotted against the stimulus
position (thesis 4.5). The CSV has one row per recorded indentation:

    # lines starting with '#' are comments (say where the data come from)
    stimulus,position_mm,rate_ips,unit,orientation
    grating_0.5,-21.4,3.0,SA1-a,parallel
    grating_0.5,-21.2,4.5,SA1-a,parallel

- `stimulus` (required): the experiment name of the indentation run it is compared with (the
  `<name>.csv` / `<name>_receptors.csv` files `pipeline.py indent` writes).
- `position_mm` (required): the stimulus offset in the same coordinate as the run's sweep
  (`offset_x_mm`, or `offset_z_mm` for a sweep along z).
- `rate_ips` (required; `rate_imp_s` is accepted too): discharge rate in impulses per second, >= 0.
- `unit` (optional): afferent id; each unit gets its own fit (default: one unit "unit").
- `orientation` (optional): bar orientation, `parallel` or `perpendicular` to the finger axis
  (free text is kept); a file holding several orientations must be narrowed to one.

Bad input (missing columns, empty or NaN rates, negative rates, non-numeric positions) raises
`fingertip.errors.InputError` with a one-line message naming the file and line.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fingertip.errors import InputError


@dataclass(frozen=True)
class NeuralData:
    """Recorded rates: arrays of equal length n (strings as object arrays)."""
    stimulus: np.ndarray        # (n,) experiment names
    position_mm: np.ndarray     # (n,) stimulus offsets
    rate_ips: np.ndarray        # (n,) impulses per second
    unit: np.ndarray            # (n,) afferent ids
    orientation: np.ndarray     # (n,) bar orientation ('' when not given)
    source: str = "<memory>"

    def __len__(self) -> int:
        return len(self.rate_ips)

    @property
    def stimuli(self) -> list[str]:
        """Stimulus names in order of first appearance."""
        return list(dict.fromkeys(self.stimulus.tolist()))

    @property
    def units(self) -> list[str]:
        return list(dict.fromkeys(self.unit.tolist()))

    def select(self, mask) -> "NeuralData":
        m = np.asarray(mask, bool)
        return NeuralData(self.stimulus[m], self.position_mm[m], self.rate_ips[m], self.unit[m],
                          self.orientation[m], self.source)

    def only(self, unit=None, orientation=None, stimuli=None) -> "NeuralData":
        """Rows of one unit / orientation / stimulus subset (None: all)."""
        m = np.ones(len(self), bool)
        if unit is not None:
            m &= self.unit == unit
        if orientation is not None:
            m &= self.orientation == orientation
        if stimuli is not None:
            m &= np.isin(self.stimulus, list(stimuli))
        return self.select(m)


def make_neural(stimulus, position_mm, rate_ips, unit=None, orientation=None, source="<memory>") -> NeuralData:
    """NeuralData from arrays, validated like a CSV."""
    n = len(rate_ips)
    rate = np.asarray(rate_ips, float)
    pos = np.asarray(position_mm, float)
    if not (len(stimulus) == len(pos) == n):
        raise InputError(f"neural data {source}: stimulus, position_mm and rate_ips need equal lengths")
    if n == 0:
        raise InputError(f"neural data {source} has no rows: add recorded rates")
    bad = ~np.isfinite(rate)
    if bad.any():
        raise InputError(f"neural data {source}: rate_ips is NaN or missing in {int(bad.sum())} row(s) "
                         f"(first row {int(np.flatnonzero(bad)[0]) + 1}): remove those rows or give the rate")
    if (rate < 0).any():
        raise InputError(f"neural data {source}: negative rate_ips in row {int(np.flatnonzero(rate < 0)[0]) + 1}: "
                         f"discharge rates are >= 0 imp/s")
    if not np.isfinite(pos).all():
        raise InputError(f"neural data {source}: position_mm is NaN in row {int(np.flatnonzero(~np.isfinite(pos))[0]) + 1}")
    obj = lambda v, default: np.array([default] * n if v is None else [str(s) for s in v], dtype=object)  # noqa: E731
    return NeuralData(obj(stimulus, ""), pos, rate, obj(unit, "unit"), obj(orientation, ""), source)


# --------------------------------------------------------------------------- the CSV file
REQUIRED = ("stimulus", "position_mm", "rate_ips")
OPTIONAL = ("unit", "orientation")
RATE_ALIASES = ("rate_ips", "rate_imp_s")


# --------------------------------------------------------------------------- neural recordings
def read_neural_csv(path) -> NeuralData:
    """Read and validate the neural-data CSV (format in the module docstring; UTF-8, with or
    without the byte-order mark of Excel's "CSV UTF-8")."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"neural data '{path}' is not a text CSV file ({exc})") from None
    except OSError as exc:
        raise InputError(f"cannot read neural data '{path}': {exc.strerror or exc}") from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise InputError(f"neural data '{path}' is empty: need a header {','.join(REQUIRED)} and rows")
    rows = list(csv.DictReader(lines))
    header = [h.strip() for h in (csv.DictReader(lines).fieldnames or [])]
    rate_col = next((c for c in RATE_ALIASES if c in header), None)
    missing = [c for c in REQUIRED if c not in header and not (c == "rate_ips" and rate_col)]
    if missing:
        raise InputError(f"neural data '{path}' lacks column(s) {missing}: the header needs "
                         f"{','.join(REQUIRED)} (optional {','.join(OPTIONAL)}), got {header}")
    rows = [{(k or "").strip(): (v or "").strip() for k, v in r.items()} for r in rows]
    if not rows:
        raise InputError(f"neural data '{path}' has a header but no rows")
    pos, rate = [], []
    for i, r in enumerate(rows):
        line = i + 2
        for key, out in (("position_mm", pos), (rate_col, rate)):
            try:
                v = float(r[key]) if r[key] != "" else math.nan
            except ValueError:
                raise InputError(f"neural data '{path}' row {line}: {key} '{r[key]}' is not a number") from None
            if math.isnan(v):
                raise InputError(f"neural data '{path}' row {line}: {key} is empty or NaN: "
                                 f"give a number or drop the row")
            out.append(v)
        if not r["stimulus"]:
            raise InputError(f"neural data '{path}' row {line}: empty stimulus name")
    opt = {c: [r.get(c, "") for r in rows] if c in header else None for c in OPTIONAL}
    unit = [u or "unit" for u in opt["unit"]] if opt["unit"] else None
    return make_neural([r["stimulus"] for r in rows], pos, rate, unit, opt["orientation"], source=f"'{path}'")


def write_neural_csv(path, data: NeuralData, comment: str = "") -> None:
    """Write NeuralData in the documented format (comment lines first)."""
    lines = [f"# {c}" for c in comment.splitlines()] if comment else []
    lines.append(",".join(REQUIRED + OPTIONAL))
    for s, p, r, u, o in zip(data.stimulus, data.position_mm, data.rate_ips, data.unit, data.orientation):
        lines.append(f"{s},{p:.6g},{r:.6g},{u},{o}")
    Path(path).write_text("\n".join(lines) + "\n")
