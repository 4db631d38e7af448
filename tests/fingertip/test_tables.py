"""The table writer joins rows itself when nothing needs quoting: its text must be what the csv
module writes for the same cells, for any mix of numbers, flags and words."""
import csv
import io

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from fingertip.tables import _cells, csv_text, read_numbers


def _csv_module(columns, nan=None) -> str:
    cols = _cells(columns, "%.9g", nan)
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(list(columns))
    if cols and len(cols[0]):
        w.writerows(np.stack(cols, axis=1).tolist())
    return buf.getvalue()


WORDS = st.text(alphabet='ab ,"\r\n', max_size=4)
COLUMN = st.one_of(st.lists(st.floats(allow_infinity=False), min_size=3, max_size=3).map(np.array),
                   st.lists(st.integers(-5, 5), min_size=3, max_size=3).map(np.array),
                   st.lists(st.booleans(), min_size=3, max_size=3).map(np.array),
                   st.lists(WORDS, min_size=3, max_size=3))


@settings(max_examples=200, deadline=None)
@given(st.lists(COLUMN, min_size=1, max_size=4), st.sampled_from([None, ""]))
def test_csv_text_is_the_csv_modules(columns, nan):
    table = {f"c{i}": c for i, c in enumerate(columns)}
    assert csv_text(table, nan=nan) == _csv_module(table, nan)


def test_quoting_and_empty_tables():
    assert csv_text({"name": ["a,b", "c"], "v_mm": [1.0, 2.5]}) == 'name,v_mm\r\n"a,b",1\r\nc,2.5\r\n'
    assert csv_text({"v_mm": np.zeros(0)}) == "v_mm\r\n"


def test_read_numbers_accepts_a_byte_order_mark(tmp_path):
    """Deflection and force CSVs saved by Excel as "CSV UTF-8" start with a BOM."""
    p = tmp_path / "force.csv"
    p.write_bytes("\ufeffdepth_mm,force_N\r\n0.5,0.01\r\n1,0.03\r\n".encode())
    np.testing.assert_allclose(read_numbers(p, ("depth_mm", "force_N")), [[0.5, 0.01], [1, 0.03]])
    p.write_bytes("\ufeff0.5,0.01\n".encode())                                      # no header
    np.testing.assert_allclose(read_numbers(p, ("depth_mm", "force_N")), [[0.5, 0.01]])
