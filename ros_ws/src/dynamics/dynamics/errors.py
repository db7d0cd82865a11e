"""The dynamics package's exception and input checks (rigid body, wheels, CMGs, formation)."""

from __future__ import annotations

import math

import numpy as np
from acds_common import validation


class DynamicsError(ValueError):
    """Invalid input to the dynamics package (body, wheel, CMG or formation parameters)."""


def finite_float(name: str, value: float) -> float:
    """Return ``value`` as a finite float or raise DynamicsError naming ``name``."""
    value = float(value)
    if not math.isfinite(value):
        raise DynamicsError(f"{name} must be a finite number, got {value!r}")
    return value


def positive_dt(dt_s: float) -> float:
    """Return the step ``dt_s`` (s) as a finite float > 0 or raise DynamicsError."""
    dt = finite_float("dt_s", dt_s)
    if dt <= 0.0:
        raise DynamicsError(f"dt_s must be > 0 s, got {dt}")
    return dt


def finite_vector3(name: str, value: object) -> np.ndarray:
    """Return ``value`` as a finite float 3-vector or raise DynamicsError naming ``name``."""
    return validation.finite_vector3(name, value, DynamicsError)


def finite_xyz(name: str, value: object) -> tuple[float, float, float]:
    """Return ``value`` as a finite float triple (no numpy) or raise DynamicsError naming ``name``."""
    return validation.finite_xyz(name, value, DynamicsError)
