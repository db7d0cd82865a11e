"""The cold-gas acquisition law: rate damping on the gyros, then sun acquisition on the sun sensor + gyros (seed 002 §3.1).

The study recommends acquiring the sun on gas and states no law; this is the usual pulse-modulated
rate-plus-position switching law of a cold-gas acquisition system, per body axis i, once per control
period Δt:

* rate reference: ``gas_rate_damping``: ω_ref = 0; ``gas_sun_acquisition``: ω_ref,i = −sat(K·θ_i, ω_slew) for
  i = x, y with θ the sun-line error of body z (:func:`~acds_controller.wheel_laws.pointing_error_xyz`: the same
  sun-sensor error the wheels use in Mode 1B) and ω_ref,z = 0 (rotation about the sun line is free, its rate
  nulled). Sun absent (zero sun-sensor vector): ω_ref = 0, rate hold. The phase plane θ–ω has the switching
  line ω = −K·θ, saturated at ±ω_slew: a constant-rate slew toward the sun, then an exponential approach
  with time constant 1/K.
* rate error e_i = ω_i − ω_ref,i; deadband: no pulse while |e_i| ≤ δ.
* outside the deadband, one pulse of the thruster whose torque opposes e_i, sized to null the error:
  thrust time t = I_ii·|e_i| / T_a (T_a that thruster's nominal torque, thrust × arm), commanded on-time
  t + t_open − t_close (the valve delays), at least the minimum on-time and at most what fits in the frame
  (Δt − t_close). The subsystem's driver then sequences the pulses two valves at a time.

**Defaults derived from the study's requirement** (seed 002 §2: "the cold gas system selected will permit sun
acquisition within ten minutes"; capture = z within 10° and every rate ≤ 0.01 deg/s, as for the magnetic
acquisition). The hand-over to the wheels waits for every |ω_i| ≤ the capture rate (``modes.gas_handover_rate``
0.01 deg/s): the gas finishes the acquisition, instead of leaving the last few hundredths of a deg/s to the slow
Mode 1B wheel loop. The law holds each rate within ±δ of its reference (a pulse nulls the error; the minimum
impulse bit's rate step, at most 0.0023 deg/s on HEAO-B's roll axis with the platform layout, is under 2δ, so a
pulse cannot overshoot through the band), and the reference K·θ falls as z closes on the sun: the hand-over needs
K·θ + δ ≤ 0.01 deg/s. δ = half the hand-over rate (0.005 deg/s) splits that band evenly between the law's ripple
and the reference still to decay; a wider δ leaves no room, a narrower one spends pulses holding rates the
capture test does not ask for.

I_ii is the diagonal of the inertia tensor: the products of HEAO-B (Ixz = 359 of Ixx = 1520 slug-ft²) make the
axes couple; the next frame's rate error corrects what a pulse sized on the diagonal missed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from acds_common.modes import GAS_MODES

from acds_controller.magnetic_laws import ControllerError
from acds_controller.wheel_laws import pointing_error_xyz

_SUN_PRESENT_MIN_NORM = 0.5


@dataclass(frozen=True)
class GasLawConfig:
    """The law's parameters (SI). ``torque_nm``: nominal torque of the thruster of each signed axis (+x, −x, …)."""

    inertia_diag_kg_m2: tuple[float, float, float]
    torque_nm: tuple[float, ...]
    rate_deadband_rad_s: float
    position_gain_per_s: float
    slew_rate_rad_s: float
    min_on_time_s: float
    valve_open_delay_s: float
    valve_close_delay_s: float

    def __post_init__(self) -> None:
        if len(self.torque_nm) != 6 or not all(math.isfinite(t) and t > 0.0 for t in self.torque_nm):
            raise ControllerError(f'gas law: six positive thruster torques needed, got {self.torque_nm!r}')
        if not all(math.isfinite(i) and i > 0.0 for i in self.inertia_diag_kg_m2):
            raise ControllerError(f'gas law: inertia diagonal must be positive, got {self.inertia_diag_kg_m2!r}')
        for name in ('rate_deadband_rad_s', 'position_gain_per_s', 'slew_rate_rad_s', 'min_on_time_s'):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) >= 0.0):
                raise ControllerError(f'gas law: {name} must be ≥ 0, got {getattr(self, name)!r}')


@dataclass(frozen=True)
class GasLawOutput:
    """One frame: signed on-time per body axis (s; sign = torque direction), rate reference and error (rad/s, rad)."""

    on_time_xyz: tuple[float, float, float]
    rate_reference_xyz: tuple[float, float, float]
    sun_error_xyz: tuple[float, float, float]


def gas_law(cfg: GasLawConfig, mode: str, omega: Sequence[float], sun: Sequence[float], dt: float) -> GasLawOutput:
    """The on-time requests of one control period in gas mode ``mode`` (module docstring)."""
    if mode not in GAS_MODES:
        raise ControllerError(f'gas law: {mode!r} is not a gas mode ({", ".join(GAS_MODES)})')
    sun_present = math.sqrt(sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2]) >= _SUN_PRESENT_MIN_NORM
    theta = (0.0, 0.0, 0.0)
    ref = [0.0, 0.0, 0.0]
    if mode == 'gas_sun_acquisition' and sun_present:
        theta = pointing_error_xyz(sun)
        for i in (0, 1):
            ref[i] = -max(-cfg.slew_rate_rad_s, min(cfg.slew_rate_rad_s, cfg.position_gain_per_s * theta[i]))
    longest = dt - cfg.valve_close_delay_s
    on = [0.0, 0.0, 0.0]
    for i in range(3):
        e = omega[i] - ref[i]
        if abs(e) <= cfg.rate_deadband_rad_s:
            continue
        axis = 2 * i + (1 if e > 0.0 else 0)  # the torque opposes the rate error
        thrust_time = cfg.inertia_diag_kg_m2[i] * abs(e) / cfg.torque_nm[axis]
        command = min(longest, max(cfg.min_on_time_s, thrust_time + cfg.valve_open_delay_s - cfg.valve_close_delay_s))
        on[i] = -command if e > 0.0 else command
    return GasLawOutput((on[0], on[1], on[2]), (ref[0], ref[1], ref[2]), theta)
