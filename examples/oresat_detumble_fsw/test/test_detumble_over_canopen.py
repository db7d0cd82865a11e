"""The example's seed 003 law as a plain CANopen master (``oresat_detumble_canopen``) flies the emulated cards at 60×.

``acds run`` serves OreSat 1's ADCS and GPS cards on a bus (``oresat_c3_detumble`` at the built-in scenario's 1 s
control period, so the card's 1 s PDOs come every step); the master reads the gyro and magnetometer PDOs and writes
the three current setpoints by SDO, paced at real-time factor 60. Its detumble time (|ω| < 0.1°/s to the end) is
within 10 % of the built-in controller's on ``oresat_detumble`` (direct engine). What differs, and by how much, is
printed. The sampling: the card samples a setpoint at the step after the one whose sensors it answers (one step of
delay, 1 s). The pacing: three SDO round trips take longer than the 16.7 ms wall step at 60×, so the master answers
one sensor set in two or three and a setpoint is held that long. The quantisation: the gyro in 1 mrad/s counts, the
field in 0.1 µT counts averaged over four magnetometers with 1-count noise each, against the built-in's ideal rates
and the fluxgate through a 10-bit ADC. Measured here: built-in 91.07 min, 59.6 J; the master 95.87 min (+5.3 %),
61.8 J, 2,308 sets in 6,000 steps.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from acds_common.scenario import SCENARIO_DIR, load_scenario
from acds_runtime.direct import DirectRun

RTF = 60.0
#: 100 minutes of flight: the built-in detumble comes at ~91 min on the shipped scenario.
STEPS = 6000


def _scenario(tmp_path: Path) -> Path:
    path = tmp_path / 'oresat_canopen_detumble.yaml'
    path.write_text(yaml.safe_dump({
        'extends': str(SCENARIO_DIR / 'oresat_c3_detumble.yaml'), 'name': 'oresat_canopen_detumble',
        'description': "oresat_c3_detumble at oresat_detumble's 1 s control period",
        'control_period_s': 1.0, 'duration_s': float(STEPS), 'dynamics': {'gravity_gradient': True, 'substeps': 2}}))
    return path


def _master_command(scenario, port: int) -> list[str]:
    exe = shutil.which('oresat_detumble_canopen', path=str(Path(sys.executable).parent))
    assert exe, 'the example is not installed (./scripts/acds setup installs examples/*)'
    c = scenario.get
    return [exe, '--host', '127.0.0.1', '--port', str(port),
            '--orbit-period', repr(c('controller', 'detumble_orbit_period')),
            '--inclination', repr(c('controller', 'magnetic_inclination')),
            '--j-min', repr(c('controller', 'detumble_j_min')),
            '--max-moment', repr(c('controller', 'max_moment_am2')),
            '--dipole-per-amp', *(repr(v) for v in c('can_bus', 'dipole_per_amp'))]


def _wait_port(err: Path, proc: subprocess.Popen, timeout_s: float) -> int:
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        m = re.search(r'CAN bus \(socketcand protocol\) on 127\.0\.0\.1:(\d+)', err.read_text(errors='replace'))
        if m:
            return int(m.group(1))
        assert proc.poll() is None, f'acds run ended ({proc.returncode}):\n{err.read_text()}'
        time.sleep(0.1)
    raise AssertionError(f'acds run named no bus within {timeout_s} s:\n{err.read_text()}')


@pytest.mark.slow
@pytest.mark.duration(111)
@pytest.mark.timeout(600)
def test_the_canopen_master_detumbles_within_ten_percent_of_the_built_in(tmp_path: Path) -> None:
    path = _scenario(tmp_path)
    scenario = load_scenario(str(path))
    built_in = DirectRun(load_scenario('oresat_detumble'), steps=STEPS).run().summary
    run_dir, err, summary_json = tmp_path / 'run', tmp_path / 'run.err', tmp_path / 'summary.json'
    with open(err, 'w') as fh:
        run = subprocess.Popen([sys.executable, '-m', 'acds_cli', 'run', str(path), '--can-port', '0', '--rtf', str(RTF),
                                '--run-dir', str(run_dir), '--summary-json', str(summary_json), '--quiet'],
                               stdout=subprocess.DEVNULL, stderr=fh, stdin=subprocess.DEVNULL,
                               env={**os.environ}, start_new_session=True)
    master = None
    try:
        port = _wait_port(err, run, 120)
        master = subprocess.Popen(_master_command(scenario, port), stdout=subprocess.PIPE, text=True,
                                  start_new_session=True)
        assert run.wait(STEPS / RTF + 300) == 0, err.read_text()
    finally:
        if master is not None:
            master.send_signal(signal.SIGTERM)
            out, _ = master.communicate(timeout=30)
        if run.poll() is None:
            os.killpg(run.pid, signal.SIGTERM)
            run.wait(30)
    stats = json.loads(out.strip().splitlines()[-1])
    ours = json.loads(summary_json.read_text())
    t_bus, t_built_in = ours['detumble_time_min'], built_in['detumble_time_min']
    print(f"\nbuilt-in (oresat_detumble, direct): detumble {t_built_in:.2f} min, {built_in['detumble_energy_j']:.3f} J; "
          f"CANopen master at {RTF:g}x: {t_bus} min, {ours['detumble_energy_j']} J; master: {stats}; "
          f"late steps {ours.get('can_late_steps')}, setpoint age {ours.get('can_setpoint_age_ms')}")
    # Three SDO round trips through the hub take longer than a 16.7 ms step on this machine: the master answers one
    # sensor set in two to three (measured: 2,308 sets in 6,000 steps, setpoint age p50 10 ms); a reply lost to a
    # loaded machine (the client's 0.3 s timeout) is counted and the master flies on.
    assert stats['sets'] >= STEPS // 10 and stats['sdo_failures'] <= 0.01 * stats['setpoints']
    assert t_bus is not None and abs(t_bus - t_built_in) <= 0.10 * t_built_in
