"""``/diagnostics`` as ROS tools read it, the frames and the gyro covariance (issue 12 §2 "diagnostics", §3).

* every status on ``/diagnostics`` is one node's: level OK/WARN/ERROR, ``name`` and ``hardware_id``
  the node; ``rigid_body`` publishes its integration health every ``DIAGNOSTICS_EVERY`` steps;
* a torque-free run (no gravity gradient, no actuators) reports momentum and energy drift at
  integration-error level; a run with external torques reports no drift (it would not be error);
* on the wire (graph run): ``/diagnostics`` at the root, frames per :mod:`acds_common.frames`,
  an ideal gyro's all-zero angular-velocity covariance.
"""

from __future__ import annotations

from pathlib import Path

from acds_common import frames, topics
from acds_common.messages import ERROR, OK, WALL_CLOCK_PREFIX, WARN
from acds_common.scenario import load_scenario
from acds_runtime.bag.reader import open_bag
from acds_runtime.bag.writer import typestore
from acds_runtime.direct import DirectRun
from dynamics.rigid_body_step import DIAGNOSTICS_EVERY


def torque_free_scenario(tmp_path: Path) -> Path:
    """HEAO-B tumbling with no gravity gradient and no actuators: H and E are constants of the motion."""
    path = tmp_path / 'torque_free.yaml'
    path.write_text('extends: free_tumble_heao_b\nname: torque_free_heao_b\n'
                    'nodes: [rigid_body]\ndynamics:\n  gravity_gradient: false\n  substeps: 10\n')
    return path


def _statuses(bag_path: Path) -> list[tuple[int, object]]:
    bag = open_bag(bag_path)
    ts = typestore()
    return [(t, st) for t, data in ((t, d) for _topic, t, d in bag.messages([topics.DIAGNOSTICS]))
            for st in ts.deserialize_cdr(data, 'diagnostic_msgs/msg/DiagnosticArray').status]


def test_every_status_is_one_nodes_with_level_and_hardware_id(tmp_path):
    sc = load_scenario('heao_b_acquisition_short')
    DirectRun(sc, steps=120, record=tmp_path / 'bag').run()
    statuses = _statuses(tmp_path / 'bag')
    nodes = set(sc.get('', 'nodes'))
    assert {st.name for _t, st in statuses} >= {'rigid_body', 'reaction_wheels', 'magnetometer_sim', 'em_driver',
                                                'acds_controller'}
    for _t, st in statuses:
        assert st.name in nodes and st.hardware_id == st.name, st
        assert st.level in (OK, WARN, ERROR) and st.message, st
    health = [(t, {kv.key: kv.value for kv in st.values}) for t, st in statuses if st.name == 'rigid_body']
    dt_ns = round(sc.control_period_s * 1e9)
    assert [t // dt_ns for t, _ in health] == list(range(0, 120, DIAGNOSTICS_EVERY))
    for _t, kv in health:
        assert kv['state_finite'] == 'true' and float(kv['quaternion_norm_error']) < 1e-12
        assert kv['torque_free'] == 'false' and 'momentum_drift_rel' not in kv  # gravity gradient and magnets act
        assert float(kv[f'{WALL_CLOCK_PREFIX}step_ms']) > 0.0


def test_torque_free_run_reports_drift_at_integration_error_level(tmp_path):
    sc = load_scenario(str(torque_free_scenario(tmp_path)))
    result = DirectRun(sc, steps=400, record=tmp_path / 'bag').run()
    health = [{kv.key: kv.value for kv in st.values} for _t, st in _statuses(tmp_path / 'bag')]
    assert len(health) == 400 // DIAGNOSTICS_EVERY
    assert all(kv['torque_free'] == 'true' for kv in health)
    drifts = [(float(kv['momentum_drift_rel']), float(kv['energy_drift_rel'])) for kv in health]
    assert max(max(d) for d in drifts) < 1e-9, drifts
    assert any(d[0] > 0.0 or d[1] > 0.0 for d in drifts), 'RK4 is not exact: some drift must show'
    assert result.summary['torque_free'] is True
    assert result.summary['momentum_drift_rel'] < 1e-9 and result.summary['energy_drift_rel'] < 1e-9


def test_graph_publishes_diagnostics_at_the_root_with_rep_frames(launch_graph):
    with launch_graph('heao_b_acquisition_short', steps=60) as graph:
        graph.wait()
        mon = graph.monitor
        diags = mon.messages(topics.DIAGNOSTICS)
        odom, gyro = mon.messages(topics.TRUTH_ODOMETRY), mon.messages(topics.GYRO)
        field, cosines = mon.messages(topics.MAG_FIELD), mon.messages(topics.TRUTH_SUN_COSINES)
    assert topics.resolve(topics.DIAGNOSTICS) == '/diagnostics'
    assert 'rigid_body' in {st.name for m in diags for st in m.status}
    assert (odom[0].header.frame_id, odom[0].child_frame_id) == (frames.ECI, frames.BODY) == ('eci', 'base_link')
    assert gyro[0].header.frame_id == cosines[0].header.frame_id == frames.BODY
    assert field[0].header.frame_id == frames.MAGNETOMETER
    assert all(list(m.angular_velocity_covariance) == [0.0] * 9 for m in gyro)  # ideal gyros (spec §3)
    assert all(m.orientation_covariance[0] == -1.0 for m in gyro)  # no orientation estimate
