"""Small-vector kernels on plain Python floats, shared by the cores' per-step loops (no numpy).

3-vectors are float triples, 3×3 matrices triples of rows (quaternions and rotations:
:mod:`acds_common.attitude`). On 3-vectors numpy's call overhead (~0.5–1 µs per operation) is many times the
arithmetic, and the cores run dozens of such operations per control step; IEEE doubles give the
same bits on every machine (CPython never fuses a multiply and an add). The ones a compiled kernel calls are
marked :func:`acds_common.kernels.helper`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from acds_common import kernels

Vec3 = tuple[float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]
#: The zero 3-vector.
ZERO: Vec3 = (0.0, 0.0, 0.0)


@kernels.helper
def cross(a: Sequence[float], b: Sequence[float]) -> Vec3:
    """a × b."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a: Sequence[float], b: Sequence[float]) -> float:
    """a · b."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@kernels.helper
def norm(a: Sequence[float]) -> float:
    """|a|."""
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


@kernels.helper
def mv(m: Mat3, v: Sequence[float]) -> Vec3:
    """M v."""
    return (m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
            m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2])


@kernels.helper
def mtv(m: Mat3, v: Sequence[float]) -> Vec3:
    """Mᵀ v."""
    return (m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
            m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
            m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2])


def mat3(m: np.ndarray | Sequence[Sequence[float]]) -> Mat3:
    """A 3×3 array as a triple of float rows."""
    return tuple(tuple(float(c) for c in row) for row in np.asarray(m, dtype=float))  # type: ignore[return-value]


@kernels.helper
def clip(v: Sequence[float], limit: float) -> Vec3:
    """Each component limited to ±``limit`` (as ``min(max(x, −limit), limit)``: a NaN stays NaN)."""
    x, y, z = v
    lo = -limit
    return (lo if x < lo else limit if x > limit else x, lo if y < lo else limit if y > limit else y,
            lo if z < lo else limit if z > limit else z)
