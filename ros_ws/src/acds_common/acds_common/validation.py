"""Input checks shared by the cores: each core raises its own package's exception type."""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager

import numpy as np


def finite_vector3(name: str, value: object, error: type[Exception] = ValueError) -> np.ndarray:
    """``value`` as a finite float (3,) array, or ``error`` naming ``name`` and what was wrong."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise error(f'{name} must be a 3-vector of numbers, got {value!r}') from exc
    if arr.shape != (3,):
        raise error(f'{name} must be a 3-vector, got shape {arr.shape}')
    if not np.all(np.isfinite(arr)):
        raise error(f'{name} must be finite, got {arr.tolist()}')
    return arr


def all_finite(values: Sequence[float]) -> bool:
    """Whether every value is finite: one sum when they are (a finite sum means finite terms), each value
    checked when the sum is not (it may overflow)."""
    return math.isfinite(sum(values)) or all(math.isfinite(v) for v in values)


def finite_xyz(name: str, value: object, error: type[Exception] = ValueError) -> tuple[float, float, float]:
    """``value`` as a finite float triple: the cores' fast path of :func:`finite_vector3` (no numpy),
    with its messages for anything that is not three finite numbers."""
    try:
        x, y, z = value  # type: ignore[misc]
        x, y, z = float(x), float(y), float(z)
    except (TypeError, ValueError):
        x = y = z = math.nan
    # A finite sum means three finite numbers; otherwise check each (a sum may overflow).
    if math.isfinite(x + y + z) or (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
        return x, y, z
    finite_vector3(name, value, error)  # raises, naming what is wrong
    raise error(f'{name} must be a finite 3-vector, got {value!r}')


@contextmanager
def scenario_key(key: str, error: type[Exception]) -> Iterator[None]:
    """Re-raise an ``error`` raised inside as ``error('<key>: <message>')``.

    Builders that turn scenario sections into a core wrap each part in this, so a
    model's own check names the scenario section or key it came from (the node's
    start-up error and the launcher's pre-flight line say the same).
    """
    try:
        yield
    except error as exc:
        raise error(f'{key}: {exc}') from None
