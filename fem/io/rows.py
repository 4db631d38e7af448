"""Quantised row files: a (k, s) float64 array stored row by row, each row's values rounded to a
power-of-two step and compressed, so that any set of rows is read without reading the others.

The columns fall into blocks (e.g. displacements and strains); in each row and block the step is
the smallest power of two at or above `rel` times the block's largest magnitude there, so every
value carries an error of at most half a step, less than `rel` times that magnitude.
`quantise` rounds an array in memory exactly as `write_rows` stores it: a process that keeps the
rounded array and one that reads the file back hold the same bits.

    steps = quantise(a, blocks=[0, 300, 900], rel=1e-7)     # a (k, 900) rounded in place
    write_rows("RT.rows", a, steps, [0, 300, 900])
    rows = RowFile("RT.rows")                               # rows.shape == (k, 900)
    rows[np.array([3, 17])]                                 # (2, 900) float64, == a[[3, 17]]

File layout (little-endian): MAGIC, uint64 header length h, h bytes of JSON {"shape": [k, s],
"blocks": [...], "codec": CODEC}, int64 offsets (k + 1,) of the rows in the data that follows
(from its start), int16 step exponents (k, blocks), then the rows. A row: its integers
q = value / 2^e as int32, zigzag coded (0, -1, 1, -2, ... -> 0, 1, 2, 3, ...), its bytes grouped
by significance (four planes: the upper planes of small numbers are zeros), zlib level ZLIB_LEVEL.
"""
from __future__ import annotations

import json
import os
import zlib
from concurrent.futures import ThreadPoolExecutor

import numpy as np

MAGIC = b"FTROWS1\n"
CODEC = "int32 zigzag, byte planes, zlib"
ZLIB_LEVEL = 6
REL_MIN = 2.0 ** -30
"""The finest relative step: the integers then stay within int32."""


def quantise(a: np.ndarray, blocks, rel: float, chunk: int = 256) -> np.ndarray:
    """Round the (k, s) float64 array `a` in place to the steps of the module docstring; returns
    their exponents e (k, len(blocks) - 1) int16 (step 2^e; 0 for a block of zeros). blocks: column
    starts and the end, [0, ..., s]."""
    if not REL_MIN <= rel < 1:
        raise ValueError(f"rel must lie in [2^-30, 1): {rel}")
    if not (a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable):
        raise ValueError("quantise needs a writeable C-ordered float64 array")
    bounds = list(zip(blocks[:-1], blocks[1:]))
    expo = np.zeros((len(a), len(bounds)), np.int16)
    for r in range(0, len(a), chunk):
        for b, (lo, hi) in enumerate(bounds):
            v = a[r:r + chunk, lo:hi]
            top = np.abs(v).max(axis=1) if hi > lo else np.zeros(len(v))
            if not np.isfinite(top).all():
                raise ValueError("quantise: the array holds NaN or infinite values")
            mant, ex = np.frexp(rel * top)                    # rel top = mant 2^ex, mant in [0.5, 1)
            e = np.where(top > 0, ex - (mant == 0.5), 0)      # 2^e >= rel top > 2^(e - 1)
            expo[r:r + chunk, b] = e
            v[:] = np.ldexp(np.rint(np.ldexp(v, -e[:, None])), e[:, None])
    return expo


def _encode(row: np.ndarray, expo: np.ndarray, blocks) -> bytes:
    q = np.empty(len(row), np.int64)
    for b, (lo, hi) in enumerate(zip(blocks[:-1], blocks[1:])):
        q[lo:hi] = np.ldexp(row[lo:hi], -int(expo[b]))        # integers, exactly
    z = ((q << 1) ^ (q >> 63)).astype(np.uint32)
    return zlib.compress(z.view(np.uint8).reshape(-1, 4).T.tobytes(), ZLIB_LEVEL)


def write_rows(path, a: np.ndarray, expo: np.ndarray, blocks) -> int:
    """Write a `quantise`d (k, s) array with its exponents (k, len(blocks) - 1) to `path`; returns
    the file's bytes. Rows are compressed on two threads (zlib releases the GIL) and written as
    they come, their offsets last."""
    k, s = a.shape
    blocks = [int(b) for b in blocks]
    if blocks[0] != 0 or blocks[-1] != s or np.any(np.diff(blocks) < 0) or expo.shape != (k, len(blocks) - 1):
        raise ValueError("blocks must run from 0 to the column count, one exponent per row and block")
    header = json.dumps({"shape": [k, s], "blocks": blocks, "codec": CODEC}).encode()
    offsets = np.zeros(k + 1, np.int64)
    with open(path, "wb") as fh, ThreadPoolExecutor(2) as pool:
        fh.write(MAGIC + np.uint64(len(header)).tobytes() + header)
        index_at = fh.tell()
        fh.write(offsets.astype("<i8").tobytes() + expo.astype("<i2").tobytes())
        for i, data in enumerate(pool.map(lambda i: _encode(a[i], expo[i], blocks), range(k))):
            fh.write(data)                                  # in order, as they are compressed
            offsets[i + 1] = offsets[i] + len(data)
        fh.seek(index_at)
        fh.write(offsets.astype("<i8").tobytes())
    return os.path.getsize(path)


class RowFile:
    """A file of `write_rows` read by rows: `rows[idx]` (len(idx), s) float64 for an int array idx
    (an int gives (s,)); only those rows are read and decoded. ValueError when the file is not
    one, or is shorter or longer than its header says."""

    def __init__(self, path):
        self.path = path
        with open(path, "rb") as fh:
            if fh.read(len(MAGIC)) != MAGIC:
                raise ValueError(f"{path} is not a row file")
            h = int(np.frombuffer(fh.read(8), "<u8")[0])
            meta = json.loads(fh.read(h))
            if meta.get("codec") != CODEC:
                raise ValueError(f"{path}: unknown codec {meta.get('codec')!r}")
            k, s = self.shape = tuple(int(v) for v in meta["shape"])
            self.blocks = [int(b) for b in meta["blocks"]]
            nb = len(self.blocks) - 1
            self._offsets = np.frombuffer(fh.read(8 * (k + 1)), "<i8").astype(np.int64)
            self._expo = np.frombuffer(fh.read(2 * k * nb), "<i2").reshape(k, nb).astype(np.int64)
            self._start = fh.tell()
        size = os.path.getsize(path)
        if (len(self._offsets) != k + 1 or len(self._expo) != k or self._offsets[0] != 0
                or np.any(np.diff(self._offsets) <= 0) or self._start + self._offsets[-1] != size):
            raise ValueError(f"{path} is truncated or its index is damaged")
        self._data = np.memmap(path, np.uint8, "r", offset=self._start) if size > self._start else None
        self.nbytes = size

    CHUNK = 16
    """Rows decoded together (their arrays stay in the processor's cache)."""

    def _decode(self, idx) -> np.ndarray:
        s = self.shape[1]
        planes = np.empty((4, len(idx), s), np.uint8)
        for j, i in enumerate(idx):
            raw = zlib.decompress(self._data[self._offsets[i]:self._offsets[i + 1]])
            planes[:, j] = np.frombuffer(raw, np.uint8).reshape(4, s)
        z = planes[0].astype(np.uint32)
        for b in (1, 2, 3):
            z |= planes[b].astype(np.uint32) << np.uint32(8 * b)
        q = (z >> np.uint32(1)).view(np.int32) ^ -(z & np.uint32(1)).view(np.int32)
        out = q.astype(np.float64)
        for b, (lo, hi) in enumerate(zip(self.blocks[:-1], self.blocks[1:])):
            out[:, lo:hi] *= np.ldexp(1.0, self._expo[idx, b])[:, None]     # a power of two: exact
        return out

    def __len__(self) -> int:
        return self.shape[0]

    def __getitem__(self, idx) -> np.ndarray:
        one = np.ndim(idx) == 0
        idx = np.atleast_1d(np.asarray(idx, np.int64))
        k, s = self.shape
        if idx.size and (idx.min() < -k or idx.max() >= k):
            raise IndexError(f"row index out of range for {k} rows")
        idx = idx % max(k, 1)
        out = np.empty((len(idx), s))
        for c in range(0, len(idx), self.CHUNK):
            out[c:c + self.CHUNK] = self._decode(idx[c:c + self.CHUNK])
        return out[0] if one else out
