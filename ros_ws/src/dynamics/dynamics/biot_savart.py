"""Near field of circular coils: numerical Biot–Savart force and torque between coils (spec §10).

Seed 004, slide 12 "Magnetic Dipole Approximation": "the interaction force between two arbitrary
magnetic circuits is given by the Law of Biot and Savart ... difficult to solve, except for cases of
special symmetry"; slide 16 "Far Field/Near Field Comparison": "the far field model does not work in
the near field: (Separation/Distance) > 10 to be within 10 %; some configurations are more accurate".
This module is the "better model ... for near-field motion" the slide asks for: thin circular
filaments of radius R carrying N·I amp-turns, each discretised into ``segments`` current elements.

* Field of a loop (Biot–Savart): B(p) = μ0/(4π) ∮ N I dl × (p − x)/|p − x|³.
* Force and torque on a target loop: dF = N I dl × B, F = ∮ dF, τ = ∮ (x − c) × dF about a chosen
  point c (the target vehicle's centre).

Discretisation: nodes at equal angles θ_k = 2πk/M with the exact tangent element
dl_k = R Δθ (−sin θ_k û + cos θ_k v̂). On a circle the integrands are smooth and 2π-periodic in θ,
so this (the trapezoidal rule) converges geometrically in M, at a rate set by the ratio of the gap
between the loops to the loop radius; ``converged_loop_wrench`` doubles M until the result stops
changing. Filaments that touch or cross give a singular force (the thin-wire model does not
apply): raised as DynamicsError.

Exact reference for coaxial loops (``coaxial_loop_force_n``): F = I_1 I_2 dM/dz with Maxwell's
mutual inductance M = μ0 √(ab) [(2/k − k) K(k) − (2/k) E(k)], k² = 4ab/((a + b)² + z²), giving

    F_z = −μ0 I_1 I_2 z k /(4 √(ab)) · [ (2 − k²)/(1 − k²) E(k) − 2 K(k) ]

(attractive for co-directed currents), K and E complete elliptic integrals (computed here by the
arithmetic–geometric mean).

Cost: one pair evaluation is O(M_source · M_target) vectorised numpy (a few (M², 3) arrays).
SI throughout: m, A (amp-turns), T, N, N·m.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from acds_common.dipole_field import MU0_OVER_4PI, dipole_force_n, dipole_torque_nm, unit_perpendicular
from acds_common.units import MU0

from dynamics.errors import DynamicsError, finite_float, finite_vector3

#: Default current elements per loop: for the table geometries at s/d ≥ 1.5 the wrench is converged to
#: better than 1e-9 relative (see ``converged_loop_wrench`` and test_biot_savart).
DEFAULT_SEGMENTS = 64
#: A field point closer to a source node than this fraction of the source's size is "on" the
#: filament (touching or crossing loops): refused rather than returning a meaningless huge number.
_CONTACT_FRACTION = 1e-6


@dataclass(frozen=True)
class Loop:
    """A thin circular current loop (filament): ``centre_m`` (m), ``normal`` (unit vector; current
    circulates right-handed about it), ``radius_m`` (m), ``amp_turns_a`` (N·I, A, signed).

    Its far-field dipole is N I π R² n̂ (slide 12: "the product of the total current around the loop
    (Amp-turns) and the area enclosed").
    """

    centre_m: np.ndarray
    normal: np.ndarray
    radius_m: float
    amp_turns_a: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "centre_m", finite_vector3("Loop.centre_m", self.centre_m))
        n = finite_vector3("Loop.normal", self.normal)
        norm = float(np.linalg.norm(n))
        if norm < 1e-12:
            raise DynamicsError("Loop.normal must be a non-zero vector")
        object.__setattr__(self, "normal", n / norm)
        if not finite_float("Loop.radius_m", self.radius_m) > 0.0:
            raise DynamicsError(f"Loop.radius_m must be > 0 m, got {self.radius_m}")
        finite_float("Loop.amp_turns_a", self.amp_turns_a)

    @property
    def dipole_am2(self) -> np.ndarray:
        """Far-field dipole moment N I π R² n̂, A·m²."""
        return self.amp_turns_a * math.pi * self.radius_m ** 2 * self.normal


def discretise(loops: Sequence[Loop], segments: int = DEFAULT_SEGMENTS) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (M·n, 3) in m and current elements N I dl (M·n, 3) in A·m of the loops, M = ``segments``."""
    if int(segments) != segments or segments < 3:
        raise DynamicsError(f"segments must be an integer >= 3, got {segments!r}")
    theta = 2.0 * math.pi * np.arange(int(segments)) / int(segments)
    c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
    points, elements = [], []
    for loop in loops:
        u = unit_perpendicular(loop.normal)
        v = np.cross(loop.normal, u)  # û × v̂ = n̂
        points.append(loop.centre_m + loop.radius_m * (c * u + s * v))
        elements.append((loop.amp_turns_a * loop.radius_m * 2.0 * math.pi / int(segments)) * (-s * u + c * v))
    return np.concatenate(points), np.concatenate(elements)


def field_t(nodes: tuple[np.ndarray, np.ndarray], field_points_m: np.ndarray) -> np.ndarray:
    """Biot–Savart field (T) of discretised loops ``nodes`` = (points, N I dl) at ``field_points_m`` (P, 3)."""
    src, idl = nodes
    pts = np.asarray(field_points_m, dtype=float)
    dx, dy, dz = (pts[:, i, None] - src[None, :, i] for i in range(3))
    r2 = dx * dx + dy * dy + dz * dz
    extent = float(np.ptp(src, axis=0).max())
    if not np.all(r2 > (_CONTACT_FRACTION * extent) ** 2):
        raise DynamicsError("a field point lies on a current filament: the loops touch or cross "
                            "(the thin-filament Biot–Savart model is singular there)")
    inv_r3 = MU0_OVER_4PI / (r2 * np.sqrt(r2))
    wx, wy, wz = dx * inv_r3, dy * inv_r3, dz * inv_r3
    lx, ly, lz = idl[:, 0], idl[:, 1], idl[:, 2]
    # Σ_m N I dl_m × (p − x_m)/|p − x_m|³, as matrix–vector products
    return np.stack([wz @ ly - wy @ lz, wx @ lz - wz @ lx, wy @ lx - wx @ ly], axis=-1)


def wrench(source: tuple[np.ndarray, np.ndarray], target: tuple[np.ndarray, np.ndarray],
           about_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(F, τ): force (N) on the ``target`` loops from the ``source`` loops' field and torque (N·m)
    about the point ``about_m``; both arguments from ``discretise``."""
    pts, idl = target
    df = np.cross(idl, field_t(source, pts))
    return df.sum(axis=0), np.cross(pts - np.asarray(about_m, dtype=float), df).sum(axis=0)


def loop_wrench(source: Loop, target: Loop, segments: int = DEFAULT_SEGMENTS) -> tuple[np.ndarray, np.ndarray]:
    """(F, τ) on loop ``target`` from loop ``source``, torque about the target's centre (N, N·m)."""
    return wrench(discretise([source], segments), discretise([target], segments), target.centre_m)


def converged_loop_wrench(source: Loop, target: Loop, rtol: float = 1e-9, segments: int = 16,
                          max_segments: int = 8192) -> tuple[np.ndarray, np.ndarray, int]:
    """``loop_wrench`` with the segment count doubled from ``segments`` until both force and torque
    change by less than ``rtol`` (relative to |F| and to max(|τ|, |F| R_target)); returns (F, τ, M).

    Raises DynamicsError if ``max_segments`` is reached first (loops nearly touching).
    """
    f, t = loop_wrench(source, target, segments)
    m = segments
    while m < max_segments:
        m *= 2
        f2, t2 = loop_wrench(source, target, m)
        f_scale = float(np.linalg.norm(f2))
        t_scale = max(float(np.linalg.norm(t2)), f_scale * target.radius_m)
        if np.linalg.norm(f2 - f) <= rtol * f_scale and np.linalg.norm(t2 - t) <= rtol * t_scale:
            return f2, t2, m
        f, t = f2, t2
    raise DynamicsError(f"Biot–Savart wrench not converged to {rtol} with {max_segments} segments: "
                        "the loops are too close for the thin-filament model")


# ------------------------------------------------------------------------- exact coaxial reference


def _agm_elliptic_ke(k: float) -> tuple[float, float]:
    """Complete elliptic integrals K(k), E(k) (modulus k, 0 ≤ k < 1) by the arithmetic–geometric mean."""
    a, b = 1.0, math.sqrt(1.0 - k * k)
    c_sum, power = 0.5 * k * k, 0.5  # Σ 2^(n−1) c_n², c_0 = k
    for _ in range(60):
        c = 0.5 * (a - b)
        a, b = 0.5 * (a + b), math.sqrt(a * b)
        power *= 2.0
        c_sum += power * c * c
        if abs(c) < 1e-17 * a:
            break
    kk = math.pi / (2.0 * a)
    return kk, kk * (1.0 - c_sum)


def coaxial_loop_force_n(radius_a_m: float, radius_b_m: float, amp_turns_a: float, amp_turns_b: float,
                         separation_m: float) -> float:
    """Exact axial force (N) on coaxial loop B from loop A, B at ``separation_m`` along A's normal
    (negative = attraction for co-directed currents); see the module docstring."""
    a, b, z = radius_a_m, radius_b_m, separation_m
    k = math.sqrt(4.0 * a * b / ((a + b) ** 2 + z * z))
    kk, ee = _agm_elliptic_ke(k)
    return -MU0 * amp_turns_a * amp_turns_b * z * k / (4.0 * math.sqrt(a * b)) * (
        (2.0 - k * k) / (1.0 - k * k) * ee - 2.0 * kk)


# ------------------------------------------------------------------------ far/near-field comparison

#: Geometries of the far/near-field table: (A's normal, B's normal), baseline along x.
#: coaxial: both along the baseline; side_by_side: both perpendicular to it (coplanar loops);
#: perpendicular: A along the baseline, B across it (pure shear force plus torques, slide 20).
TABLE_GEOMETRIES: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "coaxial": ((1.0, 0.0, 0.0), (1.0, 0.0, 0.0)),
    "side_by_side": ((0.0, 0.0, 1.0), (0.0, 0.0, 1.0)),
    "perpendicular": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
}
#: Separation/diameter ratios of the table (slide 16's axis).
TABLE_S_OVER_D = (1.0, 1.5, 2.0, 3.0, 5.0, 10.0, 20.0)


@dataclass(frozen=True)
class FarFieldErrorRow:
    """One row of the far/near-field comparison: ``geometry``, ``s_over_d`` (centre separation over
    loop diameter), the near-field (converged Biot–Savart) and far-field (dipole) force and torque on
    B (N, N·m), the relative errors |far − near|/|near| (torque error None when the near torque is
    zero by symmetry), and the segments used. ``touching`` rows (filaments in contact) carry no numbers."""

    geometry: str
    s_over_d: float
    touching: bool
    force_near_n: np.ndarray | None = None
    force_far_n: np.ndarray | None = None
    torque_near_nm: np.ndarray | None = None
    torque_far_nm: np.ndarray | None = None
    force_error: float | None = None
    torque_error: float | None = None
    segments: int | None = None


def far_field_error_row(geometry: str, s_over_d: float, radius_m: float, amp_turns_a: float,
                        rtol: float = 1e-9) -> FarFieldErrorRow:
    """Far-field (exact dipole–dipole) against near-field (Biot–Savart) wrench on B, two equal loops."""
    if geometry not in TABLE_GEOMETRIES:
        raise DynamicsError(f"geometry must be one of {sorted(TABLE_GEOMETRIES)}, got {geometry!r}")
    n_a, n_b = (np.array(n) for n in TABLE_GEOMETRIES[geometry])
    s = finite_float("s_over_d", s_over_d) * 2.0 * radius_m
    r = np.array([s, 0.0, 0.0])
    # coplanar or crossing filaments: distance between the loops' planes' traces along the baseline
    if geometry == "side_by_side" and s <= 2.0 * radius_m:
        return FarFieldErrorRow(geometry, s_over_d, touching=True)
    loop_a = Loop(np.zeros(3), n_a, radius_m, amp_turns_a)
    loop_b = Loop(r, n_b, radius_m, amp_turns_a)
    f_near, t_near, m = converged_loop_wrench(loop_a, loop_b, rtol=rtol)
    f_far = dipole_force_n(loop_a.dipole_am2, loop_b.dipole_am2, r)
    t_far = dipole_torque_nm(loop_a.dipole_am2, loop_b.dipole_am2, r)
    t_norm = float(np.linalg.norm(t_near))
    t_err = None if t_norm < 1e-9 * float(np.linalg.norm(f_near)) * radius_m else float(
        np.linalg.norm(t_far - t_near) / t_norm)
    return FarFieldErrorRow(geometry, s_over_d, False, f_near, f_far, t_near, t_far,
                            float(np.linalg.norm(f_far - f_near) / np.linalg.norm(f_near)), t_err, m)


def far_field_error_table(radius_m: float, amp_turns_a: float, s_over_d: Sequence[float] = TABLE_S_OVER_D,
                          geometries: Sequence[str] = tuple(TABLE_GEOMETRIES)) -> list[FarFieldErrorRow]:
    """Rows of ``far_field_error_row`` for every geometry and separation (slide 16's comparison)."""
    return [far_field_error_row(g, x, radius_m, amp_turns_a) for g in geometries for x in s_over_d]


def row_error(row: FarFieldErrorRow) -> float:
    """The larger of a row's force and torque errors (inf for touching loops)."""
    if row.touching:
        return math.inf
    return max(e for e in (row.force_error, row.torque_error) if e is not None)


def far_field_valid_from(geometry: str, radius_m: float, amp_turns_a: float, tolerance: float = 0.10,
                         s_over_d_range: tuple[float, float] = (1.0, 20.0), iterations: int = 30) -> float:
    """The separation/diameter beyond which the far field is within ``tolerance`` of the near field
    (force and, where defined, torque), by bisection on ``row_error`` (monotonic in s/d for the
    TABLE_GEOMETRIES). Raises DynamicsError if the error does not cross ``tolerance`` in the range."""
    lo, hi = s_over_d_range
    err = lambda x: row_error(far_field_error_row(geometry, x, radius_m, amp_turns_a))  # noqa: E731
    if not (err(lo) >= tolerance > err(hi)):
        raise DynamicsError(f"far-field error of {geometry!r} does not cross {tolerance} between s/d = {lo} and {hi}")
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        if err(mid) >= tolerance:
            lo = mid
        else:
            hi = mid
    return hi
