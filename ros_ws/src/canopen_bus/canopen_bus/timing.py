"""Timing of the bus edge: p50/p99/max of a wall-time series, and steps late by more than a step (spec §13)."""

from __future__ import annotations

import math

import numpy as np


class Percentiles:
    """A series of wall times (s); NaN values (no sample this step) are left out."""

    def __init__(self) -> None:
        self.values: list[float] = []

    def add(self, value: float) -> None:
        if not math.isnan(value):
            self.values.append(value)

    def summary(self) -> dict[str, float]:
        """{'p50', 'p99', 'max'} (s); empty without a sample."""
        if not self.values:
            return {}
        a = np.asarray(self.values)
        return {'p50': float(np.percentile(a, 50)), 'p99': float(np.percentile(a, 99)), 'max': float(a.max())}
