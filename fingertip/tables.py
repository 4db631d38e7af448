"""The table writer (and the reader of measured number tables): CSV (RFC 4180 line endings, a header of column names with unit suffixes,
`_mm`, `_N`, `_MPa`, ...) and the same table as Markdown. Columns are formatted whole; rows
are joined directly unless a text cell needs the csv module's quoting.

    write_csv("out/c5.csv", {"depth_mm": depths, "force_N": forces, "kkt_ok": ok})
"""
from __future__ import annotations

import csv
import io
from typing import Mapping

import numpy as np

from fingertip.errors import InputError


def format_column(values, float_format: str = "%.9g", nan: str | None = None) -> np.ndarray:
    """(n,) strings of one column: floats with `float_format` (NaN as `nan` when given), anything
    else (ints, bools, strings) as str()."""
    v = np.asarray(values)
    if v.dtype.kind == "f":
        out = np.array([float_format % x for x in v.ravel().tolist()], dtype=object)   # 2x np.char.mod
        if nan is not None:
            out[np.isnan(v)] = nan
        return out
    if v.dtype.kind == "O":         # mixed column: format the float entries only
        return np.array([float_format % x if isinstance(x, float) and not (nan is not None and x != x)
                         else (nan if isinstance(x, float) else str(x)) for x in v], dtype=object)
    return v.astype(str).astype(object)


def columns_of(rows: list[Mapping]) -> dict[str, list]:
    """Rows (dicts with the same keys, in order) -> {column name: values}."""
    return {k: [r[k] for r in rows] for k in rows[0]} if rows else {}


def _cells(columns: Mapping[str, object], float_format: str, nan: str | None) -> list[np.ndarray]:
    cols = [format_column(c, float_format, nan) for c in columns.values()]
    lengths = {len(c) for c in cols}
    if len(lengths) > 1:
        raise ValueError(f"table columns differ in length: {dict(zip(columns, map(len, cols)))}")
    return cols


def csv_text(columns: Mapping[str, object], float_format: str = "%.9g", nan: str | None = None) -> str:
    """The CSV text of a table {name: (n,) values} (header, then n rows; CRLF line ends)."""
    cols = _cells(columns, float_format, nan)
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(list(columns))
    if not cols or not len(cols[0]):
        return buf.getvalue()
    words = [c for c, v in zip(cols, columns.values()) if np.asarray(v).dtype.kind in "OSU"]
    if len(cols) == 1 or any(ch in cell for c in words for cell in c for ch in ',"\r\n'):
        w.writerows(np.stack(cols, axis=1).tolist())     # csv quotes the cells that need it
    else:                                                # numbers and plain words: nothing to quote
        buf.write("".join(",".join(row) + "\r\n" for row in zip(*cols)))
    return buf.getvalue()


def write_csv(path, columns: Mapping[str, object], float_format: str = "%.9g", nan: str | None = None) -> None:
    """Write a table {name: (n,) values} as CSV at `path`."""
    with open(path, "w", newline="") as fh:
        fh.write(csv_text(columns, float_format, nan))


def write_markdown(path, columns: Mapping[str, object], title: str, float_format: str = "%.9g",
                   nan: str | None = None) -> None:
    """Write a table {name: (n,) values} as a Markdown table under a `# title` heading."""
    cols = _cells(columns, float_format, nan)
    md = [f"# {title}", "", "| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    md += ["| " + " | ".join(row) + " |" for row in zip(*cols)]
    with open(path, "w") as fh:
        fh.write("\n".join(md) + "\n")


def read_numbers(path, columns: tuple[str, ...]) -> np.ndarray:
    """(n, len(columns)) floats from a CSV with those columns (header optional, any order if
    given; '#' comment lines skipped; UTF-8, with or without the byte-order mark spreadsheet
    programs write, e.g. Excel's "CSV UTF-8"). Empty or malformed -> InputError."""
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
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
