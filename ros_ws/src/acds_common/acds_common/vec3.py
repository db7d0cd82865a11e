"""Small-vector kernels on plain Python floats, shared by the cores' per-step loops (no numpy).

3-vectors are float triples, 3×3 matrices triples of rows, quaternions (x, y, z, w) Hamilton,
scalar last. On 3-vectors numpy's call overhead (~0.5–1 µs per operation) is many times the
arithmetic, and the cores run dozens of such operations per control step; IEEE doubles give the
same bits on every machine (CPython never fuses a multiply and an add).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

Vec3 = tuple[float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]
Quat = tuple[float, float, float, float]
#: The zero 3-vector.
ZERO: Vec3 = (0.0, 0.0, 0.0)


def cross(a: Sequence[float], b: Sequence[float]) -> Vec3:
    """a × b."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a: Sequence[float], b: Sequence[float]) -> float:
    """a · b."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def norm(a: Sequence[float]) -> float:
    """|a|."""
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


def mv(m: Mat3, v: Sequence[float]) -> Vec3:
    """M v."""
    return (m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
            m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2])


def mtv(m: Mat3, v: Sequence[float]) -> Vec3:
    """Mᵀ v."""
    return (m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
            m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
            m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2])


def mat3(m: np.ndarray | Sequence[Sequence[float]]) -> Mat3:
    """A 3×3 array as a triple of float rows."""
    return tuple(tuple(float(c) for c in row) for row in np.asarray(m, dtype=float))  # type: ignore[return-value]


def dcm(q: Sequence[float]) -> Mat3:
    """Rotation matrix R of the unit quaternion q = (x, y, z, w): v_rotated = R v (body → reference)."""
    x, y, z, w = q
    return ((1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)),
            (2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)),
            (2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)))


def quat_mul(q1: Sequence[float], q2: Sequence[float]) -> Quat:
    """Hamilton product q1 ⊗ q2 of (x, y, z, w) quaternions, so that R(q1 ⊗ q2) = R(q1) R(q2)."""
    x1, y1, z1, w1 = q1
    x2, y2, z2, w2 = q2
    return (w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2)


def clip(v: Sequence[float], limit: float) -> Vec3:
    """Each component limited to ±``limit`` (as ``min(max(x, −limit), limit)``: a NaN stays NaN)."""
    x, y, z = v
    lo = -limit
    return (lo if x < lo else limit if x > limit else x, lo if y < lo else limit if y > limit else y,
            lo if z < lo else limit if z > limit else z)
