"""Graph tests of the magnetics hardware: rigid_body + reaction_wheels + magnetometer_sim + em_driver.

Scenario ``magnetics_bench_heao_b`` (HEAO-B tumbling at about 1°/s per axis, no controller,
the em_driver holding a constant ``bench_command``). Lockstep pairing checked here:

* rigid_body integrates [t_k, t_k+1] with em_driver's ``dipole_avg`` of step k and
  publishes the step-average ``truth/torque_magnetic`` with truth k+1;
* magnetometer_sim at step k sees B_true(t_k) + residual + Δ·dipole_avg(k−1).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from acds_common import topics
from acds_common.scenario import load_scenario
from acds_common.units import GAUSS_T


def _stamp_ns(stamp) -> int:
    return stamp.sec * 10**9 + stamp.nanosec

STEPS = 60
DT_S = 0.5
FAULT_STEP = 20
BIAS_SHIFT_V = 0.1
#: Custom Δ, T/(A·m²) (sensor axis i, magnet j): large and asymmetric so that a wrong
#: sign, a transposed matrix or the wrong step's dipole shows far above the quantisation.
COUPLING = np.array([[1.0, -0.5, 0.3], [0.2, 1.0, -0.4], [-0.3, 0.6, 1.0]]) * 1e-8
RESIDUAL_T = np.array([0.005, -0.004, 0.003]) * GAUSS_T


def _by_step(msgs: list[Any], name: str | None = None) -> dict[int, Any]:
    """Messages keyed by step (diagnostics: only the status named ``name``)."""
    out = {}
    for m in msgs:
        k = round(_stamp_ns(m.header.stamp) / (DT_S * 1e9))
        if name is None:
            out[k] = m
        elif m.status and m.status[0].name == name:
            out[k] = m.status[0]
    return out


def _v(m: Any) -> np.ndarray:
    return np.array([m.vector.x, m.vector.y, m.vector.z])


def _b(m: Any) -> np.ndarray:
    f = m.magnetic_field
    return np.array([f.x, f.y, f.z])


def _kv(status: Any) -> dict[str, str]:
    return {kv.key: kv.value for kv in status.values}


@pytest.fixture(scope='module')
def bench_run(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """One 60-step bench run with a custom coupling, a residual field and a bias-shift fault at step 20."""
    from acds_runtime.launcher import GraphRun
    from acds_runtime.testing import alive

    sc = load_scenario('magnetics_bench_heao_b')
    mag = sc.values['magnetometer']
    mag.update(coupling_preset='custom', coupling=COUPLING.ravel().tolist(), residual_field=RESIDUAL_T.tolist(),
               fault='bias_shift', fault_unit='A', fault_axis=-1, fault_value_v=BIAS_SHIFT_V,
               fault_time=FAULT_STEP * DT_S)
    lines: list[str] = []
    graph = GraphRun(sc, tmp_path_factory.mktemp('magnetics_bench'), steps=STEPS, echo=lines.append, keep=True)
    try:
        graph.start()
        result = graph.wait()
    finally:
        graph.stop()
        left = [p.popen.pid for p in graph.processes.values() if alive(p.popen.pid)]
        assert not left, f'processes left behind: {left}'
    mon = result.monitor
    return {
        'scenario': sc,
        'codes': result.exit_codes,
        'b_true': {k: _b(m) for k, m in _by_step(mon.messages(topics.TRUTH_B_BODY)).items()},
        'torque': {k: _v(m) for k, m in _by_step(mon.messages(topics.TRUTH_TORQUE_MAG)).items()},
        'dipole': {k: _v(m) for k, m in _by_step(mon.messages(topics.DIPOLE_AVG)).items()},
        'field': {k: _b(m) for k, m in _by_step(mon.messages(topics.MAG_FIELD)).items()},
        'bias': {k: _v(m) for k, m in _by_step(mon.messages(topics.MAG_BIAS_VOLTS)).items()},
        'volts': {k: _v(m) for k, m in _by_step(mon.messages(topics.MAG_VOLTS)).items()},
        'mag_diag': _by_step(mon.messages(topics.DIAGNOSTICS), 'magnetometer_sim'),
        'drv_diag': _by_step(mon.messages(topics.DIAGNOSTICS), 'em_driver'),
    }


def test_every_node_completes_and_publishes_each_step(bench_run):
    assert bench_run['codes'] == {n: 0 for n in ('rigid_body', 'reaction_wheels', 'magnetometer_sim', 'em_driver')}
    assert sorted(bench_run['torque']) == list(range(STEPS + 1))
    # stage nodes may or may not compute step N before rigid_body ends the run at t_N
    assert set(range(STEPS)) <= set(bench_run['field']) <= set(range(STEPS + 1))
    assert set(range(STEPS)) <= set(bench_run['dipole']) <= set(range(STEPS + 1))


def test_magnetic_torque_in_dynamics_is_achieved_dipole_cross_b_true(bench_run):
    """truth/torque_magnetic(k) = dipole_avg(k−1) × mean of B over [t_k−1, t_k].

    B is known at the step ends; the trapezoid (B_k−1 + B_k)/2 differs from the true
    mean of B(t) over the step by Δt²/12·B'' (B'' estimated from the second difference
    of the published B_k), so the tolerance per step is |M|·Δt²/12·|B''|, doubled for the
    estimate, plus 1e-6 of |M||B| for the integrator's own truncation.

    Tighter: subtracting that curvature term, (B_k−1 + B_k)/2 − (B_k+1 − 2B_k + B_k−1)/12,
    leaves the error of using B'' at t_k instead of the step middle, Δt³/24·|B'''|; B
    turns in body axes by at most θ = the largest angle between successive B_k, so
    |B'''| ≲ (θ/Δt)³|B| and the relative error ≲ θ³/24 (θ ≈ 0.015 rad here: 1.4e-7).
    Next-order terms are θ⁴-small but not negligible at this θ: tolerance 4·θ³/24·|M||B|.
    """
    b, tq, m = bench_run['b_true'], bench_run['torque'], bench_run['dipole']
    command = np.array(bench_run['scenario'].get('em_driver', 'bench_command'))
    assert np.allclose(m[STEPS - 1], command, rtol=0.02), 'the coils settle on the bench command'
    theta = max(math.acos(min(1.0, b[k] @ b[k + 1] / np.linalg.norm(b[k]) / np.linalg.norm(b[k + 1])))
                for k in range(STEPS))
    worst = worst_corrected = 0.0
    for k in range(1, STEPS):
        b_mid = 0.5 * (b[k - 1] + b[k])
        expected = np.cross(m[k - 1], b_mid)
        b_dd = np.linalg.norm(b[k + 1] - 2 * b[k] + b[k - 1]) / DT_S**2
        tol = 2 * np.linalg.norm(m[k - 1]) * DT_S**2 / 12 * b_dd + 1e-6 * np.linalg.norm(m[k - 1]) * np.linalg.norm(b_mid)
        err = np.linalg.norm(tq[k] - expected)
        worst = max(worst, err / max(np.linalg.norm(expected), 1e-30))
        assert err <= tol, f'step {k}: torque {tq[k]} vs M×B {expected} (|err| {err:.3e} > tol {tol:.3e} N·m)'
        b_mean = b_mid - (b[k + 1] - 2 * b[k] + b[k - 1]) / 12
        corrected = np.cross(m[k - 1], b_mean)
        err_c = np.linalg.norm(tq[k] - corrected)
        tol_c = 4 * theta**3 / 24 * np.linalg.norm(m[k - 1]) * np.linalg.norm(b_mean)
        worst_corrected = max(worst_corrected, err_c / np.linalg.norm(corrected))
        assert err_c <= tol_c, f'step {k}: torque {tq[k]} vs M×mean(B) {corrected} (|err| {err_c:.3e} > {tol_c:.3e})'
        if k == 1:  # while the coils charge, the step's own dipole (wrong pairing) misses by far more
            wrong = np.cross(m[k], b_mid)
            assert np.linalg.norm(tq[k] - wrong) > 100 * tol
    assert tq[0].tolist() == [0.0, 0.0, 0.0], 'no torque before the first integration'
    print(f'worst relative torque error: trapezoid {worst:.3e}, curvature-corrected {worst_corrected:.3e}, '
          f'theta {theta:.4f} rad')


def test_magnetometer_field_is_b_true_plus_residual_plus_coupling_of_previous_dipole(bench_run):
    """field(k) = B_true(k) + residual + Δ·dipole_avg(k−1), within half a 0.004 G quantisation step plus
    the documented end-point nonlinearity 0.005·|b³ − b| G; after the bias shift the naive field reads
    +0.1 V/(2.5 V/G) = 0.04 G high on every axis."""
    b, f, m = bench_run['b_true'], bench_run['field'], bench_run['dipole']
    for k in range(STEPS):
        m_prev = m[k - 1] if k > 0 else np.zeros(3)
        sensed_g = (b[k] + RESIDUAL_T + COUPLING @ m_prev) / GAUSS_T
        bound_g = 0.002 + 0.005 * np.abs(sensed_g**3 - sensed_g) + 1e-9
        shift_g = BIAS_SHIFT_V / 2.5 if k >= FAULT_STEP else 0.0
        err_g = f[k] / GAUSS_T - sensed_g - shift_g
        assert np.all(np.abs(err_g) <= bound_g), f'step {k}: field error {err_g} G exceeds {bound_g} G'
        if k == 1:  # while the coils charge, the step's own dipole would be visibly wrong
            wrong_g = (b[k] + RESIDUAL_T + COUPLING @ m[k]) / GAUSS_T
            assert np.max(np.abs(f[k] / GAUSS_T - wrong_g) - bound_g) > 0.0
    no_coupling_g = (b[STEPS - 1] + RESIDUAL_T) / GAUSS_T
    assert np.max(np.abs(f[STEPS - 1] / GAUSS_T - BIAS_SHIFT_V / 2.5 - no_coupling_g)) > 0.05


def test_bias_shift_fault_shows_in_bias_volts_and_diagnostics(bench_run):
    bias, diag = bench_run['bias'], bench_run['mag_diag']
    for k in range(STEPS):
        expected = 2.5 + (BIAS_SHIFT_V if k >= FAULT_STEP else 0.0)
        assert np.allclose(bias[k], expected, atol=1e-12), f'step {k}: bias volts {bias[k]}'
    before, at = _kv(diag[FAULT_STEP - 10]), _kv(diag[FAULT_STEP])
    assert diag[FAULT_STEP - 10].level == b'\x00' and before['bias_volts_x'] == '2.5000'
    assert diag[FAULT_STEP].level == b'\x01', 'a shifted bias voltage is a WARN'
    assert [at[f'bias_volts_{a}'] for a in 'xyz'] == ['2.6000'] * 3
    assert at['active_unit'] == 'A'
    assert 'bias_shift' in at['event_0'] and 'unit A' in at['event_0']
    assert at['volts_x'] == f'{bench_run["volts"][FAULT_STEP][0]:.4f}'
    assert FAULT_STEP - 1 not in diag, 'telemetry every 10 steps and at events only'


def test_driver_telemetry_reports_duty_switching_power_and_no_alarm(bench_run):
    diag = bench_run['drv_diag']
    assert sorted(k for k in diag if k < STEPS) == list(range(0, STEPS, 10))
    last = _kv(diag[50])
    assert diag[50].level == b'\x00'
    for a in 'xyz':
        assert 0.5 < float(last[f'duty_{a}']) < 1.0
        assert int(last[f'switch_count_{a}']) > 10
        assert float(last[f'power_w_{a}']) > 0.0
        assert last[f'alarm_{a}'] == 'false' and last[f'active_unit_{a}'] == 'A'
    current = bench_run['scenario'].get('em_driver', 'bench_command')[0] / (2062 / 0.727)
    assert math.isclose(float(last['coil_current_a_x']), current, rel_tol=0.011)


def test_standby_units_take_over(launch_graph):
    """Scenario keys select the standby magnetometer (unit B) while unit A takes a bias shift, and an
    open winding on the x driver A trips the mismatch alarm (ERROR) and the automatic switch to B."""
    sc = load_scenario('magnetics_bench_heao_b')
    sc.values['magnetometer'].update(active_unit='B', fault='bias_shift', fault_unit='A', fault_axis=-1,
                                     fault_value_v=BIAS_SHIFT_V, fault_time=0.0)
    sc.values['em_driver'].update(failure='open_winding', failure_axis=0, failure_unit='A', failure_time=5.0,
                                  auto_switch_to_standby=True, mismatch_settle=1.5)
    steps = 40
    with launch_graph(sc, steps=steps) as graph:
        result = graph.wait()
    mon = result.monitor
    bias = {k: _v(m) for k, m in _by_step(mon.messages(topics.MAG_BIAS_VOLTS)).items()}
    assert all(np.allclose(v, 2.5) for v in bias.values()), 'the standby unit B does not see unit A\'s fault'
    mag0 = _kv(_by_step(mon.messages(topics.DIAGNOSTICS), 'magnetometer_sim')[0])
    assert mag0['active_unit'] == 'B' and mag0['bias_volts_x'] == '2.5000'
    diag = _by_step(mon.messages(topics.DIAGNOSTICS), 'em_driver')
    alarm_steps = [k for k, s in diag.items() if s.level == b'\x02']
    assert alarm_steps, 'the open winding raises the mismatch alarm at ERROR'
    k_alarm = alarm_steps[0]
    text = ' | '.join(v for kv in [_kv(diag[k_alarm])] for key, v in kv.items() if key.startswith('event_'))
    assert 'mismatch alarm on unit A' in text and 'auto switch from unit A to standby unit B' in text
    assert k_alarm == 13, f'alarm at step {k_alarm}: failure at step 10, mismatch > 1.5 s after 4 steps'
    dipole = {k: _v(m) for k, m in _by_step(mon.messages(topics.DIPOLE_AVG)).items()}
    command = sc.get('em_driver', 'bench_command')
    assert abs(dipole[k_alarm][0]) < 0.1 * abs(command[0]), 'no moment through the open winding'
    assert math.isclose(dipole[steps - 1][0], command[0], rel_tol=0.02), 'unit B restores the x moment'
    assert _kv(diag[steps - 10])['active_unit_x'] == 'B'


def test_forwarded_ground_commands_select_the_standby_units(launch_graph):
    """Scheduled ground commands through ascs_mode_manager (forwarded in the step-k ``mode`` array):
    em_driver applies ``eea_select x B`` at step k (lag 0), magnetometer_sim applies
    ``magnetometer_select B`` at step k+1 (lag 1), which removes unit A's bias shift from the output."""
    sc = load_scenario('magnetics_bench_heao_b')
    sc.values['']['nodes'] = [*sc.get('', 'nodes'), 'ascs_mode_manager']
    sc.values['modes'].update(system='heao', initial_mode='standby',
                              ground_commands=['5: magnetometer_select b', '5: eea_select x B'])
    sc.values['magnetometer'].update(fault='bias_shift', fault_unit='A', fault_axis=-1, fault_value_v=BIAS_SHIFT_V,
                                     fault_time=0.0)
    steps, k_cmd = 30, 10
    with launch_graph(sc, steps=steps) as graph:
        result = graph.wait()
    mon = result.monitor
    mode = _by_step(mon.messages(topics.MODE))
    forwarded = {k: [(kv.key, kv.value) for kv in m.status[0].values if kv.key.startswith('command/')]
                 for k, m in mode.items()}
    assert forwarded[k_cmd] == [('command/magnetometer_sim', 'magnetometer_select B'),
                                ('command/em_driver', 'eea_select x B')]
    assert not any(v for k, v in forwarded.items() if k != k_cmd)
    bias = {k: _v(m) for k, m in _by_step(mon.messages(topics.MAG_BIAS_VOLTS)).items()}
    for k in range(steps):
        assert np.allclose(bias[k], 2.5 + (BIAS_SHIFT_V if k <= k_cmd else 0.0)), f'step {k}: {bias[k]}'
    mag = _by_step(mon.messages(topics.DIAGNOSTICS), 'magnetometer_sim')
    assert _kv(mag[k_cmd + 1])['active_unit'] == 'B' and 'unit B active' in _kv(mag[k_cmd + 1])['event_0']
    assert mag[k_cmd + 1].level == b'\x00', 'unit B reads a nominal bias'
    drv = _by_step(mon.messages(topics.DIAGNOSTICS), 'em_driver')
    kv = _kv(drv[k_cmd])
    assert kv['event_0'] == 'eea_select: axis x unit B active'
    assert [kv[f'active_unit_{a}'] for a in 'xyz'] == ['B', 'A', 'A']
    dipole = {k: _v(m) for k, m in _by_step(mon.messages(topics.DIPOLE_AVG)).items()}
    command = sc.get('em_driver', 'bench_command')
    assert np.allclose(dipole[steps - 1], command, rtol=0.02), 'unit B holds the x moment'
