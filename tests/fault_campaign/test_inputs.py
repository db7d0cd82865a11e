"""Fault campaign, issue 9 §6 and §8: every bad input is one precise line, checked before anything starts.

Each case runs the user command in-process (``acds_cli.__main__.main``) with the
launcher's ``GraphRun.start`` — where the run folder, the ROS domain and the node
processes come into being — replaced by a tripwire, so a case that slips through
fails at once instead of starting a graph. The file-type cases go through
``scripts/acds`` itself (``CI=true``, no stdin). Every case asserts the exit code,
exactly one stderr line with the expected words (no traceback), and that no run
folder was created.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
from pathlib import Path

import numpy as np
import pytest
from acds_cli import __main__ as acds_main
from acds_common.scenario import ScenarioError, load_scenario
from ascs_mode_manager.ground_commands import submit

ROOT = Path(__file__).resolve().parents[2]
FREE_TUMBLE = (ROOT / 'scenarios' / 'free_tumble_heao_b.yaml').read_text()


class NodeWouldStart(AssertionError):
    """The launcher was asked to start the graph: the bad input was not caught before it."""


@pytest.fixture(autouse=True)
def tripwire(monkeypatch):
    """No graph may start and no sweep run may be spawned; the handler ``main`` installs is put back."""
    from acds_cli.verbs import sweep
    from acds_runtime import launcher

    def refuse_start(self):
        raise NodeWouldStart(f'GraphRun.start reached for {self.scenario.name} (run folder {self.run_dir})')

    def refuse_run(name, *_args):
        raise NodeWouldStart(f'sweep would run {name}')

    monkeypatch.setattr(launcher.GraphRun, 'start', refuse_start)
    monkeypatch.setattr(sweep, 'run_one', refuse_run)
    previous = signal.getsignal(signal.SIGTERM)
    yield
    signal.signal(signal.SIGTERM, previous)


def acds(capsys, *argv: str) -> tuple[int, list[str]]:
    """Run the user command in-process: (exit code, non-empty stderr lines)."""
    try:
        code = acds_main.main(list(argv))
    except SystemExit as exc:
        code = exc.code
    return code, [line for line in capsys.readouterr().err.splitlines() if line.strip()]


def assert_one_line(code: int, lines: list[str], expected_code: int, *fragments: str) -> None:
    assert code == expected_code, (code, lines)
    assert len(lines) == 1, lines
    assert 'Traceback' not in lines[0]
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def scenario(tmp_path: Path, text: str, name: str = 'bad.yaml') -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def run_bad(capsys, tmp_path: Path, path: str, *fragments: str, extra: tuple[str, ...] = ('--steps', '3')) -> None:
    """``acds run PATH`` must fail with one scenario-error line (exit 2) and leave no run folder."""
    run_dir = tmp_path / 'run'
    code, lines = acds(capsys, 'run', path, *extra, '--no-record', '--run-dir', str(run_dir))
    assert_one_line(code, lines, 2, 'acds: scenario error:', *fragments)
    assert not run_dir.exists()


# ---- the scenario file itself ---------------------------------------------------------------------------------------

@pytest.mark.parametrize(('make', 'fragment'), [
    (lambda p: p.write_bytes(b'name: x\n' + bytes(range(256)) * 4), 'is a binary file'),
    (lambda p: p.write_bytes('name: caf\u00e9\n'.encode('latin-1')), 'is not UTF-8 text (byte 0xe9 at offset 9)'),
    (lambda p: p.mkdir(), 'is a directory, not a scenario file'),
])
def test_a_scenario_path_that_is_not_yaml_text_is_one_line(tmp_path, make, fragment):
    path = tmp_path / 'scenario.yaml'
    make(path)
    run_dir = tmp_path / 'run'
    proc = subprocess.run([str(ROOT / 'scripts' / 'acds'), 'run', str(path), '--no-record', '--run-dir', str(run_dir)],
                          stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=120, check=False,
                          cwd=tmp_path, env={**os.environ, 'CI': 'true'})
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert_one_line(proc.returncode, lines, 2, f'acds: scenario error: {path}: {fragment}')
    assert not run_dir.exists()


def test_duplicate_yaml_keys_are_refused_at_any_level(capsys, tmp_path):
    top = scenario(tmp_path, FREE_TUMBLE.replace('seed: 1\n', 'seed: 1\nseed: 2\n'), 'top.yaml')
    run_bad(capsys, tmp_path, top, "line 7, column 1 is not valid YAML: duplicate key 'seed' (first given on line 6)")
    nested = scenario(tmp_path, FREE_TUMBLE.replace('  substeps: 1\n', '  substeps: 1\n  substeps: 3\n'), 'n.yaml')
    run_bad(capsys, tmp_path, nested, "duplicate key 'substeps'")


def test_exponent_floats_without_a_dot_are_numbers_and_other_strings_stay_strings(capsys, tmp_path):
    text = FREE_TUMBLE.replace('duration_orbits: 1', 'duration_s: 2.25e2').replace(
        'control_period_s: 0.5', 'control_period_s: 5e-1').replace(
        'initial_rates_deg_s: [1.0, 1.0, 1.0]', 'initial_rates_deg_s: [1e0, -3E-2, +15E-1]').replace(
        'description: HEAO-B', 'description: 1e5x HEAO-B')
    sc = load_scenario(scenario(tmp_path, text, 'exp.yaml'))
    assert sc.duration_s() == 225.0 and sc.control_period_s == 0.5 and sc.total_steps() == 450
    assert np.degrees(sc.get('spacecraft', 'initial_rates')) == pytest.approx([1.0, -0.03, 1.5])
    assert sc.get('', 'description').startswith('1e5x ')
    run_bad(capsys, tmp_path, scenario(tmp_path, text.replace('duration_s: 2.25e2', 'duration_s: 2e5x')),
            "duration_s: expected a number, got '2e5x'")


@pytest.mark.parametrize(('old', 'new', 'fragment'), [
    ('seed: 1\n', f'seed: {10**400}\n', 'seed: an integer with 401 digits (10000000…) is out of range [0, 2147483647]'),
    ('[1520, 7970', f'[{10**400}, 7970', 'spacecraft.inertia_slug_ft2: an integer with 401 digits'),
    ('[1520, 7970', '[1e300, 7970', 'spacecraft.inertia_slug_ft2: 1e+300 is out of range [-7.37562e+08, 7.37562e+08]'),
    ('[1520, 7970, 7920', '[1.0e+300, 1.0e+300, 1.0e+300', 'spacecraft.inertia_slug_ft2: 1e+300 is out of range'),
])
def test_huge_numbers_are_out_of_range_not_a_crash_or_a_nan(capsys, tmp_path, old, new, fragment):
    run_bad(capsys, tmp_path, scenario(tmp_path, FREE_TUMBLE.replace(old, new)), fragment)


@pytest.mark.parametrize(('nodes', 'fragment'), [
    ('[reaction_wheels]', 'nodes: rigid_body is missing (it owns sim time'),
    ('[rigid_body, reaction_wheels, rigid_body]', 'nodes: rigid_body listed more than once'),
])
def test_a_node_list_that_cannot_run_is_refused(capsys, tmp_path, nodes, fragment):
    text = FREE_TUMBLE.replace('nodes: [rigid_body, reaction_wheels]', f'nodes: {nodes}')
    run_bad(capsys, tmp_path, scenario(tmp_path, text), fragment)


@pytest.mark.parametrize(('section', 'key'), [('spacecraft', 'initial_quaternion_xyzw'),
                                              ('controller', 'target_quaternion_xyzw')])
def test_a_zero_quaternion_is_refused_in_any_quaternion_key(capsys, tmp_path, section, key):
    text = f'name: zero_q\nextends: free_tumble_heao_b\n{section}:\n  {key}: [0, 0, 0, 0]\n'
    run_bad(capsys, tmp_path, scenario(tmp_path, text), f'{section}.{key}: [0, 0, 0, 0] has norm 0',
            'cannot be normalised')


def test_more_than_1e9_steps_is_refused_before_the_run(capsys, tmp_path):
    text = FREE_TUMBLE.replace('duration_orbits: 1', 'duration_s: 2500000').replace(
        'control_period_s: 0.5', 'control_period_s: 0.001')
    run_bad(capsys, tmp_path, scenario(tmp_path, text), 'give 2,500,000,000 steps, more than the 1,000,000,000',
            extra=())


@pytest.mark.parametrize('name', ['../../escaped', '.hidden', 'a/b', 'x' * 101])
def test_the_scenario_name_cannot_leave_the_runs_folder(capsys, tmp_path, monkeypatch, name):
    repo = tmp_path / 'a' / 'repo'
    monkeypatch.setenv('ACDS_WORKSPACE', str(repo))  # the default run folder is <workspace>/runs/<name>_<time>
    path = scenario(tmp_path, FREE_TUMBLE.replace('name: free_tumble_heao_b', f'name: "{name}"'))
    code, lines = acds(capsys, 'run', path, '--steps', '3', '--no-record')
    assert_one_line(code, lines, 2, f'name: {repr(name)[:30]}', 'is not a safe folder name')
    assert sorted(p.name for p in tmp_path.rglob('*')) == ['bad.yaml']  # no run folder anywhere
    assert load_scenario(scenario(tmp_path, FREE_TUMBLE.replace('name: free_tumble_heao_b', 'name: ok-1.2_b'),
                                  'ok.yaml')).name == 'ok-1.2_b'


def test_extends_resolves_beside_the_extending_file_from_any_folder(tmp_path, monkeypatch):
    here, shared, elsewhere = tmp_path / 'mine', tmp_path / 'shared', tmp_path / 'elsewhere'
    for folder in (here, shared, elsewhere):
        folder.mkdir()
    scenario(here, FREE_TUMBLE.replace('name: free_tumble_heao_b', 'name: base'), 'base.yaml')
    scenario(here, FREE_TUMBLE.replace('description: HEAO-B', 'description: LOCAL COPY HEAO-B'),
             'free_tumble_heao_b.yaml')
    scenario(shared, FREE_TUMBLE.replace('name: free_tumble_heao_b', 'name: common').replace(
        'altitude_nmi: 225', 'altitude_nmi: 300'), 'common.yaml')
    monkeypatch.chdir(elsewhere)
    by_name = load_scenario(scenario(here, 'name: c1\nextends: base\n', 'c1.yaml'))
    assert by_name.get('', 'description').startswith('HEAO-B free tumble')
    shadowed = load_scenario(scenario(here, 'name: c2\nextends: free_tumble_heao_b\n', 'c2.yaml'))
    assert shadowed.get('', 'description').startswith('LOCAL COPY')  # beside the file first ...
    shipped = load_scenario(scenario(shared, 'name: c3\nextends: free_tumble_heao_b\n', 'c3.yaml'))
    assert shipped.get('', 'description').startswith('HEAO-B free tumble')  # ... then the shipped one
    relative = load_scenario(scenario(here, 'name: c4\nextends: ../shared/common.yaml\n', 'c4.yaml'))
    assert relative.get('orbit', 'altitude') == pytest.approx(300 * 1852.0)
    with pytest.raises(ScenarioError, match=r'c5.yaml: extends: .nowhere. not found \(looked for .*mine/nowhere.yaml'):
        load_scenario(scenario(here, 'name: c5\nextends: nowhere\n', 'c5.yaml'))


# ---- the models' own checks, before any process starts (pre-flight) --------------------------------------------------

@pytest.mark.parametrize(('text', 'fragment'), [
    ('extends: sss_a_spin_up\norbit:\n  apogee_radius_km: 6500\n',
     'orbit: OrbitConfig.apogee_radius_m is geocentric and must be >= the perigee radius'),
    ('extends: free_tumble_heao_b\nwheels:\n  failed_wheel: 2\n',
     "wheels: WheelsConfig.failed_wheel needs layout 'four_cant20'"),
    ('extends: heao_b_acquisition\ncontroller:\n  target_quaternion_xyzw: [0, 0, 0, 0.5]\n',
     'controller: target_q_body_to_eci must be a unit quaternion, |q| = 0.5 (the acds_controller model refuses it)'),
    ('extends: heao_b_acquisition\nmodes:\n  capture_cone_deg: 0\n', 'modes: capture_cone_rad = 0.0 must be in (0, π)'),
    ('extends: sss_a_spin_up\nsss:\n  polarity_level_gauss: 0\n', 'sss: polarity_level_t must be > 0 T'),
    ('extends: sss_a_spin_up\nmodes:\n  ground_commands: ["0: sss enable", "soon: sss mode attitude"]\n',
     "modes.ground_commands entry 'soon: sss mode attitude' is not \"T_S: command\""),
    ('extends: heao_b_acquisition\nmodes:\n  ground_commands: ["600 mode celestial_point"]\n',
     "modes.ground_commands entry '600 mode celestial_point'"),
])
def test_a_model_check_fails_before_any_process_starts(capsys, tmp_path, text, fragment):
    run_bad(capsys, tmp_path, scenario(tmp_path, 'name: model_check\n' + text), fragment)


@pytest.mark.parametrize(('node', 'module', 'builder', 'error', 'label'), [
    ('magnetometer_sim', 'magnetometer_sim.magnetometer_step', 'build_magnetometer',
     'magnetometer_sim.fluxgate.MagnetometerError', 'magnetometer'),
    ('em_driver', 'em_driver.em_driver_step', 'build_assembly', 'em_driver.bridge_switch.EmDriverError', 'em_driver'),
    ('rigid_body', 'dynamics.rigid_body_step', 'build_rigid_body', 'dynamics.errors.DynamicsError', ''),
    ('acds_controller', 'acds_controller.controller_step', 'build_dpa', 'acds_controller.magnetic_laws.ControllerError',
     ''),
])
def test_preflight_builds_every_node_model_the_node_builds(capsys, tmp_path, monkeypatch, node, module, builder, error,
                                                           label):
    """No schema-valid value makes these cores refuse today, so the core's refusal is injected into the very
    builder the node's stepper calls: the pre-flight must build the stepper and turn its error into the one line."""
    import importlib

    error_module, error_name = error.rsplit('.', 1)
    error_type = getattr(importlib.import_module(error_module), error_name)

    def refuse(*_args, **_kwargs):
        raise error_type('injected refusal')

    monkeypatch.setattr(importlib.import_module(module), builder, refuse)
    where = f'{label}: ' if label else ''
    run_bad(capsys, tmp_path, str(ROOT / 'scenarios' / 'heao_b_acquisition.yaml'),
            f'{where}injected refusal (the {node} model refuses it)')


# ---- command-line options ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize(('args', 'fragment'), [
    (('--until-min', 'nan'), 'argument --until-min: must be a finite number of minutes > 0, got nan'),
    (('--until-min', 'inf'), 'argument --until-min: must be a finite number of minutes > 0, got inf'),
    (('--until-min', '-5'), 'argument --until-min: must be a finite number of minutes > 0, got -5'),
    (('--until-min', '0'), 'argument --until-min: must be a finite number of minutes > 0, got 0'),
    (('--until-min', '1e12'), '--until-min 1e+12: 120,000,000,000,000 steps of 0.5 s, more than the 1,000,000,000'),
    (('--rtf', '-1'), 'argument --rtf: must be a finite number in [0, 1e+06] (0: as fast as possible), got -1'),
    (('--rtf', 'nan'), 'argument --rtf: must be a finite number in [0, 1e+06] (0: as fast as possible), got nan'),
    (('--steps', '0'), 'argument --steps: must be a positive integer, got 0'),
    (('--record', 'x_bag', '--no-record'), 'argument --no-record: not allowed with argument --record'),
])
def test_bad_run_options_are_one_line_before_the_run(capsys, tmp_path, args, fragment):
    run_dir = tmp_path / 'run'
    code, lines = acds(capsys, 'run', 'free_tumble_heao_b', *args, '--run-dir', str(run_dir))
    assert_one_line(code, lines, 2, 'acds run: error: ', fragment)
    assert not run_dir.exists() and not (tmp_path / 'x_bag').exists()


def test_rtf_zero_still_means_as_fast_as_possible(capsys, tmp_path):
    with pytest.raises(NodeWouldStart):  # accepted: the run would start (the tripwire stops it)
        acds_main.main(['run', 'free_tumble_heao_b', '--rtf', '0', '--no-record', '--run-dir', str(tmp_path / 'r')])
    capsys.readouterr()
    code, lines = acds(capsys, 'run', 'free_tumble_heao_b', '--rtf', '-0.5', '--run-dir', str(tmp_path / 'r'))
    assert_one_line(code, lines, 2, 'argument --rtf: must be a finite number in [0, 1e+06]')


def test_unwritable_outputs_are_refused_before_the_run(capsys, tmp_path):
    blocker = tmp_path / 'a_file'
    blocker.write_text('not a folder\n')
    cases = [
        (('--run-dir', str(blocker / 'run')), f'--run-dir {blocker}/run: {blocker} is not a directory'),
        (('--run-dir', str(blocker)), f'--run-dir {blocker}: exists and is not a directory'),
        (('--run-dir', str(tmp_path / 'run'), '--summary-json', str(blocker / 'deep' / 's.json')),
         f'--summary-json {blocker}/deep/s.json: {blocker} is not a directory'),
        (('--run-dir', str(tmp_path / 'run'), '--summary-json', str(tmp_path)), f'--summary-json {tmp_path}: is a directory'),
    ]
    for args, fragment in cases:
        code, lines = acds(capsys, 'run', 'free_tumble_heao_b', '--no-record', *args)
        assert_one_line(code, lines, 2, 'acds run: error: ', fragment)
    assert sorted(p.name for p in tmp_path.iterdir()) == ['a_file']


@pytest.mark.parametrize(('args', 'fragment'), [
    (('--jobs', '0'), 'acds sweep: error: argument --jobs/-j: must be a positive integer, got 0'),
    (('--until-min', 'nan'), 'acds sweep: error: argument --until-min: must be a finite number of minutes > 0'),
    (('--json', '/dev/null/t.json'), 'acds sweep: error: --json /dev/null/t.json: /dev/null is not a directory'),
])
def test_bad_sweep_options_are_one_line_before_any_run(capsys, args, fragment):
    code, lines = acds(capsys, 'sweep', 'free_tumble_heao_b', *args)
    assert_one_line(code, lines, 2, fragment)


def test_sweep_preflights_every_scenario_before_the_first_run(capsys, tmp_path):
    bad = scenario(tmp_path, 'name: bad_orbit\nextends: sss_a_spin_up\norbit:\n  apogee_radius_km: 6500\n')
    code, lines = acds(capsys, 'sweep', 'free_tumble_heao_b', bad)
    assert_one_line(code, lines, 2, f'acds: scenario error: {bad}: orbit: OrbitConfig.apogee_radius_m')


# ---- summaries never carry NaN or Infinity ------------------------------------------------------------------------

def test_summary_json_writes_non_finite_numbers_as_null_and_says_so(capsys, tmp_path):
    from acds_runtime.summary import summary_json, write_summary_json

    summary = {'scenario': 's', 'momentum_drift_rel': math.nan, 'final_rates_deg_s': [0.1, math.inf, -math.inf],
               'passes': [{'mode': 'spin', 'ripple_pct': np.float64('nan'), 'energy_j': 2.0}]}
    text, replaced = summary_json(summary)
    assert replaced == ['momentum_drift_rel', 'final_rates_deg_s[1]', 'final_rates_deg_s[2]', 'passes[0].ripple_pct']

    def strict(constant: str) -> None:
        raise AssertionError(f'{constant} in a summary')

    assert json.loads(text, parse_constant=strict) == {
        'scenario': 's', 'momentum_drift_rel': None, 'final_rates_deg_s': [0.1, None, None],
        'passes': [{'mode': 'spin', 'ripple_pct': None, 'energy_j': 2.0}]}
    out = tmp_path / 'new' / 'summary.json'
    write_summary_json(out, [summary])
    json.loads(out.read_text(), parse_constant=strict)
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and 'non-finite value(s) written as null' in lines[0] and '[0].passes[0].ripple_pct' in lines[0]


# ---- §8: one mode per perigee pass ----------------------------------------------------------------------------------

def test_disable_mode_attitude_enable_mid_spin_pass_cannot_start_an_attitude_pass():
    """Seed 001: "The spin mode and attitude mode will not both be activated on a single perigee pass"."""
    from acds_common.units import GAUSS_T, rpm_to_rad_s
    from ascs_mode_manager.sss_ascs import SssAscs

    ascs, dt = SssAscs(), 0.05

    def perigee(t0: float, seconds: float, gauss: float) -> list:
        out = []
        for t in t0 + dt * np.arange(int(seconds / dt)):
            theta = -rpm_to_rad_s(4.0) * t
            out.append(ascs.step(float(t), dt, gauss * GAUSS_T * np.array([math.cos(theta), math.sin(theta), 0.0])))
        return out

    assert submit(ascs, 'sss enable', 0.0).accepted and submit(ascs, 'sss mode spin', 0.0).accepted
    assert perigee(0.0, 60.0, 0.27)[-1].mode == 'spin'
    assert submit(ascs, 'sss disable', 60.0).accepted
    refused = submit(ascs, 'sss mode attitude', 60.0)
    assert not refused.accepted and 'already had a spin-mode pass' in refused.reason
    assert submit(ascs, 'sss enable', 60.0).accepted
    assert all(o.attitude_coil == 0 for o in perigee(60.0, 60.0, 0.27))
    perigee(120.0, 60.0, 0.02)  # the field falls below 0.075 G: the perigee pass ends
    assert submit(ascs, 'sss mode attitude', 180.0).accepted  # the next perigee: attitude mode
    assert perigee(180.0, 30.0, 0.27)[-1].attitude_coil == 1
