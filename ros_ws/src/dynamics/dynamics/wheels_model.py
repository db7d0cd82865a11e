"""Reaction wheels: square-law drive, momentum capacity, optional 4-wheel 20°-cant cluster (spec §4).

Sign convention: wheel momentum h (body axes) is the wheels' angular momentum; ``step`` returns its
rate ḣ, and the body feels the reaction −ḣ (see rigid_body_model).

Seed 002: §4.2.2/Table 4-2 (V_sat = 17.1 V, average wheel torque 0.117 ft-lb per axis), §4.3
(square law; "only three reaction wheels were modeled - one for each axis"; Table 4-6 capacities),
§4.3.2.2 (yaw wheel saturates at 39 ft-lb-sec), §6.1/§6.2 (four wheels, momentum axes 90° apart,
symmetric about the Y-Z plane, canted 20° from it).

A step is one kernel call (:func:`wheels_step`, on floats in :data:`SLOTS` wheel slots: :mod:`acds_common.kernels`,
compiled in the direct engine); numpy appears only at the API edge.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from acds_common import kernels, units

from dynamics.errors import DynamicsError, finite_float, finite_vector3, finite_xyz, positive_dt

#: Drive saturation voltage, V (seed 002 §4.2.2).
V_SAT_V = 17.1
#: Square-law gain k in T = k·V·|V|, N·m/V². Reading of seed 002 (Table 4-2 "average wheel torque
#: 0.117 ft-lb (each axis)", used as the available deceleration torque T_ave in eq. 4-21, with the
#: voltage reaching V_sat at the edge of the deadbeat error limit, eq. 4-25): the wheel gives
#: 0.117 ft-lb at V_sat (averaged over the torque-speed curve of Figure 4-13), k = 0.117 ft-lb/17.1².
DEFAULT_TORQUE_GAIN_NM_PER_V2 = units.ftlb_to_nm(0.117) / V_SAT_V ** 2
#: Cant of the 4-wheel cluster's momentum axes from the body Y-Z plane, rad (seed 002 §6.2).
CANT_RAD = math.radians(20.0)
#: One HEAO-B wheel's momentum capacity H_w, N·m·s: chosen so that the study's yaw wheel
#: (z capacity 1.328 H_w, Table 4-6, 4 wheels active) saturates at 39 ft-lb-sec (§4.3.2.2),
#: H_w = 39 / (√2 cos 20°) = 29.35 ft-lb-sec.
DEFAULT_WHEEL_CAPACITY_NMS = units.ftlbs_to_nms(39.0 / (math.sqrt(2.0) * math.cos(CANT_RAD)))
LAYOUTS = ("three_orthogonal", "four_cant20")


def four_cant20_axes_body() -> np.ndarray:
    """Unit momentum axes (columns, body axes) of the 4-wheel cluster (seed 002 §6.1, §6.2).

    a_i = (sin 20°, cos 20° cos φ_i, cos 20° sin φ_i), φ_i = 45°, 135°, 225°, 315°: all canted +20°
    from the Y-Z plane, projections on it 90° apart and symmetric about Y and Z. Reversing a wheel's
    axis changes nothing (its momentum is signed), so this is also the "±20°, symmetric about the
    Y-Z plane" arrangement of §6.1. It reproduces Table 4-6 (see ``box_capacity_nms``).
    """
    s, c = math.sin(CANT_RAD), math.cos(CANT_RAD)
    phis = [math.radians(45.0 + 90.0 * i) for i in range(4)]
    return np.array([[s] * 4, [c * math.cos(p) for p in phis], [c * math.sin(p) for p in phis]])


def _min_max_norm(a_scaled: np.ndarray, v: np.ndarray) -> float:
    """min ‖m‖_∞ subject to a_scaled @ m = v (a_scaled 3×N of rank 3, N = 3 or 4)."""
    n = a_scaled.shape[1]
    m0 = np.linalg.pinv(a_scaled) @ v
    if n == 3:
        return float(np.max(np.abs(m0)))
    if n != 4:
        raise DynamicsError(f"capacity needs 3 or 4 active wheels, got {n}")
    z = np.linalg.svd(a_scaled)[2][-1]  # null-space direction
    # max_i |m0_i + t z_i| is convex piecewise linear in t: its minimum is at a crossing of two lines.
    cands = [0.0]
    for i, j in itertools.combinations(range(n), 2):
        for sign in (1.0, -1.0):
            den = z[i] - sign * z[j]
            if abs(den) > 1e-12:
                cands.append(-(m0[i] - sign * m0[j]) / den)
    return min(float(np.max(np.abs(m0 + t * z))) for t in cands)


#: Wheel slots of the per-step kernel (:func:`wheels_step`): the 4-wheel cluster's wheels; three orthogonal wheels
#: leave the last slot empty (no axis, zero capacity, no torque: it stays at zero momentum).
SLOTS = 4
#: Per wheel slot, as :func:`wheels_step` takes and gives it.
Slots = tuple[float, float, float, float]


@kernels.helper
def _row_times(row: Slots, v: Slots) -> float:
    """A row of a 3×N matrix times an N-vector (slots), on floats, summed in slot order."""
    acc = 0.0
    for j in range(SLOTS):
        acc += row[j] * v[j]
    return acc


@kernels.helper
def _dot3(row: tuple[float, float, float], r0: float, r1: float, r2: float) -> float:
    """A distribution row times the body-axis request (r0, r1, r2)."""
    d0, d1, d2 = row
    return d0 * r0 + d1 * r1 + d2 * r2


@kernels.helper
def _limit(x: float, c: float) -> float:
    """x limited to ±c."""
    return -c if x < -c else c if x > c else x


#: What :func:`wheels_step` takes once per wheel set: the square-law gain k, V_sat, one wheel per body axis
#: (``orthogonal``), the distribution rows (slot × body axis), the axis rows (body axis × slot), the capacities.
WheelParams = tuple[float, float, bool, tuple[tuple[float, float, float], ...], tuple[Slots, Slots, Slots], Slots]


@kernels.helper
def wheels_step(p: WheelParams, h: Slots, volts: Sequence[float], dt: float) -> tuple[Slots, Slots, tuple[
        float, float, float], tuple[float, float, float]]:
    """One step of :meth:`ReactionWheels.step_xyz_unchecked` on the wheels' momenta ``h`` (per slot, N·m·s):
    (momenta at the step end, wheel torques before capacity limiting, h at the step start and the mean ḣ in body
    axes). A kernel (:mod:`acds_common.kernels`), compiled in the direct engine."""
    k, vsat, orthogonal, dist, axes, caps = p
    vx, vy, vz = volts  # body-axis torque requests k·V|V|, V limited to ±V_sat
    vx = -vsat if vx < -vsat else vsat if vx > vsat else vx
    vy = -vsat if vy < -vsat else vsat if vy > vsat else vy
    vz = -vsat if vz < -vsat else vsat if vz > vsat else vz
    r0, r1, r2 = k * vx * abs(vx), k * vy * abs(vy), k * vz * abs(vz)
    if orthogonal:
        torque = (r0, r1, r2, 0.0)
    else:
        torque = (_dot3(dist[0], r0, r1, r2), _dot3(dist[1], r0, r1, r2), _dot3(dist[2], r0, r1, r2),
                  _dot3(dist[3], r0, r1, r2))
    peak = max(abs(torque[0]), abs(torque[1]), abs(torque[2]), abs(torque[3]))
    t_max = k * vsat * vsat
    if peak > t_max:
        torque = (torque[0] * (t_max / peak), torque[1] * (t_max / peak), torque[2] * (t_max / peak),
                  torque[3] * (t_max / peak))
    # each wheel's h + τ·dt limited to ±its capacity
    h_end = (_limit(h[0] + torque[0] * dt, caps[0]), _limit(h[1] + torque[1] * dt, caps[1]),
             _limit(h[2] + torque[2] * dt, caps[2]), _limit(h[3] + torque[3] * dt, caps[3]))
    if orthogonal:
        start, end = (h[0], h[1], h[2]), (h_end[0], h_end[1], h_end[2])
    else:
        start = (_row_times(axes[0], h), _row_times(axes[1], h), _row_times(axes[2], h))
        end = (_row_times(axes[0], h_end), _row_times(axes[1], h_end), _row_times(axes[2], h_end))
    return h_end, torque, start, ((end[0] - start[0]) / dt, (end[1] - start[1]) / dt, (end[2] - start[2]) / dt)


def box_capacity_nms(axes_body: np.ndarray, capacities_nms: np.ndarray) -> np.ndarray:
    """Body-axis momentum capacities (N·m·s) of a wheel set (Table 4-6 reading, seed 002 §4.3).

    Table 4-6 gives the half-widths of the largest box, centred on zero and shaped like the wheels'
    mean per-axis lever p = mean_i |a_i|·H_i, whose every corner the wheels can store at once
    (4 active: 2·p = (0.684, 1.328, 1.328) H_w; 3 active: 1·p = (0.342, 0.664, 0.664) H_w). Pure
    single-axis storage can reach more (e.g. 4 sin 20° H_w along x); the box is what every axis has
    simultaneously. For three orthogonal wheels it is just each wheel's capacity.
    """
    a = np.asarray(axes_body, dtype=float)
    caps = np.asarray(capacities_nms, dtype=float)
    return np.array(_box_capacity(tuple(map(tuple, a.tolist())), tuple(caps.tolist())))


@functools.lru_cache(maxsize=64)
def _box_capacity(axes: tuple[tuple[float, ...], ...], capacities: tuple[float, ...]) -> tuple[float, ...]:
    """:func:`box_capacity_nms` of the axes (rows) and capacities as tuples, remembered: a process builds the same
    wheel set for every sample of a study (a 4-wheel capacity is 8 SVD solutions, ~1 ms)."""
    a, caps = np.array(axes), np.array(capacities)
    p = np.mean(np.abs(a) * caps, axis=1)
    a_scaled = a * caps
    worst = max(_min_max_norm(a_scaled, np.array(signs) * p)
                for signs in itertools.product((1.0, -1.0), repeat=3))
    return tuple((p / worst).tolist())


@dataclass(frozen=True)
class WheelsConfig:
    """Reaction-wheel parameters (spec §4).

    ``layout``: 'three_orthogonal' (the study's simulation, one wheel per body axis) or 'four_cant20'.
    ``torque_gain_nm_per_v2``: k in T = k·V·|V| (N·m/V²); ``v_sat_v``: drive limit (V);
    ``wheel_capacity_nms``: H_w, one HEAO-B wheel (N·m·s). For 'three_orthogonal' each axis wheel
    gets the Table 4-6 box capacity of the HEAO-B cluster with ``orthogonal_equivalent_active_wheels``
    (4 or 3) wheels active, as the study did ("the inertia assumed for each wheel was based on either
    the three or four wheel model of HEAO-B"), so the yaw wheel holds 1.328 H_w = 39 ft-lb-sec.
    ``failed_wheel``: index 0–3 of a failed wheel ('four_cant20' only).
    """

    layout: str = "three_orthogonal"
    torque_gain_nm_per_v2: float = DEFAULT_TORQUE_GAIN_NM_PER_V2
    v_sat_v: float = V_SAT_V
    wheel_capacity_nms: float = DEFAULT_WHEEL_CAPACITY_NMS
    orthogonal_equivalent_active_wheels: int = 4
    failed_wheel: int | None = None

    def __post_init__(self) -> None:
        if self.layout not in LAYOUTS:
            raise DynamicsError(f"WheelsConfig.layout must be one of {LAYOUTS}, got {self.layout!r}")
        for name in ("torque_gain_nm_per_v2", "v_sat_v", "wheel_capacity_nms"):
            if finite_float(f"WheelsConfig.{name}", getattr(self, name)) <= 0.0:
                raise DynamicsError(f"WheelsConfig.{name} must be > 0, got {getattr(self, name)}")
        if self.orthogonal_equivalent_active_wheels not in (3, 4):
            raise DynamicsError("WheelsConfig.orthogonal_equivalent_active_wheels must be 3 or 4, got "
                                f"{self.orthogonal_equivalent_active_wheels!r}")
        if self.failed_wheel is not None:
            if self.layout != "four_cant20":
                raise DynamicsError("WheelsConfig.failed_wheel needs layout 'four_cant20' (the study's "
                                    "three-orthogonal model has no redundant wheel)")
            if self.failed_wheel not in (0, 1, 2, 3):
                raise DynamicsError(f"WheelsConfig.failed_wheel must be 0..3 or None, got {self.failed_wheel!r}")


class ReactionWheels:
    """Reaction-wheel assembly (spec §4): per-wheel momentum with capacity, square-law torque.

    Drive: body-axis volts are clipped to ±V_sat and give the body-axis torque request
    T = k·V·|V| per axis. For the 4-wheel cluster the request is distributed to the active wheels by
    the pseudo-inverse of their axis matrix (a failed wheel gets nothing; with three active wheels this
    is the exact inverse); if a wheel would need more than k·V_sat², all wheel torques are scaled down
    together (the torque direction is kept). A wheel at capacity gives no torque in the saturating
    direction; reaching capacity mid-step is handled exactly (the wheel stops at capacity, the step
    average ḣ is reduced). Wheel momentum may always be driven back from capacity.
    """

    def __init__(self, cfg: WheelsConfig, h0_body_nms: np.ndarray | None = None) -> None:
        self.cfg = cfg
        if cfg.layout == "three_orthogonal":
            self._axes = np.eye(3)
            eq_active = np.ones(4, dtype=bool)
            if cfg.orthogonal_equivalent_active_wheels == 3:
                eq_active[3] = False
            cluster = four_cant20_axes_body()[:, eq_active]
            self._caps = box_capacity_nms(cluster, np.full(cluster.shape[1], cfg.wheel_capacity_nms))
            self._active = np.ones(3, dtype=bool)
        else:
            self._axes = four_cant20_axes_body()
            self._caps = np.full(4, cfg.wheel_capacity_nms)
            self._active = np.ones(4, dtype=bool)
            if cfg.failed_wheel is not None:
                self._active[cfg.failed_wheel] = False
        self._dist = np.zeros((self._axes.shape[1], 3))
        self._dist[self._active] = np.linalg.pinv(self._axes[:, self._active])
        h0 = np.zeros(3) if h0_body_nms is None else finite_vector3("h0_body_nms", h0_body_nms)
        h = self._dist @ h0
        if np.any(np.abs(h) > self._caps * (1.0 + 1e-12)):
            raise DynamicsError(f"h0_body_nms {h0.tolist()} needs wheel momenta {h.tolist()} N·m·s "
                                f"beyond the wheel capacities {self._caps.tolist()} N·m·s")
        #: One wheel per body axis (three_orthogonal): the body-axis and per-wheel quantities coincide.
        orthogonal = self._axes.shape == (3, 3) and bool(np.all(self._axes == np.eye(3))) and bool(
            np.all(self._dist == np.eye(3)))
        n = self._axes.shape[1]
        if not (orthogonal or n == SLOTS):  # the slots' empty last wheel is exact only with one wheel per axis
            raise DynamicsError(f"the wheel kernel takes three orthogonal wheels or {SLOTS}, got {n} wheels")
        self._n = n
        # The per-step state and matrices as floats in the kernel's slots (N wheels, then empty ones): momenta,
        # torques, and the parameters (:data:`WheelParams`: axis rows 3×slots, distribution rows slots×3).
        pad = SLOTS - n
        self._h: Slots = tuple(h.tolist()) + (0.0,) * pad  # type: ignore[assignment]
        self._torque: Slots = (0.0,) * SLOTS  # type: ignore[assignment]
        self._params: WheelParams = (
            float(cfg.torque_gain_nm_per_v2), float(cfg.v_sat_v), orthogonal,
            tuple(tuple(row) for row in self._dist.tolist()) + ((0.0, 0.0, 0.0),) * pad,
            tuple(tuple(row) + (0.0,) * pad for row in self._axes.tolist()),  # type: ignore[arg-type]
            tuple(self._caps.tolist()) + (0.0,) * pad)  # type: ignore[arg-type]
        #: :func:`wheels_step` bound to the one signature :meth:`step_xyz_unchecked` calls it with
        #: (:func:`kernels.bound`): the parameters float tuples and a ``bool`` built here (``float``, ``tolist``), the
        #: momenta float slots (``tolist`` here, then the kernel's own results), volts a float triple (the
        #: contract of :meth:`step_xyz_unchecked`: :meth:`step_xyz` makes them with :func:`finite_xyz`, the stepper
        #: passes its input's Vector3Stamped value or its last valid one, plain floats from
        #: :func:`acds_common.messages.vector3` or a kernel) and dt a float (:func:`positive_dt`).
        self._step = kernels.bound(wheels_step, self._params, self._h, (0.0, 0.0, 0.0), 1.0)

    def momentum_body_nms(self) -> np.ndarray:
        """Total wheel momentum in body axes, N·m·s."""
        return self._axes @ np.array(self._h[:self._n])

    def wheel_momenta_nms(self) -> np.ndarray:
        """Signed momentum of each wheel along its own axis, N·m·s."""
        return np.array(self._h[:self._n])

    def wheel_capacities_nms(self) -> np.ndarray:
        """Momentum capacity of each wheel, N·m·s."""
        return self._caps.copy()

    def wheel_axes_body(self) -> np.ndarray:
        """Wheel momentum axes as columns in body axes."""
        return self._axes.copy()

    def wheel_torques_nm(self) -> np.ndarray:
        """Torque applied to each wheel during the last step before capacity limiting, N·m."""
        return np.array(self._torque[:self._n])

    def saturated(self) -> np.ndarray:
        """Per wheel: True when the wheel is at its momentum capacity (either sign)."""
        return np.abs(np.array(self._h[:self._n])) >= self._caps

    def capacity_per_axis_nms(self) -> np.ndarray:
        """Body-axis momentum capacities, N·m·s (Table 4-6 box, see ``box_capacity_nms``)."""
        return box_capacity_nms(self._axes[:, self._active], self._caps[self._active])

    def step_xyz(self, volts_body_axes_v: object, dt_s: float) -> tuple[tuple[float, float, float],
                                                                      tuple[float, float, float]]:
        """:meth:`step` on floats: (h at step start, mean ḣ) in body axes as float triples."""
        return self.step_xyz_unchecked(finite_xyz("volts_body_axes_v", volts_body_axes_v), positive_dt(dt_s))

    def kernel_parts(self) -> tuple[WheelParams, tuple[Slots, Slots]]:
        """:func:`wheels_step`'s parameters and the state it steps (momenta, torques): for a compiled caller (the
        direct engine's fused loop, :mod:`acds_common.fused`)."""
        return self._params, (self._h, self._torque)

    def set_kernel_state(self, h: Slots, torque: Slots) -> None:
        """The state :meth:`kernel_parts` gave, stepped by a compiled caller."""
        self._h, self._torque = h, torque

    def step_xyz_unchecked(self, volts: Sequence[float], dt: float) -> tuple[tuple[float, float, float],
                                                                           tuple[float, float, float]]:
        """:meth:`step_xyz` for a caller that has checked its inputs (the stepper, every step): ``volts`` three
        finite floats, ``dt`` a float > 0. Spec §4 (:func:`wheels_step`)."""
        self._h, self._torque, start, hdot = self._step(self._params, self._h, volts, dt)
        return start, hdot

    def step(self, volts_body_axes_v: np.ndarray, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Apply body-axis drive volts for ``dt_s`` s; return (h at step start, mean ḣ) in body axes.

        h in N·m·s, ḣ = (h_end − h_start)/dt in N·m (the wheels' momentum rate; the body feels −ḣ).
        """
        h_start, hdot = self.step_xyz(volts_body_axes_v, dt_s)
        return np.array(h_start), np.array(hdot)
