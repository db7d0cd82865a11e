"""The 1-D EMFF airtrack through the graph (spec §10; seed 004 slides 52–55; issue 23 item 6).

Frame ``line`` flies the airtrack plant's force (``acds_common.airtrack``) and holds everything but x; the
airtrack scenarios give the same data on the per-process graph and the direct engine; the unstable
configuration diverges open loop at least as fast as its linearisation says and settles under LQR within
what its closed-loop poles say; the stable one oscillates open loop at its open-loop frequency without
decaying; bad airtrack input is one line, exit 2, before any process starts.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from acds_common.airtrack import AirtrackPlant
from acds_common.scenario import load_scenario
from acds_runtime.direct import DirectRun
from dynamics.errors import DynamicsError
from dynamics.formation import Coil, FormationConfig, FormationDynamics, VehicleInput, VehicleSpec, VehicleState
from emff_studies.emff_cli import airtrack_graph_study

ROOT = Path(__file__).resolve().parents[1]


def _track(tilt_rad: float, magnet_am2: float, x0_m: float) -> FormationDynamics:
    magnet = VehicleSpec('magnet', 5.0, np.eye(3) * 0.01, (Coil(np.array([1.0, 0.0, 0.0]), 0.1, 1000, 65.0),),
                         fixed=True)
    slider = VehicleSpec('slider', 1.0, np.eye(3) * 0.01, (), np.array([magnet_am2, 0.0, 0.0]))
    return FormationDynamics(FormationConfig(frame='line', substeps=10, track_tilt_rad=tilt_rad), [magnet, slider],
                             [VehicleState(), VehicleState((x0_m, 0.0, 0.0))])


@pytest.mark.parametrize(('tilt_deg', 'magnet_am2'), [(0.2, -10.0), (-0.2, 10.0)])
def test_line_frame_flies_the_airtrack_plant(tilt_deg, magnet_am2):
    plant = AirtrackPlant(1.0, magnet_am2, math.radians(tilt_deg))
    dyn = _track(plant.tilt_rad, magnet_am2, 0.45)
    mu = plant.equilibrium_dipole_am2(0.5)
    force = dyn.wrenches_now([(mu, 0.0, 0.0), (0.0, 0.0, 0.0)]).em_force_n[1]
    assert force[0] / 1.0 + plant.track_acceleration_m_s2 == pytest.approx(plant.acceleration(0.45, mu), rel=1e-12)
    dt = 1e-3  # one short step: x − x0 = ½ ẍ dt² to the RK4's accuracy
    dyn.advance(dt, [VehicleInput((mu, 0.0, 0.0)), VehicleInput()])
    magnet, slider = dyn.truth().vehicles
    assert (slider.position_m[0] - 0.45) / (0.5 * dt ** 2) == pytest.approx(plant.acceleration(0.45, mu), rel=1e-4)
    assert np.all(magnet.position_m == 0.0) and np.all(magnet.velocity_m_s == 0.0)  # bolted to the track
    assert np.all(slider.position_m[1:] == 0.0) and np.all(slider.velocity_m_s[1:] == 0.0)
    assert np.all(slider.q_body_to_inertial == [0.0, 0.0, 0.0, 1.0]) and np.all(slider.omega_body_rad_s == 0.0)
    with pytest.raises(DynamicsError, match='free_space'):
        dyn.momentum([np.zeros(3)] * 2)


def test_line_frame_refuses_what_the_track_cannot_hold():
    with pytest.raises(DynamicsError, match="frame 'line' needs every vehicle on the track"):
        FormationDynamics(FormationConfig(frame='line'), _track(0.01, 10.0, 0.5).vehicles,
                          [VehicleState(), VehicleState((0.5, 0.1, 0.0))])
    with pytest.raises(DynamicsError, match='fixed vehicles are the airtrack'):
        FormationDynamics(FormationConfig(frame='free_space'), _track(0.01, 10.0, 0.5).vehicles,
                          [VehicleState(), VehicleState((0.5, 0.0, 0.0))])


def test_airtrack_graph_equals_direct(launch_graph):
    sc = load_scenario('emff_airtrack_unstable')
    with launch_graph(sc, steps=40) as graph:
        result = graph.wait()
    assert result.summary['truth_messages'] == 2 * 4 * 41
    assert DirectRun(sc, steps=40).run().summary['truth_digest'] == result.summary['truth_digest']


def _lqr_bound_s(row: dict) -> float:
    """2 % settling of the slowest closed-loop mode, ln(50)/|Re s|, with the coil's lag and the step's
    nonlinearity allowed for (× 1.5)."""
    return 1.5 * math.log(50.0) / min(abs(re) for re, _im in row['closed_loop_poles'])


def test_unstable_airtrack_diverges_open_loop_and_lqr_holds_it():
    row = airtrack_graph_study('unstable')
    s = max(re for re, _im in row['open_loop_poles'])
    assert s > 0.0  # a real unstable pole (slide 54)
    (t_o, x_o, _), (t_c, x_c, _) = row['_runs']
    x_ref, dx0 = row['separation_m'], x_o[0] - row['separation_m']
    # the linearisation's δx(t) = δx0 cosh(s t); closer in, the attraction grows faster than linear
    assert (x_o[-1] - x_ref) / dx0 >= math.cosh(s * t_o[-1]) and x_o[-1] < x_o[0]
    assert row['lqr']['settling_time_2pct_s'] is not None and row['lqr']['settling_time_2pct_s'] < _lqr_bound_s(row)
    assert abs(x_c[-1] - x_ref) < 1e-3 * abs(dx0)


def test_stable_airtrack_oscillates_open_loop_and_lqr_damps_it():
    row = airtrack_graph_study('stable')
    w = max(im for _re, im in row['open_loop_poles'])
    assert w > 0.0 and max(abs(re) for re, _im in row['open_loop_poles']) < 1e-12  # slide 53: on the imaginary axis
    (t_o, x_o, _), (t_c, x_c, _) = row['_runs']
    err = x_o - row['separation_m']
    ups = t_o[1:][(err[:-1] < 0.0) & (err[1:] >= 0.0)]  # upward crossings of the set point
    period = np.diff(ups)
    assert len(period) >= int(t_o[-1] * w / (2 * math.pi)) - 1  # it keeps oscillating
    assert np.allclose(period, 2 * math.pi / w, rtol=0.1)  # at the open-loop frequency (nonlinear: within 10 %)
    half = len(err) // 2
    assert np.max(np.abs(err[half:])) > 0.95 * np.max(np.abs(err[:half]))  # undamped: frictionless
    assert row['open_loop']['settling_time_2pct_s'] is None
    assert row['lqr']['settling_time_2pct_s'] is not None and row['lqr']['settling_time_2pct_s'] < _lqr_bound_s(row)
    assert abs(x_c[-1] - row['separation_m']) < 1e-3 * abs(err[0])


BASE = (ROOT / 'scenarios' / 'emff_airtrack_stable.yaml').read_text()


def _run_acds(*args: str) -> subprocess.CompletedProcess[str]:
    env = {'PATH': '/usr/bin:/bin', 'ROS_LOG_DIR': '/tmp/acds_ros_log'}
    return subprocess.run([sys.executable, '-m', 'acds_cli', *args], capture_output=True, text=True, cwd=ROOT,
                          env=env, timeout=120, check=False)


@pytest.mark.parametrize(('edit', 'message'), [
    (lambda s: s.replace('airtrack_dipole_scale_am2: 100', 'airtrack_dipole_scale_am2: 0'),
     'the airtrack LQR scale dipole_am2 must be > 0'),
    (lambda s: s.replace('airtrack_position_scale_m: 0.01', 'airtrack_position_scale_m: -0.01'),
     'airtrack_position_scale'),
    (lambda s: s.replace('track_tilt_deg: 0.18257979432926477', 'track_tilt_deg: 0'), 'formation: the airtrack needs'),
    (lambda s: s.replace('law: airtrack_lqr', 'law: hold'), 'frame line (the airtrack) flies the laws'),
    (lambda s: s.replace('      magnet: permanent\n', ''), 'one free slider (magnet: permanent, no nodes)'),
    (lambda s: s.replace('permanent_dipole_am2: [-10.0, 0.0, 0.0]', 'permanent_dipole_am2: [0, 0, 0]'),
     'a magnet (dipole ≠ 0 A·m²)'),
    (lambda s: s.replace('initial_position_m: [0.45, 0.0, 0.0]', 'initial_position_m: [0.45, 0.1, 0.0]'),
     'frame line puts every vehicle on the track'),
    (lambda s: s.replace('initial_position_m: [0.45, 0.0, 0.0]', 'initial_position_m: [-0.45, 0.0, 0.0]'),
     'the slider starts on the +x side'),
    (lambda s: s.replace('      fixed: true\n', ''), 'one fixed electromagnet'),
])
def test_bad_airtrack_is_one_line_exit_2(tmp_path, edit, message):
    path = tmp_path / 'bad.yaml'
    text = edit(BASE)
    assert text != BASE
    path.write_text(text)
    proc = _run_acds('run', str(path), '--steps', '5')
    assert proc.returncode == 2, proc.stderr
    assert message in proc.stderr, proc.stderr
    assert 'Traceback' not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1


def test_bad_airtrack_study_weight_is_one_line_exit_2():
    proc = _run_acds('emff-airtrack', '--weight-dipole-am2', '0')
    assert proc.returncode == 2 and 'must be > 0' in proc.stderr and len(proc.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize('step', ['0.5', '10'])
def test_a_step_that_starts_the_slider_off_the_track_is_one_line_exit_2(tmp_path, step):
    """x0 − step must be a separation on the track (> 0): 0.5 m was a ZeroDivisionError traceback, 10 m a 'response'
    from −9.5 m, behind the electromagnet."""
    proc = _run_acds('emff-airtrack', '--step-m', step, '--out', str(tmp_path))
    assert proc.returncode == 2, proc.stderr
    assert 'Traceback' not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert '--step-m' in proc.stderr and 'must be < 0.5' in proc.stderr, proc.stderr


@pytest.mark.parametrize('args', [['--dt-s', '1e-9'], ['--duration-s', '1e12']])
def test_a_response_of_more_steps_than_a_run_may_have_is_one_line_exit_2(tmp_path, args):
    """duration / dt past the step bound of a run: it had no bound (--dt-s 1e-9 ran for hours)."""
    proc = _run_acds('emff-airtrack', *args, '--out', str(tmp_path))
    assert proc.returncode == 2, proc.stderr
    assert 'Traceback' not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert 'steps, more than the' in proc.stderr, proc.stderr


def test_the_default_plot_folder_is_in_the_workspace_not_the_current_folder(tmp_path):
    """Every other verb writes its default runs/... in the workspace (ACDS_WORKSPACE, which ./scripts/acds sets to
    the checkout); emff-airtrack wrote runs/emff_airtrack into whatever folder the user stood in."""
    work, here = tmp_path / 'work', tmp_path / 'here'
    work.mkdir()
    here.mkdir()
    env = {'PATH': '/usr/bin:/bin', 'ROS_LOG_DIR': '/tmp/acds_ros_log', 'ACDS_WORKSPACE': str(work)}
    proc = subprocess.run([sys.executable, '-m', 'acds_cli', 'emff-airtrack', '--duration-s', '1'], capture_output=True,
                          text=True, cwd=here, env=env, timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr
    assert (work / 'runs' / 'emff_airtrack' / 'airtrack_stable.png').is_file()
    assert not (here / 'runs').exists()
