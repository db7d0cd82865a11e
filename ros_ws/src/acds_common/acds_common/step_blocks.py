"""A block of steps as rows of float64: the per-step reductions of a streaming summary, done at once, same bits.

The direct engine's compiled blocks of steps hand a run's summaries each per-step topic as rows of float64
(n × width, the topic's :class:`acds_common.cdr.RowLayout`; :meth:`acds_runtime.summary.RunObserver.feed_block`).
A summary module's ``Accumulator.step_block`` (:mod:`acds_common.plugins`) must give exactly what its ``step``
gives row by row. These are the reductions that do, and why they are exact:

* elementwise numpy arithmetic is the IEEE operation Python does on floats, in the order written (numpy never
  fuses a multiply and an add), so ``sqrt(x*x + y*y + z*z)`` of each row is :func:`acds_common.vec3.norm` of it;
* a running ``peak = v if v > peak else peak`` keeps the largest value and never a NaN (a comparison with NaN is
  false): ``np.fmax`` (which skips NaN) reduced, then compared once;
* "the first step at which" is the first true row of a mask.
"""

from __future__ import annotations

import numpy as np


def norms(rows: np.ndarray) -> np.ndarray:
    """|a| of each row of the first three columns: :func:`acds_common.vec3.norm` row by row, the same bits."""
    x, y, z = rows[:, 0], rows[:, 1], rows[:, 2]
    return np.sqrt(x * x + y * y + z * z)


def running_max(current: float, values: np.ndarray) -> float:
    """``current`` after ``current = v if v > current else current`` for each v of ``values`` in turn."""
    top = np.fmax.reduce(values, initial=-np.inf)
    return float(top) if top > current else current


def running_min(current: float, values: np.ndarray) -> float:
    """``current`` after ``current = v if v < current else current`` for each v of ``values`` in turn."""
    low = np.fmin.reduce(values, initial=np.inf)
    return float(low) if low < current else current


def running_max_3(current: tuple[float, ...], rows: np.ndarray) -> tuple[float, ...]:
    """:func:`running_max` of each of the three columns of ``rows`` (a per-axis peak)."""
    return tuple(running_max(c, rows[:, i]) for i, c in enumerate(current))


def first(mask: np.ndarray) -> int | None:
    """The index of the first true element of ``mask``, None when there is none."""
    i = int(np.argmax(mask)) if len(mask) else 0
    return i if len(mask) and mask[i] else None


def nonzero(rows: np.ndarray) -> np.ndarray:
    """Per row, whether ``any(row)`` (a NaN counts, as ``bool(nan)`` is true; −0.0 does not)."""
    return np.any(rows != 0.0, axis=1)
