"""Neural recordings for receptor analysis: recorded discharge rates and their validation (the
CSV format is read and written by fem.measured).

A spatial response profile is the discharge rate of one afferent plotted against the stimulus
position (thesis 4.5); one entry per recorded indentation.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from common.errors import InputError


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
