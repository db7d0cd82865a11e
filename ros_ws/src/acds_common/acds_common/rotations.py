"""Attitude conventions shared outside the dynamics kernel: Hamilton quaternions (x, y, z, w), body → inertial."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def quat_to_dcm(q: Sequence[float]) -> np.ndarray:
    """Rotation matrix R (v_inertial = R v_body) of a unit quaternion (x, y, z, w), scalar last."""
    x, y, z, w = (float(c) for c in q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
