"""GSFC Mark VI torque-meter test stand for the SSS ASCS (seed 001, "Subsystem testing", Figs. 11–14).

The spacecraft sits on the stand with its spin axis vertical and is held fixed (no dynamics); a
controlled horizontal field rotates at 4 rpm (the sense a +z spin would see), its magnitude stepped to
simulate a perigee pass (0.070 → 0.075 G ... 0.274 G peak ... back down).  The subsystem, enabled, drives
its coil through :class:`SssAscs` with the coil's RL transient; the stand reads the vertical torque.

Spin mode: stand frame = body frame; reading = τ_z = M_x B_y.

Attitude mode (``--attitude``): the spacecraft is tilted 10° about the magnetometer axis (body y), so the
magnetometer stays horizontal and sees the full rotating field, while the attitude dipole (body z) gets a
horizontal component M sin 10°.  The stand reads only (M × B)_vertical = M sin 10° · B_⊥-component, a
sinusoid at the field rotation whose peaks (twice per rotation) are M·B·sin 10°.  The seed converts stand
readings to developed torque with a factor 5.61; geometry alone gives 1/sin 10° = 5.76 (the seed's
factor is 2.6 % lower; we apply 5.61 as the seed does and report the geometric value beside it).

Rows (``step_rows``), one per field step: field_g; enabled (1 if the automatic turn-on is active at the end
of the step); on_fraction (fraction of the step with torquing active, i.e. the hold on); torque columns
in dyne-cm: spin mode avg/peak/ripple of the stand reading; attitude mode avg and ripple of the developed
torque |M × B| (the emulator's truth) and peak = 5.61 × the peak stand reading (the seed's reduction).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from acds_common.units import GAUSS_T, nm_to_dyne_cm, rpm_to_rad_s

from ascs_mode_manager.spin_mechanizations import (
    NOMINAL_SPIN_RPM,
    AscsError,
    CoilRL,
    ripple_pct,
    rotating_field_body_t,
)
from ascs_mode_manager.sss_ascs import Event, SssAscs, SssAscsConfig, SssCommand

#: Field steps of a simulated perigee pass, G (seed: turn-on stepping 0.070 → 0.075 G, Fig. 13's 0.081 G,
#: 0.274 G peak).  0.076 G is added: at exactly the 0.075 G level an ideal comparator gives zero-width
#: pulses; the flight hardware fired there through its tolerances.
DEFAULT_FIELD_STEPS_G: tuple[float, ...] = (0.070, 0.075, 0.076, 0.081, 0.120, 0.180, 0.240, 0.274,
                                            0.240, 0.180, 0.120, 0.081, 0.076, 0.075, 0.070)
#: Tilt of the spacecraft for attitude-mode tests, deg (seed: 10° from the vertical).
STAND_TILT_DEG = 10.0
#: The seed's multiplying factor from torque-meter reading to developed attitude torque.
SEED_TILT_FACTOR = 5.61


@dataclass(frozen=True)
class StandRun:
    """A torque-meter run: per-sample arrays (n,) and the events.

    step_index: which field step; field_g: commanded magnitude, G; signal_g: the ASCS magnetometer
    (body y) reading, G; stand_torque_nm: vertical torque the stand reads, N·m; developed_torque_nm:
    |M × B|, N·m; coil_on: coil command non-zero; active: torquing active (hold on).
    """

    attitude: bool
    field_steps_g: tuple[float, ...]
    dt_s: float
    t_s: np.ndarray
    step_index: np.ndarray
    field_g: np.ndarray
    signal_g: np.ndarray
    stand_torque_nm: np.ndarray
    developed_torque_nm: np.ndarray
    coil_on: np.ndarray
    active: np.ndarray
    events: list[Event]


def _tilt_body_to_stand(attitude: bool) -> np.ndarray:
    """Rotation body → stand: identity in spin mode; 10° about body y in attitude mode."""
    if not attitude:
        return np.eye(3)
    c, s = math.cos(math.radians(STAND_TILT_DEG)), math.sin(math.radians(STAND_TILT_DEG))
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


#: The most samples one stand run records (the default run: 45,750); more does not fit in memory for long.
MAX_SAMPLES = 5_000_000


def run_torque_meter(field_steps_g: tuple[float, ...] = DEFAULT_FIELD_STEPS_G, *, attitude: bool = False,
                     dwell_s: float = 60.0, dt_s: float = 0.02, spin_rpm: float = NOMINAL_SPIN_RPM,
                     direction: str = "spin_up", settle_s: float | None = None,
                     config: SssAscsConfig | None = None) -> StandRun:
    """Run the stand test (seed 001 Figs. 11–14): each field step lasts ``dwell_s`` (s), sampled every
    ``dt_s`` (s); before the first step the field rotates for ``settle_s`` (s, default one revolution) at
    the first magnitude, unrecorded, so a single step is in steady rotation.  ``direction`` 'spin_up' or
    'despin' (spin mode)."""
    steps = tuple(float(f) for f in field_steps_g)
    if not steps or not all(math.isfinite(f) and 0.0 <= f <= 2.0 for f in steps):
        raise AscsError(f"field steps must be 1+ magnitudes in 0..2 G, got {field_steps_g!r}")
    for name, value in (("dwell_s", dwell_s), ("dt_s", dt_s), ("spin_rpm", spin_rpm)):
        if not math.isfinite(value) or value <= 0.0:
            raise AscsError(f"{name} must be a finite positive number, got {value!r}")
    if direction not in ("spin_up", "despin"):
        raise AscsError(f"direction must be 'spin_up' or 'despin', got {direction!r}")
    omega = rpm_to_rad_s(spin_rpm)
    settle = 2.0 * math.pi / omega if settle_s is None else float(settle_s)
    if not math.isfinite(settle) or settle < 0.0:
        raise AscsError(f"settle_s must be >= 0 s, got {settle_s!r}")
    per_step = int(round(dwell_s / dt_s))
    n_settle = int(round(settle / dt_s))
    if per_step < 1:
        raise AscsError(f"dwell_s={dwell_s} must hold at least one step of dt_s={dt_s}")
    samples = n_settle + len(steps) * per_step
    if samples > MAX_SAMPLES:
        raise AscsError(f"dwell_s={dwell_s:g} and dt_s={dt_s:g} give {samples:,} samples, more than the "
                        f"{MAX_SAMPLES:,} the stand records (lengthen dt_s or shorten dwell_s)")
    mag_g = np.concatenate([np.full(n_settle, steps[0]), np.repeat(steps, per_step)])
    step_index = np.concatenate([np.full(n_settle, -1), np.repeat(np.arange(len(steps)), per_step)])
    t = (np.arange(mag_g.size) - n_settle) * dt_s
    b_stand = np.zeros((mag_g.size, 3))
    b_stand[:, :2] = rotating_field_body_t(1.0, omega, t) * (mag_g * GAUSS_T)[:, None]
    r_sb = _tilt_body_to_stand(attitude)
    b_body = b_stand @ r_sb  # rows: r_sbᵀ b
    ascs = SssAscs(config)
    cfg = ascs.config
    for cmd in (SssCommand("enable"), SssCommand("mode", "attitude" if attitude else "spin"), SssCommand(direction)):
        result = ascs.apply(cmd, float(t[0]))
        if not result.accepted:
            raise AscsError(f"stand set-up command refused: {result.reason}")
    spin_rl, att_rl = CoilRL(cfg.spin_coil), CoilRL(cfg.attitude_coil)
    spin_full_a = cfg.spin_coil.current_a(cfg.bus_v)
    att_full_a = cfg.attitude_coil.current_a(cfg.bus_v)
    dipole_body = np.zeros((mag_g.size, 3))
    coil_on = np.zeros(mag_g.size, dtype=bool)
    active = np.zeros(mag_g.size, dtype=bool)
    events: list[Event] = []
    for k in range(mag_g.size):
        out = ascs.step(float(t[k]), dt_s, b_body[k])
        events.extend(out.events)
        i_spin = spin_rl.advance(out.spin_coil * spin_full_a, dt_s)
        i_att = att_rl.advance(out.attitude_coil * att_full_a, dt_s)
        dipole_body[k] = (i_spin * cfg.spin_coil.turns * cfg.spin_coil.area_m2, 0.0,
                          i_att * cfg.attitude_coil.turns * cfg.attitude_coil.area_m2)
        coil_on[k] = out.spin_coil != 0 or out.attitude_coil != 0
        active[k] = out.torquing_active
    torque_body = np.cross(dipole_body, b_body)
    stand_torque = (torque_body @ r_sb.T)[:, 2]
    keep = step_index >= 0
    return StandRun(attitude, steps, dt_s, t[keep], step_index[keep], mag_g[keep],
                    b_body[keep, 1] / GAUSS_T, stand_torque[keep], np.linalg.norm(torque_body, axis=1)[keep],
                    coil_on[keep], active[keep], events)


def step_rows(run: StandRun) -> list[dict]:
    """One row per field step with the CSV columns (see module docstring) plus 'coil_duty' (fraction of
    the step with the coil energised)."""
    rows = []
    for i, field_g in enumerate(run.field_steps_g):
        sel = run.step_index == i
        stand = run.stand_torque_nm[sel]
        if run.attitude:
            developed = run.developed_torque_nm[sel]
            avg = float(np.mean(developed))
            peak = SEED_TILT_FACTOR * float(np.max(np.abs(stand)))
            ripple = ripple_pct(developed)
        else:
            avg = float(np.mean(stand))
            peak = float(np.max(np.abs(stand)))
            ripple = ripple_pct(stand)
        rows.append({
            "field_g": field_g,
            "enabled": int(run.active[sel][-1]),
            "on_fraction": float(np.mean(run.active[sel])),
            "avg_torque_dyne_cm": float(nm_to_dyne_cm(avg)),
            "peak_torque_dyne_cm": float(nm_to_dyne_cm(peak)),
            "ripple_pct": ripple,
            "coil_duty": float(np.mean(run.coil_on[sel])),
            "peak_reading_dyne_cm": float(nm_to_dyne_cm(np.max(np.abs(stand)))),
        })
    return rows
