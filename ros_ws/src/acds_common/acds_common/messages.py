"""Helpers on the values of the graph's standard messages (see :mod:`acds_common.cdr`; no rclpy).

Steppers receive and return message *values*: 3-tuples for ``Vector3Stamped``, (field,
covariance) for ``MagneticField``, tuples of :class:`~acds_common.cdr.Status` for
``DiagnosticArray``. These helpers build and read them.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from acds_common.cdr import Status

#: DiagnosticStatus levels (diagnostic_msgs/DiagnosticStatus).
OK, WARN, ERROR, STALE = 0, 1, 2, 3
#: Name of the mode manager's status inside the ``mode`` DiagnosticArray.
MODE_STATUS = 'ascs_mode_manager'
_ZERO_COV = (0.0,) * 9
#: Diagnostic keys starting with this report wall-clock measurements (a stage's wall time): they
#: describe the machine, not the data, and differ between two runs of the same scenario.
WALL_CLOCK_PREFIX = 'wall_'


def vec(value: Sequence[float] | None, default: Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """A Vector3Stamped value → 3-vector (``default`` for an absent input)."""
    return np.array(default if value is None else value, dtype=float)


def xyz(value: Sequence[float] | None, default: Sequence[float] = (0.0, 0.0, 0.0)) -> Sequence[float]:
    """A Vector3Stamped value as it is, a float triple (``default`` for an absent input): :func:`vec`
    without numpy, for the steppers' per-step paths."""
    return default if value is None else value


def vector3(values: Iterable[float]) -> tuple[float, float, float]:
    """A 3-vector → the Vector3Stamped value (plain floats)."""
    x, y, z = values.tolist() if isinstance(values, np.ndarray) else values
    return float(x), float(y), float(z)


def field(value: tuple[Sequence[float], Sequence[float]] | None) -> np.ndarray:
    """A MagneticField value → 3-vector, tesla (zeros for an absent input)."""
    return np.zeros(3) if value is None else np.array(value[0], dtype=float)


def magnetic_field(b_t: Iterable[float], covariance: Iterable[float] | None = None) -> tuple[tuple, tuple]:
    """3-vector (T) and row-major 3×3 covariance (T², zeros = unknown) → the MagneticField value."""
    cov = _ZERO_COV if covariance is None else tuple(float(c) for c in covariance)
    return vector3(b_t), cov


def diagnostic(node: str, values: dict[str, object], message: str = 'ok', level: int = OK) -> tuple[Status]:
    """One DiagnosticStatus named after the node (hardware_id too), with key/value telemetry."""
    return (Status(level, node, message, node, tuple((k, str(v)) for k, v in values.items())),)
