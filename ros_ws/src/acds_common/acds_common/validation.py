"""Input checks shared by the cores: each core raises its own package's exception type."""

from __future__ import annotations

from collections.abc import Iterator
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
