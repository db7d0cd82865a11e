"""Tests of the SSS ASCS logic: threshold, hold, exclusivity, Direct Attitude, attitude precession, passes
(spec §8; seed 001)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.units import GAUSS_T, rpm_to_rad_s
from ascs_mode_manager.ground_commands import submit
from ascs_mode_manager.sss_ascs import (
    AscsError,
    PassAccumulator,
    SssAscs,
    SssAscsConfig,
    SssOutput,
)

OMEGA = rpm_to_rad_s(4.0)
DT = 0.05


def _field(amplitude_g: float, t: float) -> np.ndarray:
    """Spin-plane field of the given amplitude rotating in body axes as for a +z spin at 4 rpm."""
    theta = 0.3 - OMEGA * t
    return amplitude_g * GAUSS_T * np.array([math.cos(theta), math.sin(theta), 0.0])


def _run(ascs: SssAscs, amplitude_g, t0: float, duration_s: float) -> tuple[list[SssOutput], np.ndarray]:
    times = t0 + DT * np.arange(int(round(duration_s / DT)))
    outs = [ascs.step(float(t), DT, _field(amplitude_g(t), t)) for t in times]
    return outs, times


def _enabled(mode: str = "spin") -> SssAscs:
    ascs = SssAscs()
    assert submit(ascs, "sss enable", 0.0).accepted
    assert submit(ascs, f"sss mode {mode}", 0.0).accepted
    return ascs


def test_defaults_from_seed() -> None:
    cfg = SssAscsConfig()
    assert cfg.polarity_level_t == pytest.approx(0.075e-4)
    assert cfg.hold_time_s > 15.0  # outlasts one whole revolution at 4 rpm (half-frequency commutation)
    assert cfg.spin_coil.peak_moment_am2(cfg.bus_v) == pytest.approx(2.65, rel=3e-3)
    ascs = SssAscs()
    assert (ascs.enabled, ascs.mode, ascs.spin_direction, ascs.direct_attitude, ascs.torquing_active) == (
        False, "spin", "spin_up", False, False)


def test_threshold_ramp_turns_on_at_level_and_off_below_it() -> None:
    ascs = _enabled()

    def ramp(t: float) -> float:  # 0.060 G → 0.090 G over 300 s, then back down to 0.060 G
        return 0.060 + 0.030 * (t / 300.0 if t < 300.0 else max(0.0, 2.0 - t / 300.0))

    outs, times = _run(ascs, ramp, 0.0, 700.0)
    events = [e for o in outs for e in o.events]
    assert [e.kind for e in events] == ["turn_on", "turn_off"]
    on, off = events
    assert 0.075 <= ramp(on.t_s) < 0.0755  # turned on at the level, not before (0.070 G passed silently)
    assert not any(o.torquing_active for o, t in zip(outs, times, strict=True) if ramp(t) <= 0.0705)
    last_above = max(t for t in times if t > 300.0 and ramp(t) >= 0.075)
    assert last_above < off.t_s <= last_above + ascs.config.hold_time_s + 0.1
    assert "hold released" in off.detail and "0.075" in on.detail


def test_constant_0070_never_turns_on_and_disabled_never_turns_on() -> None:
    outs, _ = _run(_enabled(), lambda t: 0.070, 0.0, 60.0)
    assert not any(o.torquing_active or o.spin_coil or o.events for o in outs)
    outs, _ = _run(SssAscs(), lambda t: 0.3, 0.0, 60.0)
    assert not any(o.torquing_active or o.spin_coil or o.events for o in outs)


@pytest.mark.parametrize("direction,sign", [("spin_up", 1), ("despin", -1)])
def test_spin_coil_follows_magnetometer_polarity(direction: str, sign: int) -> None:
    ascs = _enabled()
    assert submit(ascs, f"sss {direction}", 0.0).accepted
    outs, times = _run(ascs, lambda t: 0.3, 0.0, 30.0)
    for o, t in zip(outs, times, strict=True):
        b = _field(0.3, t)
        level = 0.075 * GAUSS_T
        expected = sign * (int(b[1] >= level) - int(b[1] <= -level))
        assert o.spin_coil == expected
        assert o.attitude_coil == 0
        torque_z = np.cross(o.dipole_body_am2, b)[2]
        assert sign * torque_z >= 0.0
    duty = np.mean([o.spin_coil != 0 for o in outs])
    assert duty == pytest.approx(1 - 2 / math.pi * math.asin(0.075 / 0.3), abs=0.01)  # > 80 %, seed Fig. 12


def test_exclusivity_spin_pass_refuses_attitude_mode() -> None:
    ascs = _enabled("spin")
    _run(ascs, lambda t: 0.3, 0.0, 10.0)
    assert ascs.torquing_active
    result = submit(ascs, "sss mode attitude", 10.0)
    assert not result.accepted
    assert "already had a spin-mode pass" in result.reason and "stayed below 0.075 G for 20.8 s" in result.reason
    assert ascs.mode == "spin"
    refused = submit(ascs, "sss direct_attitude on", 10.0)
    assert not refused.accepted and "spin-mode pass" in refused.reason
    assert submit(ascs, "sss mode spin", 10.0).accepted  # no change requested: fine
    outs, _ = _run(ascs, lambda t: 0.05, 10.0, 40.0)
    assert [e.kind for o in outs for e in o.events] == ["turn_off"]
    assert submit(ascs, "sss mode attitude", 50.0).accepted
    assert ascs.mode == "attitude"


def test_one_mode_per_perigee_pass_survives_disable_mode_change_enable() -> None:
    """Seed 001: "The spin mode and attitude mode will not both be activated on a single perigee pass" — per
    perigee pass, not per activation: disable → mode attitude → enable mid-pass must not start an attitude pass."""
    ascs = _enabled("spin")
    outs, _ = _run(ascs, lambda t: 0.3, 0.0, 10.0)
    assert ascs.torquing_active and outs[-1].mode == "spin"
    assert submit(ascs, "sss disable", 10.0).accepted
    outs, _ = _run(ascs, lambda t: 0.3, 10.0, 5.0)
    assert [e.kind for o in outs for e in o.events] == ["turn_off"] and not ascs.torquing_active
    assert ascs.perigee_pass  # the field still reaches the level: same perigee pass
    refused = submit(ascs, "sss mode attitude", 15.0)
    assert not refused.accepted and ascs.mode == "spin"
    assert "already had a spin-mode pass (from t=0.0 s)" in refused.reason
    assert "never both active on one perigee pass" in refused.reason and "below 0.075 G for 20.8 s" in refused.reason
    da = submit(ascs, "sss direct_attitude on", 15.0)
    assert not da.accepted and "spin-mode pass" in da.reason and not ascs.direct_attitude
    assert submit(ascs, "sss enable", 15.0).accepted  # re-enabled: still spin mode, the one this pass had
    outs, _ = _run(ascs, lambda t: 0.3, 15.0, 30.0)
    assert all(o.attitude_coil == 0 and o.mode in ("spin", "off") for o in outs)
    assert [e.kind for o in outs for e in o.events] == ["turn_on"] and "spin mode" in outs[0].events[0].detail
    # The pass ends: below the level for the hold time (disabled or not). The next perigee may be attitude.
    assert submit(ascs, "sss disable", 45.0).accepted
    _run(ascs, lambda t: 0.05, 45.0, 30.0)
    assert not ascs.perigee_pass
    assert submit(ascs, "sss mode attitude", 75.0).accepted and submit(ascs, "sss enable", 75.0).accepted
    outs, _ = _run(ascs, lambda t: 0.3, 75.0, 20.0)
    assert [e.kind for o in outs for e in o.events] == ["turn_on"] and outs[-1].mode == "attitude"
    assert all(o.spin_coil == 0 for o in outs) and outs[-1].attitude_coil == 1


def test_perigee_pass_follows_the_signal_not_the_enable() -> None:
    ascs = SssAscs()  # never enabled: no torquing, but the pass is still tracked
    outs, _ = _run(ascs, lambda t: 0.3, 0.0, 10.0)
    assert ascs.perigee_pass and not any(o.torquing_active for o in outs)
    states = []
    for t in 10.0 + DT * np.arange(int(30.0 / DT)):
        ascs.step(float(t), DT, _field(0.05, float(t)))
        states.append((float(t), ascs.perigee_pass))
    last_detection = max(t for t in DT * np.arange(int(10.0 / DT)) if abs(_field(0.3, t)[1]) >= 0.075 * GAUSS_T)
    end = next(t for t, on in states if not on)
    assert end - last_detection == pytest.approx(ascs.config.hold_time_s, abs=DT + 1e-9)


def test_spin_mode_is_inhibited_after_direct_attitude_on_the_same_perigee_pass() -> None:
    ascs = _enabled("spin")
    assert submit(ascs, "sss direct_attitude on", 0.0).accepted
    outs, _ = _run(ascs, lambda t: 0.3, 0.0, 10.0)
    assert all(o.attitude_coil == 1 and o.spin_coil == 0 for o in outs)
    assert [e.kind for o in outs for e in o.events] == ["inhibited"]
    assert "spin mode not activated: this perigee pass already had an attitude-mode pass" in outs[0].events[0].detail
    assert submit(ascs, "sss direct_attitude off", 10.0).accepted
    outs, _ = _run(ascs, lambda t: 0.3, 10.0, 30.0)  # same perigee pass: the spin coil stays off
    assert all(o.spin_coil == 0 and o.attitude_coil == 0 and not o.torquing_active for o in outs)
    assert not [e for o in outs for e in o.events]
    _run(ascs, lambda t: 0.05, 40.0, 30.0)  # the pass ends; the next perigee is a spin-mode pass
    outs, _ = _run(ascs, lambda t: 0.3, 70.0, 10.0)
    assert [e.kind for o in outs for e in o.events] == ["turn_on"] and any(o.spin_coil != 0 for o in outs)


def test_direct_attitude_energises_attitude_coil_without_enable() -> None:
    ascs = SssAscs()
    assert submit(ascs, "sss direct_attitude on", 0.0).accepted
    out = ascs.step(0.0, DT, np.zeros(3))
    assert out.attitude_coil == 1 and out.spin_coil == 0 and out.mode == "direct_attitude"
    assert out.dipole_body_am2 == pytest.approx([0.0, 0.0, 9.08], rel=1e-3)
    assert out.power_w == pytest.approx(28.0 * 0.0776, rel=1e-3)
    assert submit(ascs, "sss direct_attitude off", 1.0).accepted
    assert ascs.step(1.0, DT, np.zeros(3)).attitude_coil == 0


def test_unknown_and_malformed_commands_refused() -> None:
    ascs = SssAscs()
    for text, reason in [("sss fly", "usage: sss enable|"), ("enable", "unknown command 'enable'; known: sss"),
                         ("sss mode orbit", "usage: sss "), ("sss direct_attitude maybe", "usage: sss "),
                         ("sss enable now", "usage: sss "), ("", "empty command")]:
        result = submit(ascs, text, 0.0)
        assert not result.accepted and result.reason.startswith(reason), text
    with pytest.raises(AscsError):
        submit(ascs, "sss enable", math.nan)
    with pytest.raises(AscsError):
        ascs.step(0.0, DT, np.array([math.nan, 0.0, 0.0]))
    with pytest.raises(AscsError):
        ascs.step(0.0, 0.0, np.zeros(3))
    with pytest.raises(AscsError):
        SssAscsConfig(hold_release_fraction=1.5)


def test_attitude_coil_held_through_zero_crossings() -> None:
    ascs = _enabled("attitude")
    outs, _ = _run(ascs, lambda t: 0.3, 0.0, 60.0)
    assert all(o.attitude_coil == 1 and o.spin_coil == 0 for o in outs)
    assert [e.kind for o in outs for e in o.events] == ["turn_on"]
    # Without the hold the comparator alone would leave the coil off ~16 % of the time at 0.3 G.


def test_disable_during_pass_emits_turn_off() -> None:
    ascs = _enabled("attitude")
    _run(ascs, lambda t: 0.3, 0.0, 5.0)
    assert submit(ascs, "sss disable", 5.0).accepted
    out = ascs.step(5.0, DT, _field(0.3, 5.0))
    assert [e.kind for e in out.events] == ["turn_off"] and "disabled" in out.events[0].detail
    assert out.attitude_coil == 0


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def test_attitude_pass_precesses_spin_axis_as_t_equals_omega_p_cross_h() -> None:
    """Rigid spinning body, attitude coil from SssAscs, inertially fixed field direction; ΔH is along the
    time-averaged torque, the spin axis keeps its angle to B and turns about −B at rate M·B/H."""
    inertia = np.diag([8.0, 8.0, 10.0])  # kg·m², spin about the major axis z
    inv_inertia = np.linalg.inv(inertia)
    omega = np.array([0.0, 0.0, OMEGA])
    rot = np.eye(3)  # body → inertial
    b_hat = np.array([math.cos(math.radians(30.0)), 0.0, math.sin(math.radians(30.0))])
    ascs = _enabled("attitude")
    acc = PassAccumulator()
    h0 = rot @ inertia @ omega
    s0 = rot[:, 2].copy()
    torque_int = np.zeros(3)
    expected_angle = 0.0
    dt = 0.05
    n = int(600.0 / dt)
    for k in range(n):
        t = k * dt
        mag_g = 0.05 + 0.25 * math.sin(math.pi * t / 600.0)  # a perigee pass: 0.05 → 0.30 → 0.05 G
        b_i = mag_g * GAUSS_T * b_hat
        b_b = rot.T @ b_i
        out = ascs.step(t, dt, b_b)
        torque_b = np.cross(out.dipole_body_am2, b_b)
        acc.add(t, torque_b, float(omega[2]), rot[:, 2], out.power_w, out.mode)
        torque_int += rot @ torque_b * dt
        h_mag = float(np.linalg.norm(inertia @ omega))
        expected_angle += np.linalg.norm(out.dipole_body_am2) * np.linalg.norm(b_i) / h_mag * dt
        omega_dot = inv_inertia @ (torque_b - np.cross(omega, inertia @ omega))
        omega_mid = omega + 0.5 * dt * omega_dot
        angle = np.linalg.norm(omega_mid) * dt
        axis = _skew(omega_mid / np.linalg.norm(omega_mid))
        rot = rot @ (np.eye(3) + math.sin(angle) * axis + (1 - math.cos(angle)) * axis @ axis)
        omega = omega + dt * (inv_inertia @ (torque_b - np.cross(omega_mid, inertia @ omega_mid)))
    assert acc.close(n * dt) is None  # the pass ended by itself as the field fell below the level
    h1 = rot @ inertia @ omega
    s1 = rot[:, 2]
    dh = h1 - h0
    assert np.dot(dh, torque_int) / (np.linalg.norm(dh) * np.linalg.norm(torque_int)) > 0.999
    assert np.linalg.norm(dh) == pytest.approx(np.linalg.norm(torque_int), rel=0.01)
    ds = s1 - s0
    along = np.cross(s0, b_hat)  # T = M s × B for a dipole along +s
    assert np.dot(ds, along) / (np.linalg.norm(ds) * np.linalg.norm(along)) > 0.99
    assert math.degrees(math.acos(np.dot(s1, b_hat))) == pytest.approx(60.0, abs=0.05)
    s0_perp = s0 - np.dot(s0, b_hat) * b_hat
    s1_perp = s1 - np.dot(s1, b_hat) * b_hat
    turned = math.atan2(np.dot(np.cross(s0_perp, s1_perp), -b_hat), np.dot(s0_perp, s1_perp))
    assert expected_angle > math.radians(1.0)
    assert turned == pytest.approx(expected_angle, rel=0.02)
    assert len(acc.reports) == 1
    report = acc.reports[0]
    assert report["mode"] == "attitude"
    assert report["precession_deg"] == pytest.approx(math.degrees(math.acos(np.dot(s0, s1))), rel=0.02)
    assert abs(report["spin_rate_change_rpm"]) < 0.01  # attitude torque is transverse
    assert report["energy_j"] == pytest.approx(28.0**2 / 361.0 * report["on_time_min"] * 60.0, rel=1e-6)


def test_pass_accumulator_spin_pass_statistics() -> None:
    acc = PassAccumulator()
    axis = np.array([0.0, 0.0, 1.0])

    def torque(k: int) -> np.ndarray:  # 1e-4 / 2e-4 N·m alternating about the spin axis
        return np.array([0.0, 0.0, 1e-4 * (1.0 + (k % 2))])

    assert acc.add(0.0, np.zeros(3), 0.4, axis, 0.0, "off") is None
    for k in range(10):
        acc.add(1.0 + k, torque(k), 0.4 + 0.001 * k, axis, 2.0, "spin")
    report = acc.add(11.0, np.zeros(3), 0.41, axis, 0.0, "off")
    assert report is not None and acc.reports == [report]
    assert set(report) >= {"on_time_min", "avg_torque_dyne_cm", "peak_torque_dyne_cm", "ripple_pct",
                           "spin_rate_change_rpm", "precession_deg", "energy_j", "mode"}
    assert report["mode"] == "spin"
    assert report["on_time_min"] == pytest.approx(10.0 / 60.0)
    assert report["avg_torque_dyne_cm"] == pytest.approx(1500.0)
    assert report["peak_torque_dyne_cm"] == pytest.approx(2000.0)
    assert report["ripple_pct"] == pytest.approx(100.0 / 3.0)
    assert report["energy_j"] == pytest.approx(20.0)
    assert report["spin_rate_change_rpm"] == pytest.approx(0.01 * 60 / (2 * math.pi))
    assert report["precession_deg"] == pytest.approx(0.0)
    # A mode change ends a pass and starts another.
    acc.add(20.0, torque(0), 0.4, axis, 2.0, "spin")
    closed = acc.add(21.0, np.array([1e-4, 0.0, 0.0]), 0.4, axis, 2.2, "attitude")
    assert closed is not None and closed["mode"] == "spin"
    last = acc.close(22.0)
    assert last is not None and last["mode"] == "attitude" and last["avg_torque_dyne_cm"] == pytest.approx(1000.0)
    with pytest.raises(AscsError):
        acc.add(30.0, np.zeros(3), 0.4, axis, 0.0, "warp")
    acc.add(30.0, np.zeros(3), 0.4, axis, 0.0, "spin")
    with pytest.raises(AscsError):
        acc.add(30.0, np.zeros(3), 0.4, axis, 0.0, "spin")
