"""The real OreSat C3 flight software (``oresat-c3`` 0.6.6, unmodified, from ``.venv-c3``) flies the emulated cards.

``acds run oresat_c3_detumble`` serves the ADCS and GPS cards on the bus at 127.0.0.1:29536 (the C3's one port);
the C3 starts in its private namespace (:mod:`canopen_bus.c3_runner`), an operator sets its ADCS manager to
DETUMBLE with the study's orbit by SDO to node 0x01 (:mod:`canopen_bus.c3_cli`), and the run flies on at real
time. The C3's ADCS manager sleeps 300 s in IDLE before it looks at the new mode (``adcs_manager.py`` on_loop), so
the run lasts 370 s of wall time: this test takes about 6½ minutes (slow; ``.venv/bin/python -m pytest -p
no:xdist tests/test_real_c3_on_the_bus.py``). It checks

* the C3's own dictionary: the gyro and magnetometer integers it stored (SDO upload of 0x5038 ``adcs``) are values
  the ADCS card sent in its PDOs shortly before;
* the run's data: every setpoint the C3 wrote (SDO downloads to 0x4007 sub 4–6 in the CAN log, with the step that
  sampled each) is the current setpoint the cards applied at that step (``cards/current_setpoint``), held until the
  next, and the rods' moment command of that step is it, clamped at the driver's limit, × the coil's A·m²/A;

* a fault it must survive: at t = 320 s (some 30 s into its detumble) the ADCS card's SDO replies are lost
  (``can_bus.fault: sdo_lost``); the C3's SDO client gives up (``SdoCommunicationError``), its ADCS service stops
  for good (``olaf/common/service.py`` ``_loop``: any exception of ``on_loop`` ends the service), and the run's
  account of the flight computer (:mod:`canopen_bus.flight_report`) says it stopped writing setpoints within a
  second of the fault while its heartbeat went on to the end;

and prints what the C3's detumble does to the spacecraft: |ω| over time, its setpoints, the rods' energy.
"""

from __future__ import annotations

import math
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import canopen
import numpy as np
import pytest
import yaml
from acds_common import topics
from acds_common.cdr import Codec
from acds_common.scenario import SCENARIO_DIR, load_scenario
from canopen_bus.c3_cli import detumble_orbit, operate_detumble
from canopen_bus.c3_commands import connect, stored_adcs
from canopen_bus.c3_runner import C3_SOCKETCAND_PORT, C3Process, c3_python
from canopen_bus.canlog import read_frames
from canopen_bus.flight_report import report

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = 'oresat_c3_detumble'
#: 300 s of the C3's IDLE sleep from its start, its start and the heartbeat wait, and ~70 s of its detumble.
STEPS = 3700
#: The fault: the ADCS card's SDO replies lost from this sim time on.
FAULT_TIME_S = 320.0
SETPOINTS = {(0x38, 0x4007, sub): name for sub, name in ((4, 'x'), (5, 'y'), (6, 'z'))}
CARD_GYRO_PDO, C3_ADCS_GYRO = 0x1B8, ('gyroscope_pitch_rate', 'gyroscope_yaw_rate', 'gyroscope_roll_rate')


def _wait_line(path: Path, pattern: str, proc: subprocess.Popen, timeout_s: float) -> re.Match:
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        m = re.search(pattern, path.read_text(errors='replace'))
        if m:
            return m
        assert proc.poll() is None, f'acds run ended ({proc.returncode}) before printing {pattern!r}:\n{path.read_text()}'
        time.sleep(0.2)
    raise AssertionError(f'acds run printed no {pattern!r} within {timeout_s} s:\n{path.read_text()}')


VECTOR3 = 'geometry_msgs/msg/Vector3Stamped'


def _series(bag_dir: Path, topic: str, dt_s: float, msg_type: str = VECTOR3) -> dict[int, object]:
    """{step: value} of one topic of the run's bag."""
    from acds_runtime.bag.reader import open_bag
    name = topics.resolve(topic)
    codec = Codec(msg_type)
    out = {}
    for _topic, _t, data in open_bag(bag_dir).messages([name]):
        t_ns, value = codec.decode(data)
        out[round(t_ns * 1e-9 / dt_s)] = value
    return out


@pytest.mark.slow
@pytest.mark.duration(383)
@pytest.mark.timeout(900)
def test_the_real_c3_detumbles_the_emulated_cards(tmp_path: Path) -> None:
    assert c3_python().is_file(), 'no .venv-c3: scripts/setup_env.sh creates it'
    with socket.socket() as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind(('127.0.0.1', C3_SOCKETCAND_PORT))  # the C3's one port must be free (fails loudly naming it)
    path = tmp_path / 'oresat_c3_detumble_sdo_lost.yaml'
    path.write_text(yaml.safe_dump({'extends': str(SCENARIO_DIR / f'{SCENARIO}.yaml'), 'name': path.stem,
                                    'input_timeout_s': 120.0,  # the C3's start (scipy, skyfield) on a loaded machine
                                    'can_bus': {'fault': 'sdo_lost', 'fault_time_s': FAULT_TIME_S}}))
    scenario = load_scenario(str(path))
    dt = scenario.control_period_s
    run_dir = tmp_path / 'run'
    err = tmp_path / 'acds_run.err'
    with open(err, 'w') as fh:
        run = subprocess.Popen([sys.executable, '-m', 'acds_cli', 'run', str(path), '--can-port', str(C3_SOCKETCAND_PORT),
                                '--steps', str(STEPS), '--run-dir', str(run_dir), '--quiet'],
                               stdout=subprocess.DEVNULL, stderr=fh, stdin=subprocess.DEVNULL, cwd=ROOT,
                               env={**os.environ, 'ACDS_WORKSPACE': str(ROOT)}, start_new_session=True)
    c3 = C3Process(run_dir / 'c3')
    stored: dict[str, int] = {}
    upload_wall = 0.0
    try:
        _wait_line(err, r'CAN bus \(socketcand protocol\) on 127\.0\.0\.1:29536', run, 120)
        c3.start()
        back = operate_detumble('127.0.0.1', C3_SOCKETCAND_PORT, *detumble_orbit(SCENARIO))
        period, inclination = detumble_orbit(SCENARIO)
        assert back['control_mode'] == 3
        assert back['orbital_period'] == pytest.approx(period, rel=1e-6)
        assert back['orbital_inclination'] == pytest.approx(math.degrees(inclination), rel=1e-6)
        # While the run flies, what the C3 stored of the ADCS card's PDOs, read from its own dictionary.
        _wait_line(err, r'flight computer heartbeat after', run, 60)
        net = canopen.Network()
        net.connect(interface='socketcand', channel='vcan0', host='127.0.0.1', port=C3_SOCKETCAND_PORT)
        try:  # until the C3 holds a gyro PDO of the card on all three axes (its 1 s period), at most 30 s; then once
            # more, so the triple read is one the C3 stored whole (an upload of 15 objects may straddle a PDO)
            node, t_end = connect(net), time.monotonic() + 30.0
            while not all(stored.get(n) for n in C3_ADCS_GYRO):
                assert time.monotonic() < t_end, f'the C3 stored no gyro PDO of the card in 30 s: {stored}'
                stored = stored_adcs(node)
            upload_wall = time.time()
            stored = stored_adcs(node)
        finally:
            net.disconnect()
        assert run.wait(STEPS * dt + 300) == 0, err.read_text()
        c3_alive_at_the_end = c3.alive()
        # Paced to the wall clock: its node processes are left to the OS (acds_runtime.placement), so the card answers
        # the C3's SDO writes within their 0.3 s whatever else the machine runs.
        assert 'placed on the two CPUs' not in err.read_text()
    finally:
        c3.stop()
        if run.poll() is None:
            os.killpg(run.pid, signal.SIGTERM)
            run.wait(30)
    assert not c3.alive()
    _check_run(run_dir, scenario, stored, upload_wall, c3_alive_at_the_end)


def _check_run(run_dir: Path, scenario, stored: dict[str, int], upload_wall: float, c3_alive_at_the_end: bool) -> None:
    """The C3's stored PDOs against the card's, every setpoint against the rods, the fault's account."""
    dt = scenario.control_period_s
    frames = read_frames(run_dir / 'can.asc')
    # The C3 stored integers the card sent: the gyro triple of one of the card's gyro PDOs before the upload.
    sent = [struct_triple(d) for _k, wall, rx, cid, d in frames if not rx and cid == CARD_GYRO_PDO and wall <= upload_wall]
    assert sent, 'the card sent no gyro PDO before the upload'
    assert tuple(stored[n] for n in C3_ADCS_GYRO) in sent[-3:], (stored, sent[-3:])
    assert any(stored[n] != 0 for n in stored)

    # Every setpoint it wrote is the setpoint applied at the step that sampled it, and drives the rods' command.
    fc = report(run_dir / 'can.asc', 1, SETPOINTS, frames)
    assert fc.heartbeats > 0 and all(w.count > 0 for w in fc.setpoints.values()), fc.as_dict()
    written: dict[int, list] = {}
    for k, _wall, rx, cid, d in frames:
        key = (cid - 0x600, int.from_bytes(d[1:3], 'little'), d[3]) if rx and len(d) == 8 and d[0] == 0x23 else None
        if key in SETPOINTS:
            written.setdefault(k, [None, None, None])['xyz'.index(SETPOINTS[key])] = int.from_bytes(d[4:8], 'little',
                                                                                                    signed=True)
    applied = _series(run_dir / 'bag', 'cards/current_setpoint', dt)
    command = _series(run_dir / 'bag', topics.MOMENT_COMMAND, dt)
    limit = np.array(scenario.get('can_bus', 'setpoint_limit'))
    per_amp = np.array(scenario.get('can_bus', 'dipole_per_amp'))
    held = np.zeros(3)
    for k in range(max(applied) + 1):
        for axis, ua in enumerate(written.get(k, (None,) * 3)):
            if ua is not None:
                held[axis] = ua * 1e-6
        assert np.array_equal(np.array(applied[k]), held), (k, applied[k], held)
        assert np.allclose(command[k], np.clip(held, -limit, limit) * per_amp, rtol=1e-12, atol=0.0), k

    # The fault: the setpoints stop within a second of it (the C3's SDO client waits 0.3 s once), the heartbeat goes on.
    fault_k = round(FAULT_TIME_S / dt)
    last_k = max(w.last_step for w in fc.setpoints.values())
    assert fault_k <= last_k <= fault_k + round(1.0 / dt), (fault_k, last_k)
    assert fc.heartbeat_steps[1] >= STEPS - round(2.0 / dt) and c3_alive_at_the_end
    assert fc.stopped_line(dt, round(10.0 / dt)), fc.as_dict()
    assert 'SdoCommunicationError' in (run_dir / 'c3' / 'c3.log').read_text()

    odometry = _series(run_dir / 'bag', topics.TRUTH_ODOMETRY, dt, topics.type_of(topics.TRUTH_ODOMETRY))
    first = min(written)
    rates = {k: math.degrees(float(np.linalg.norm(odometry[k].angular))) for k in (0, first, max(odometry))}
    print(f'\nreal C3: first setpoint at step {first} (t = {first * dt:.1f} s); |ω| '
          + ', '.join(f'{r:.4f}°/s at {k * dt:.0f} s' for k, r in rates.items())
          + '; setpoints ' + ', '.join(f'{a}: {w.count} writes, {w.low}…{w.high} µA, {w.nonzero} non-zero'
                                       for a, w in fc.setpoints.items()))


def struct_triple(data: bytes) -> tuple[int, int, int]:
    return tuple(int.from_bytes(data[i:i + 2], 'little', signed=True) for i in (0, 2, 4))
