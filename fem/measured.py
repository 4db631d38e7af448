"""Measured inputs: the CSV files of recordings and measurements that analyses are compared
with or fitted to. One reader (and writer where the toolkit makes such files) per format.

Neural recordings (`read_neural_csv`, `write_neural_csv` -> fem.neural.NeuralData).
One row per recorded indentation (thesis 4.5: a spatial response profile is the discharge rate
of one afferent plotted against the stimulus position):

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
`common.errors.InputError` with a one-line message naming the file and line.

Deflection profiles (`read_deflection_csv` -> [fem.biomech.Profile]) and force-depth curves
(`read_force_csv`); header optional (columns in any order when given), `#` comments allowed:

    deflection: distance_mm, deflection_mm, depth_mm   (distances increasing within each depth)
    force:      depth_mm, force_N                      (N per mm of thickness for 2D models)
"""
from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from common.errors import InputError
from fem.biomech import Profile
from fem.neural import NeuralData, make_neural

REQUIRED = ("stimulus", "position_mm", "rate_ips")
OPTIONAL = ("unit", "orientation")
RATE_ALIASES = ("rate_ips", "rate_imp_s")


# --------------------------------------------------------------------------- neural recordings
def read_neural_csv(path) -> NeuralData:
    """Read and validate the neural-data CSV (format in the module docstring)."""
    path = Path(path)
    try:
        text = path.read_text()
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


# --------------------------------------------------------------------------- deflection and force
def _read_table(path, columns: tuple[str, ...]) -> np.ndarray:
    """(n, len(columns)) floats from a CSV with those columns (header optional, any order if
    given; '#' comment lines skipped). Empty or malformed -> InputError."""
    try:
        with open(path, newline="") as fh:
            rows = [r for r in csv.reader(fh) if r and not r[0].lstrip().startswith("#")
                    and any(c.strip() for c in r)]
    except OSError as exc:
        raise InputError(f"cannot read '{path}': {exc.strerror}") from None
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"'{path}' is not a text CSV file ({exc})") from None
    want = ", ".join(columns)
    if not rows:
        raise InputError(f"'{path}' has no data rows: expected CSV columns {want}")
    order = list(range(len(columns)))
    head = [c.strip().lower() for c in rows[0]]

    def number(c):
        try:
            float(c)
            return True
        except ValueError:
            return False

    if not any(number(c) for c in head):          # a header row (a row with any number is data)
        missing = [c for c in columns if c.lower() not in head]
        if missing:
            raise InputError(f"'{path}': header {rows[0]} lacks column(s) {missing}; expected {want}")
        order = [head.index(c.lower()) for c in columns]
        rows = rows[1:]
        if not rows:
            raise InputError(f"'{path}' has a header but no data rows: expected CSV columns {want}")
    out = np.empty((len(rows), len(columns)))
    for i, r in enumerate(rows):
        try:
            out[i] = [float(r[j]) for j in order]
        except (ValueError, IndexError):
            raise InputError(f"'{path}' data row {i + 1}: {r} is not {len(columns)} numbers ({want})") from None
    if not np.all(np.isfinite(out)):
        raise InputError(f"'{path}' contains non-finite numbers (nan or inf): remove them")
    return out


def read_deflection_csv(path) -> list[Profile]:
    """Measured deflection profiles: CSV distance_mm, deflection_mm, depth_mm -> one Profile per
    depth (in order of depth). Distances must be >= 0 and strictly increasing within a depth."""
    t = _read_table(path, ("distance_mm", "deflection_mm", "depth_mm"))
    if np.any(t[:, 0] < 0) or np.any(t[:, 2] <= 0):
        raise InputError(f"'{path}': distances must be >= 0 mm and depths > 0 mm")
    out = []
    for d in np.unique(t[:, 2]):
        rows = t[t[:, 2] == d]
        if len(rows) < 2:
            raise InputError(f"'{path}': depth {d:g} mm has a single point; give at least 2 per depth")
        bad = np.flatnonzero(np.diff(rows[:, 0]) <= 0)
        if bad.size:
            raise InputError(f"'{path}': distances are not increasing at depth {d:g} mm "
                             f"({rows[bad[0], 0]:g} then {rows[bad[0] + 1, 0]:g}); sort each depth's rows by distance")
        out.append(Profile(float(d), rows[:, 0], rows[:, 1]))
    return out


def read_force_csv(path) -> tuple[np.ndarray, np.ndarray]:
    """Measured force-depth curve: CSV depth_mm, force_N -> (depths (k,) mm, forces (k,) N)."""
    t = _read_table(path, ("depth_mm", "force_N"))
    if np.any(t[:, 0] <= 0) or np.any(t[:, 1] < 0):
        raise InputError(f"'{path}': depths must be > 0 mm and forces >= 0 N")
    if np.any(np.diff(t[:, 0]) <= 0):
        raise InputError(f"'{path}': depths are not increasing; sort the rows by depth")
    return t[:, 0], t[:, 1]
