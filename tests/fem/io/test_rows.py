"""Quantised row files (fem.io.rows): rounding within the stated step, the file giving back the
rounded array bit for bit by any rows, and damaged files refused."""
import numpy as np
import pytest

from fem.io.rows import RowFile, quantise, write_rows


@pytest.fixture
def rounded(tmp_path):
    """(original (40, 300), rounded copy, exponents, blocks, file): rows spanning ten decades, a
    zero row and a zero block."""
    rng = np.random.default_rng(3)
    a = rng.standard_normal((40, 300)) * np.logspace(-8, 2, 300)
    a[5], a[6, 100:] = 0.0, 0.0
    blocks = [0, 100, 300]
    q = a.copy()
    expo = quantise(q, blocks, 1e-7)
    write_rows(tmp_path / "a.rows", q, expo, blocks)
    return a, q, expo, blocks, tmp_path / "a.rows"


def test_rounding_stays_within_the_step(rounded):
    a, q, expo, blocks, _ = rounded
    for b, (lo, hi) in enumerate(zip(blocks[:-1], blocks[1:])):
        top = np.abs(a[:, lo:hi]).max(axis=1)
        err = np.abs(q[:, lo:hi] - a[:, lo:hi]).max(axis=1)
        step = np.ldexp(1.0, expo[:, b])
        assert np.all(err <= step / 2)
        live = top > 0
        assert np.all(step[live] >= 1e-7 * top[live]) and np.all(step[live] < 2e-7 * top[live])
        assert np.all(err[live] < 1e-7 * top[live])
    assert not q[5].any() and not q[6, 100:].any()
    again = q.copy()
    assert np.array_equal(quantise(again, blocks, 1e-7), expo) and np.array_equal(again, q)


def test_rows_read_back_bit_for_bit(rounded):
    _, q, _, _, path = rounded
    rows = RowFile(path)
    assert rows.shape == q.shape and len(rows) == 40
    assert np.array_equal(rows[np.arange(40)], q)
    assert np.array_equal(rows[np.array([7, 2, 7, -1])], q[[7, 2, 7, -1]])
    assert np.array_equal(rows[3], q[3]) and rows[np.array([], int)].shape == (0, 300)
    assert rows.nbytes < q.nbytes / 2                  # 1e7 steps: at most 24 of 64 bits used
    with pytest.raises(IndexError):
        rows[np.array([40])]


@pytest.mark.parametrize("damage", ["truncate", "extend", "magic"])
def test_damaged_files_are_refused(rounded, damage):
    path = rounded[-1]
    data = path.read_bytes()
    data = {"truncate": data[:-10], "extend": data + b"\0", "magic": b"X" + data[1:]}[damage]
    path.write_bytes(data)
    with pytest.raises(ValueError):
        RowFile(path)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="rel"):
        quantise(np.ones((2, 2)), [0, 2], 1e-12)
    with pytest.raises(ValueError, match="NaN"):
        quantise(np.array([[1.0, np.nan]]), [0, 2], 1e-7)
