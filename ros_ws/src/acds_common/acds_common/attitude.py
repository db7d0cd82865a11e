"""Attitude: the project's one definition of its rotation conventions (spec §3; REP-103).

Hamilton quaternions (x, y, z, w), scalar last, body → reference (ECI, or a formation's frame):
v_reference = R(q) v_body, R(q1 ⊗ q2) = R(q1) R(q2), q̇ = ½ q ⊗ (ω, 0) with ω the body rates.

Two forms of the same functions: the per-step kernels on plain float tuples (``dcm``, ``quat_mul``,
``conj``, ``to_body``, as :mod:`acds_common.vec3`: numpy's per-call overhead would dominate on
4-vectors, and IEEE doubles give the same bits everywhere), and numpy forms at the API edge
(``quat_to_dcm``, ``dcm_to_quat``, ``rotation_between``, ``quat_rates`` on arrays of quaternions).
The rigid-body kernel (``dynamics.rigid_body_model``) inlines ``dcm`` and q̇ in its derivative for
speed; its expressions are these, operation for operation.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from acds_common import kernels
from acds_common.dipole_field import cross3
from acds_common.vec3 import Mat3, Vec3

Quat = tuple[float, float, float, float]


class AttitudeError(ValueError):
    """A matrix that is not a proper rotation."""


@kernels.helper
def dcm(q: Sequence[float]) -> Mat3:
    """Rotation matrix R of the unit quaternion q = (x, y, z, w): v_rotated = R v (body → reference)."""
    x, y, z, w = q
    return ((1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)),
            (2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)),
            (2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)))


def quat_to_dcm(q: Sequence[float]) -> np.ndarray:
    """``dcm`` as a 3×3 array (any sequence or array of four numbers)."""
    return np.array(dcm(tuple(float(c) for c in q)))


@kernels.helper
def quat_mul(q1: Sequence[float], q2: Sequence[float]) -> Quat:
    """Hamilton product q1 ⊗ q2 of (x, y, z, w) quaternions, so that R(q1 ⊗ q2) = R(q1) R(q2)."""
    x1, y1, z1, w1 = q1
    x2, y2, z2, w2 = q2
    return (w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2)


@kernels.helper
def conj(q: Sequence[float]) -> Quat:
    """q* (the inverse of a unit quaternion)."""
    return (-q[0], -q[1], -q[2], q[3])


@kernels.helper
def to_body(q: Sequence[float], v: Sequence[float]) -> Vec3:
    """R(q)ᵀ v: a reference-frame vector in body axes, as q* ⊗ (v, 0) ⊗ q (q a unit quaternion)."""
    r = quat_mul(quat_mul(conj(q), (v[0], v[1], v[2], 0.0)), q)
    return r[0], r[1], r[2]


def quat_rates(q: np.ndarray, w: np.ndarray) -> np.ndarray:
    """q̇ = ½ q ⊗ (ω, 0) for (N, 4) quaternions (x, y, z, w) and (N, 3) body rates (rad/s)."""
    qv, qw = q[:, :3], q[:, 3:]
    return 0.5 * np.concatenate([qw * w + cross3(qv, w), -(qv * w).sum(axis=1, keepdims=True)], axis=1)


def dcm_to_quat(m: np.ndarray) -> np.ndarray:
    """Unit quaternion (x, y, z, w), w ≥ 0, of a rotation matrix (inverse of ``quat_to_dcm``; Shepperd)."""
    m = np.asarray(m, dtype=float)
    if m.shape != (3, 3) or not np.allclose(m @ m.T, np.eye(3), atol=1e-9) or np.linalg.det(m) < 0.0:
        raise AttitudeError("the matrix must be a 3x3 proper rotation matrix")
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    cands = [tr, m[0, 0], m[1, 1], m[2, 2]]
    i = int(np.argmax(cands))
    if i == 0:
        w = 0.5 * math.sqrt(1.0 + tr)
        q = np.array([(m[2, 1] - m[1, 2]) / (4 * w), (m[0, 2] - m[2, 0]) / (4 * w),
                      (m[1, 0] - m[0, 1]) / (4 * w), w])
    else:
        a = i - 1
        b, c = (a + 1) % 3, (a + 2) % 3
        va = 0.5 * math.sqrt(1.0 + m[a, a] - m[b, b] - m[c, c])
        q = np.empty(4)
        q[a] = va
        q[b] = (m[b, a] + m[a, b]) / (4 * va)
        q[c] = (m[c, a] + m[a, c]) / (4 * va)
        q[3] = (m[c, b] - m[b, c]) / (4 * va)
    q = q / np.linalg.norm(q)
    return -q if q[3] < 0.0 else q


def rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation matrix taking the direction of ``a`` onto that of ``b`` (Rodrigues)."""
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    axis = np.cross(a, b)
    s, c = float(np.linalg.norm(axis)), float(a @ b)
    if s < 1e-12:
        if c > 0:
            return np.eye(3)
        perp = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])
        axis, s = perp / np.linalg.norm(perp), 0.0
    else:
        axis = axis / s
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)
