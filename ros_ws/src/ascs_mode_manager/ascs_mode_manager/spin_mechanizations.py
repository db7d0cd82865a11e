"""The four SSS spin-mode mechanizations (seed 001, "Alternative spin mode mechanizations", Table 1; spec §8).

Geometry and sign conventions (used by every module of the SSS part):

* Body axes: z is the spin axis; the spacecraft spins in the +z sense, so "spin-up" means a torque
  along +z and "despin" a torque along −z.  x and y span the spin plane (the plane of "motor" action).
* A field fixed in inertial space is seen in body axes rotating at −ω about z (ω the spin rate), so
  ``B_body(t) = B·(cos(φ0 − ωt), sin(φ0 − ωt))``.  That is the field the seed's GSFC torque-meter
  applies to a fixed spacecraft ("the rotating field gives correct relative field rotation").
* The spin torque is ``τ_z = (M × B)_z = M_x B_y − M_y B_x``.
* Channel wiring (the brushless-DC-motor commutation, Earth's field as the stator field):
  coil x is driven from the y magnetometer, ``I_x = +s·g(B_y)``; in two-channel systems coil y is driven
  from the x magnetometer with the sign inverted, ``I_y = −s·g(B_x)``; ``s = +1`` spin-up, ``−1`` despin.
  Then ``τ_z = s·[M_p g(B_y) B_y + M_p g(B_x) B_x]``: every term is a product ``g(b)·b`` of a drive
  function and its own input.  Because ``g`` is odd and sign-preserving (``g(b)·b ≥ 0``) the torque
  keeps the sign ``s`` through a full rotation, whatever the field direction.
* Drive functions ``g``: sine drive (proportional amplifier) ``g(b) = clip(b / B_design, −1, 1)``,
  the gain set so that the design field of the seed (0.3 G) gives the full 28 V across the coil;
  constant level (saturated switch) ``g(b) = sign(b)``.  A polarity-sensing level ``L`` (a comparator
  dead zone, 0.075 G on SSS) gates both: ``g(b) = 0`` while ``|b| < L``.

Closed forms in a constant field of magnitude ``B`` rotating in the spin plane (``θ`` the field angle,
``M_p`` each coil's peak moment, ideal coils, sine drives unsaturated ``B ≤ B_design``)::

    two-channel sine:     τ = M_p(B/B_d)(sin²θ + cos²θ)·B = M_p B²/B_d        (constant; = M_p B at B = B_d)
    one-channel sine:     τ = M_p (B/B_d) B sin²θ,        τ_avg = M_p B²/(2 B_d)
    one-channel constant: τ = M_p B |sin θ|,              τ_avg = (2/π) M_p B
    two-channel constant: τ = M_p B (|sin θ| + |cos θ|),  τ_avg = (4/π) M_p B
                          (= √2 M_p B sin ψ on ψ ∈ [π/4, 3π/4]: the resultant, of magnitude √2 M_p,
                          is fixed in body axes for a quarter turn)

rms ripple about the average, relative to the average (shape only, independent of B)::

    two-channel sine:     0
    one-channel sine:     τ = τ_avg (1 − cos 2θ)           → 1/√2
    one-channel constant: E[τ²] = M²B²/2                   → √(π²/8 − 1)
    two-channel constant: E[τ²] = M²B²(1 + 2/π)            → √(π²/16 + π/8 − 1)

Drive power from a perfect 28 V bus (the seed's assumption): ``P = V·|I|`` per coil, so the sine drive
averages ``(2/π) V I_p`` per coil and the constant level ``V I_p``.

Sweep angle of the resultant moment (Table 1): the angle through which the resultant moment turns
relative to the field (i.e. in the frame where the field stands still, the inertial frame of a spinning
spacecraft) between commutations: 0° for the two-channel sine drive (the resultant stays at 90° to the
field), 90° for the two-channel constant level (fixed in body for a quarter turn), 180° for both
one-channel systems (one coil, fixed in body for half a turn).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from acds_common.units import GAUSS_T, MU0, nm_to_dyne_cm, rpm_to_rad_s


class AscsError(ValueError):
    """Invalid input to the SSS attitude and spin control subsystem models (the package's exception)."""


#: Spacecraft main bus voltage, V (seed 001: "with 28 V used to generate the required peak coil moment").
BUS_V = 28.0
#: Field of the seed's comparison, T: "invariant with a magnitude of 0.3 G" in the plane of motor action.
DESIGN_FIELD_T = 0.3 * GAUSS_T
#: Nominal SSS spin rate, rpm (seed 001, "Subsystem testing").
NOMINAL_SPIN_RPM = 4.0
_FT_M = 0.3048


def _check_finite(name: str, value: float) -> float:
    if not math.isfinite(value):
        raise AscsError(f"{name} must be a finite number, got {value!r}")
    return float(value)


def _check_positive(name: str, value: float) -> float:
    if _check_finite(name, value) <= 0.0:
        raise AscsError(f"{name} must be > 0, got {value!r}")
    return float(value)


def awg_diameter_m(awg: int) -> float:
    """Bare diameter (m) of American Wire Gauge ``awg``: d = 0.127 mm · 92^((36 − n)/39)."""
    if not 0 <= awg <= 50:
        raise AscsError(f"wire gauge AWG {awg} is outside 0..50")
    return 0.127e-3 * 92.0 ** ((36 - awg) / 39.0)


@dataclass(frozen=True)
class Coil:
    """A multiturn air-core coil sized as in seed 001 (M = N·I·A, I = V/R: the coil resistance limits the
    current of the saturated drive).

    turns: N; area_m2: enclosed area A, m²; resistance_ohm: R, Ω; wire_awg: the aluminium wire gauge the
    seed selects; circumference_m: the turn length C, m (seed: 3.45 ft spin-plane coils, 6.18 ft attitude
    coil).
    """

    turns: int
    area_m2: float
    resistance_ohm: float
    wire_awg: int
    circumference_m: float

    def __post_init__(self) -> None:
        if self.turns <= 0:
            raise AscsError(f"coil turns must be a positive integer, got {self.turns}")
        _check_positive("coil area_m2", self.area_m2)
        _check_positive("coil resistance_ohm", self.resistance_ohm)
        _check_positive("coil circumference_m", self.circumference_m)
        awg_diameter_m(self.wire_awg)

    def current_a(self, bus_v: float = BUS_V) -> float:
        """Saturated-drive current I = V/R, A (bus voltage ``bus_v`` in V)."""
        return _check_positive("bus_v", bus_v) / self.resistance_ohm

    def peak_moment_am2(self, bus_v: float = BUS_V) -> float:
        """Peak dipole M = N·I·A, A·m² (seed: "M = NIA")."""
        return self.turns * self.current_a(bus_v) * self.area_m2

    @property
    def inductance_h(self) -> float:
        """Self-inductance estimate, H.  The seed gives no inductance; this uses the classical thick
        circular loop ``L = μ0 N² a (ln(8a/r) − 1.75)`` with ``a = √(A/π)`` (the circle of the seed's area)
        and the winding bundle radius ``r = d·√(N/π)`` (N wires of the seed's gauge, square packed).
        Good to some tens of percent: enough to show that L/R (≈ 0.5 ms) is negligible at 4 rpm."""
        a = math.sqrt(self.area_m2 / math.pi)
        r = awg_diameter_m(self.wire_awg) * math.sqrt(self.turns / math.pi)
        return MU0 * self.turns**2 * a * (math.log(8.0 * a / r) - 1.75)

    @property
    def time_constant_s(self) -> float:
        """Coil time constant L/R, s."""
        return self.inductance_h / self.resistance_ohm


_SPIN_PLANE_AREA_M2 = 0.0697
_SPIN_PLANE_C_M = 3.45 * _FT_M

#: SSS attitude coil along the spin axis (seed 001, "The attitude mode"): 435 turns of No. 29 wire,
#: C = 6.18 ft, A = 0.269 m², R = 361 Ω → 0.0776 A, 9.08 A·m² at 28 V.
ATTITUDE_COIL = Coil(turns=435, area_m2=0.269, resistance_ohm=361.0, wire_awg=29,
                     circumference_m=6.18 * _FT_M)


@dataclass(frozen=True)
class Mechanization:
    """One spin-mode mechanization of seed 001 Table 1.

    key: dictionary key; title: the seed's name; channels: 1 or 2 (one coil and one magnetometer per
    channel); drive: 'sine' (proportional amplification) or 'constant' (saturated switching);
    coil: each coil's sizing; design_field_t: field (T) at which a sine drive reaches full voltage;
    seed_peak_moment_am2, seed_power_w: the seed's Table 1 entries (reference only, never used in a
    computation); bus_v: supply, V.
    """

    key: str
    title: str
    channels: int
    drive: str
    coil: Coil
    seed_peak_moment_am2: float
    seed_power_w: float
    design_field_t: float = DESIGN_FIELD_T
    bus_v: float = BUS_V

    def __post_init__(self) -> None:
        if self.channels not in (1, 2):
            raise AscsError(f"mechanization channels must be 1 or 2, got {self.channels}")
        if self.drive not in ("sine", "constant"):
            raise AscsError(f"mechanization drive must be 'sine' or 'constant', got {self.drive!r}")
        _check_positive("design_field_t", self.design_field_t)

    @property
    def n_coils(self) -> int:
        """Number of coils (Table 1)."""
        return self.channels

    @property
    def n_magnetometers(self) -> int:
        """Number of magnetometer axes (Table 1)."""
        return self.channels

    @property
    def current_a(self) -> float:
        """Peak (full-drive) coil current, A."""
        return self.coil.current_a(self.bus_v)

    @property
    def peak_moment_am2(self) -> float:
        """Peak moment of each coil, A·m²."""
        return self.coil.peak_moment_am2(self.bus_v)


def _spin_plane_coil(turns: int, resistance_ohm: float, awg: int) -> Coil:
    return Coil(turns=turns, area_m2=_SPIN_PLANE_AREA_M2, resistance_ohm=resistance_ohm, wire_awg=awg,
                circumference_m=_SPIN_PLANE_C_M)


#: The four mechanizations with the seed's sizings (turns, wire gauge, resistance).
MECHANIZATIONS: dict[str, Mechanization] = {
    "two_channel_sine": Mechanization(
        "two_channel_sine", "Two-channel sine drive", 2, "sine", _spin_plane_coil(397, 464.0, 33), 1.69, 2.15),
    "two_channel_constant": Mechanization(
        "two_channel_constant", "Two-channel constant level", 2, "constant", _spin_plane_coil(500, 737.0, 34),
        1.33, 2.13),
    "one_channel_sine": Mechanization(
        "one_channel_sine", "One-channel sine drive", 1, "sine", _spin_plane_coil(397, 232.0, 30), 3.38, 2.15),
    "one_channel_constant": Mechanization(
        "one_channel_constant", "One-channel constant level", 1, "constant", _spin_plane_coil(500, 369.0, 31),
        2.65, 2.13),
}

#: The flight spin coil (the selected one-channel constant level): 500 turns, 0.0697 m², 369 Ω.
SPIN_COIL = MECHANIZATIONS["one_channel_constant"].coil


def polarity(b_t: float, level_t: float) -> int:
    """Polarity-sensing comparator on one magnetometer axis: +1 if b ≥ level, −1 if b ≤ −level, else 0
    (with level 0: the sign of b, 0 at exactly zero).  b_t, level_t in T (seed 001, "Selection")."""
    if level_t > 0.0:
        return int(b_t >= level_t) - int(b_t <= -level_t)
    return int(b_t > 0.0) - int(b_t < 0.0)


def _drive_fraction(mech: Mechanization, b_t: float, level_t: float) -> float:
    """Coil current as a fraction of full current, from one magnetometer channel."""
    sense = polarity(b_t, level_t)
    if sense == 0 or mech.drive == "constant":
        return float(sense)
    return float(np.clip(b_t / mech.design_field_t, -1.0, 1.0))


def _check_direction(direction: int) -> int:
    if direction not in (1, -1):
        raise AscsError(f"direction must be +1 (spin-up) or -1 (despin), got {direction!r}")
    return int(direction)


def coil_fractions(mech: Mechanization, b_spin_plane_body_t: np.ndarray, polarity_level_t: float,
                   direction: int) -> np.ndarray:
    """Coil currents (x coil, y coil) as fractions of full current, −1..1, for the sensed spin-plane
    field ``(B_x, B_y)`` (T): ``I_x = s·g(B_y)``, ``I_y = −s·g(B_x)`` (two-channel only); see the module
    docstring for the wiring and the sign argument."""
    b = np.asarray(b_spin_plane_body_t, dtype=float)
    if b.shape != (2,) or not np.all(np.isfinite(b)):
        raise AscsError(f"b_spin_plane_body_t must be 2 finite values (B_x, B_y in T), got {b_spin_plane_body_t!r}")
    level = _check_finite("polarity_level_t", polarity_level_t)
    if level < 0.0:
        raise AscsError(f"polarity_level_t must be >= 0 T, got {level}")
    s = _check_direction(direction)
    frac_x = s * _drive_fraction(mech, b[1], level)
    frac_y = -s * _drive_fraction(mech, b[0], level) if mech.channels == 2 else 0.0
    return np.array([frac_x, frac_y])


def coil_moments(mech: Mechanization, b_spin_plane_body_t: np.ndarray, polarity_level_t: float,
                 direction: int) -> np.ndarray:
    """Steady-state dipoles (M_x, M_y) in A·m² of the mechanization's coil(s) for the sensed field
    ``(B_x, B_y)`` in T, comparator level ``polarity_level_t`` in T, ``direction`` +1 spin-up / −1 despin.
    The y magnetometer feeds coil x and the x magnetometer (inverted) feeds coil y, so that
    ``τ_z = M_x B_y − M_y B_x`` keeps the sign of ``direction`` (seed 001 Figs. 2–7)."""
    return coil_fractions(mech, b_spin_plane_body_t, polarity_level_t, direction) * mech.peak_moment_am2


class CoilRL:
    """Current in a coil driven from a voltage source: first-order RL, integrated exactly over each step
    with the target (V/R) held constant (a piecewise exponential).  ``rl=False`` gives an ideal coil."""

    def __init__(self, coil: Coil, rl: bool = True, current_a: float = 0.0) -> None:
        self.tau_s = coil.time_constant_s if rl else 0.0
        self.current_a = _check_finite("current_a", current_a)

    def advance(self, target_a: float, dt_s: float) -> float:
        """Move the current toward ``target_a`` (A) for ``dt_s`` (s); return the step-average current, A."""
        _check_finite("target_a", target_a)
        _check_positive("dt_s", dt_s)
        if self.tau_s == 0.0:
            self.current_a = target_a
            return target_a
        decay = math.exp(-dt_s / self.tau_s)
        start_offset = self.current_a - target_a
        self.current_a = target_a + start_offset * decay
        return target_a + start_offset * (self.tau_s / dt_s) * (1.0 - decay)


def rotating_field_body_t(field_t: float, spin_rate_rad_s: float, t_s: np.ndarray,
                          phase_rad: float = 0.0) -> np.ndarray:
    """Spin-plane field (n, 2) in T, magnitude ``field_t``, seen from a spacecraft spinning at
    ``spin_rate_rad_s`` about +z: ``B·(cos(φ0 − ωt), sin(φ0 − ωt))``."""
    theta = phase_rad - spin_rate_rad_s * np.asarray(t_s, dtype=float)
    return field_t * np.column_stack([np.cos(theta), np.sin(theta)])


@dataclass(frozen=True)
class TorqueHistory:
    """A simulated run of one mechanization in a rotating field (arrays sampled at ``t_s``).

    b_body_t (n, 2): field (B_x, B_y), T; moment_cmd_am2 (n, 2): steady-state commanded dipoles, A·m²;
    moment_am2 (n, 2): step-average actual dipoles (after the RL lag), A·m²; torque_nm (n,): τ_z, N·m;
    power_w (n,): bus power, W.
    """

    mech: Mechanization
    field_t: float
    spin_rate_rad_s: float
    direction: int
    dt_s: float
    t_s: np.ndarray
    b_body_t: np.ndarray
    moment_cmd_am2: np.ndarray
    moment_am2: np.ndarray
    torque_nm: np.ndarray
    power_w: np.ndarray


def simulate_rotating_field(mech: Mechanization, field_g: float, spin_rpm: float = NOMINAL_SPIN_RPM,
                            duration_s: float | None = None, dt_s: float = 0.005, direction: int = 1,
                            coil_time_constant: bool = True, polarity_level_t: float = 0.0,
                            phase_rad: float = 0.25) -> TorqueHistory:
    """Fixed spacecraft in a constant field of ``field_g`` (G) rotating in the spin plane as seen from a
    spacecraft spinning at ``spin_rpm`` (seed 001 comparison, 0.3 G).

    At each sample t_k the magnetometers read B(t_k), the drive sets the coil target current, the coil
    current follows through its RL time constant L/R (``Coil.inductance_h`` estimate, since the seed gives
    no inductance) over [t_k, t_k + dt_s]; the recorded torque is the step-average dipole × B(t_k).
    The coils start at their steady current (no start-up transient).  ``duration_s`` defaults to two spin
    periods (use whole periods for unbiased averages); ``direction`` +1 spin-up, −1 despin."""
    field_t = _check_positive("field_g", field_g) * GAUSS_T
    omega = rpm_to_rad_s(_check_positive("spin_rpm", spin_rpm))
    _check_positive("dt_s", dt_s)
    s = _check_direction(direction)
    duration = 2.0 * 2.0 * math.pi / omega if duration_s is None else _check_positive("duration_s", duration_s)
    n = int(round(duration / dt_s))
    if n < 2:
        raise AscsError(f"duration_s={duration} is shorter than two steps of dt_s={dt_s}")
    t = np.arange(n) * dt_s
    b = rotating_field_body_t(field_t, omega, t, _check_finite("phase_rad", phase_rad))
    full_a = mech.current_a
    m_per_a = mech.coil.turns * mech.coil.area_m2
    fractions = np.array([coil_fractions(mech, bk, polarity_level_t, s) for bk in b])
    coils = [CoilRL(mech.coil, coil_time_constant, fractions[0, i] * full_a) for i in range(2)]
    current_avg = np.array([[coils[i].advance(f[i] * full_a, dt_s) for i in range(2)] for f in fractions])
    moment = current_avg * m_per_a
    torque = moment[:, 0] * b[:, 1] - moment[:, 1] * b[:, 0]
    power = mech.bus_v * np.abs(current_avg).sum(axis=1)
    return TorqueHistory(mech, field_t, omega, s, dt_s, t, b, fractions * mech.peak_moment_am2, moment,
                         torque, power)


def ripple_pct(torque: np.ndarray) -> float:
    """rms deviation of a uniformly sampled torque about its average, % of |average| (seed 001's torque
    ripple definition); NaN when the average is zero."""
    x = np.asarray(torque, dtype=float)
    avg = float(np.mean(x))
    if avg == 0.0:
        return math.nan
    return 100.0 * float(np.sqrt(np.mean((x - avg) ** 2))) / abs(avg)


def circular_range_deg(angles_rad: np.ndarray) -> float:
    """Smallest arc (deg) containing all the given directions (360° minus the largest empty gap)."""
    a = np.sort(np.mod(np.asarray(angles_rad, dtype=float), 2.0 * math.pi))
    if a.size == 0:
        return 0.0
    gaps = np.diff(np.concatenate([a, [a[0] + 2.0 * math.pi]]))
    return math.degrees(2.0 * math.pi - float(gaps.max()))


def summarise(history: TorqueHistory) -> dict:
    """Table 1 columns from a simulated history: coils, magnetometers, power_w (average bus power, W),
    peak_moment_am2 (largest |dipole| of any one coil, A·m²), avg_torque_dyne_cm (signed), ripple_pct,
    sweep_deg (arc swept by the commanded resultant dipole relative to the field, samples with the
    resultant on; the arc between commutations is the whole arc since the pattern repeats)."""
    m_cmd = history.moment_cmd_am2
    on = np.linalg.norm(m_cmd, axis=1) > 0.0
    b = history.b_body_t[on]
    rel = np.arctan2(b[:, 0] * m_cmd[on, 1] - b[:, 1] * m_cmd[on, 0], np.sum(b * m_cmd[on], axis=1))
    return {
        "coils": history.mech.n_coils,
        "magnetometers": history.mech.n_magnetometers,
        "power_w": float(np.mean(history.power_w)),
        "peak_moment_am2": float(np.max(np.abs(history.moment_am2))),
        "avg_torque_dyne_cm": float(nm_to_dyne_cm(np.mean(history.torque_nm))),
        "ripple_pct": ripple_pct(history.torque_nm),
        "sweep_deg": circular_range_deg(rel),
    }


def closed_form_average_torque_nm(mech: Mechanization, field_t: float) -> float:
    """Derived average |τ_z| (N·m) in a constant field ``field_t`` (T) rotating in the spin plane, ideal
    coils, no dead zone (module docstring): 2ch sine M_p B²/B_d; 1ch sine M_p B²/(2B_d); 1ch constant
    (2/π) M_p B; 2ch constant (4/π) M_p B.  Sine drives only while unsaturated (B ≤ B_d)."""
    b = _check_positive("field_t", field_t)
    m = mech.peak_moment_am2
    if mech.drive == "constant":
        return (2.0 / math.pi) * mech.channels * m * b
    if b > mech.design_field_t * (1.0 + 1e-12):
        raise AscsError(f"closed form for a sine drive needs B <= {mech.design_field_t} T (unsaturated), got {b}")
    return m * b * b / mech.design_field_t * (1.0 if mech.channels == 2 else 0.5)


def closed_form_ripple_pct(mech: Mechanization) -> float:
    """Derived rms torque ripple, % of average (module docstring): 0; 100/√2; 100√(π²/8 − 1);
    100√(π²/16 + π/8 − 1)."""
    if mech.drive == "sine":
        return 0.0 if mech.channels == 2 else 100.0 / math.sqrt(2.0)
    if mech.channels == 1:
        return 100.0 * math.sqrt(math.pi**2 / 8.0 - 1.0)
    return 100.0 * math.sqrt(math.pi**2 / 16.0 + math.pi / 8.0 - 1.0)


def closed_form_sweep_deg(mech: Mechanization) -> float:
    """Arc swept by the resultant moment relative to the field between commutations, deg: 0 (2ch sine),
    90 (2ch constant), 180 (one channel)."""
    if mech.channels == 1:
        return 180.0
    return 0.0 if mech.drive == "sine" else 90.0


def closed_form_power_w(mech: Mechanization) -> float:
    """Average bus power, W, at the design field: channels · V · I_p · (2/π for the sine drive)."""
    factor = 2.0 / math.pi if mech.drive == "sine" else 1.0
    return mech.channels * mech.bus_v * mech.current_a * factor


def table_rows(field_g: float = DESIGN_FIELD_T / GAUSS_T) -> list[dict]:
    """Seed 001 Table 1 recomputed: one dict per mechanization key, each run in a ``field_g`` (G) field rotating
    at 4 rpm in the plane of motor action (two whole revolutions, spin-up, coil RL lag included), its columns
    from the simulated history (:func:`summarise`)."""
    return [{"mechanization": key, **summarise(simulate_rotating_field(mech, field_g))}
            for key, mech in MECHANIZATIONS.items()]
