"""Inertia tensor from the study's moments and products of inertia (spec §3, seed 002 Table 4-1).

Shared by the dynamics (the body), the controller (H = I·ω in Mode 1A) and the run
summaries, so all three use one sign convention.
"""

from __future__ import annotations

import math

import numpy as np


class InertiaError(ValueError):
    """Moments and products of inertia that no physical body has (the message says which check failed)."""


def inertia_tensor(ixx: float, iyy: float, izz: float, ixy: float, ixz: float, iyz: float) -> np.ndarray:
    """Inertia tensor from moments and products of inertia (any consistent unit; spec §3, Table 4-1).

    Sign convention (the seed's Table 4-1 lists products without stating one): products of inertia
    are the integrals I_xy = ∫ x y dm etc., so the tensor is
    [[Ixx, −Ixy, −Ixz], [−Ixy, Iyy, −Iyz], [−Ixz, −Iyz, Izz]].
    Raises InertiaError unless the tensor is finite, positive definite and its principal moments
    satisfy the triangle inequalities (a physical body).
    """
    vals = {"ixx": ixx, "iyy": iyy, "izz": izz, "ixy": ixy, "ixz": ixz, "iyz": iyz}
    for name, v in vals.items():
        if not math.isfinite(float(v)):
            raise InertiaError(f"{name} must be a finite number, got {v!r}")
    tensor = np.array([[ixx, -ixy, -ixz], [-ixy, iyy, -iyz], [-ixz, -iyz, izz]], dtype=float)
    principal = np.linalg.eigvalsh(tensor)
    if principal[0] <= 0.0:
        raise InertiaError(
            f"inertia tensor is not positive definite (principal moments {principal.tolist()}): "
            "check the products of inertia and their sign convention")
    tol = 1e-9 * principal[2]
    if principal[0] + principal[1] < principal[2] - tol:
        raise InertiaError(
            f"principal moments {principal.tolist()} violate the triangle inequality I1 + I2 >= I3: "
            "no physical body has this inertia")
    return tensor
