"""The run's account of the flight computer from its CAN frames, and the C3 runner's checks (no C3 started here)."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest
from canopen_bus.c3_runner import C3_SOCKETCAND_PORT, C3Error, C3Process
from canopen_bus.flight_report import report, setpoint_objects

SCENARIOS = Path(__file__).resolve().parents[4] / 'scenarios'
SETPOINTS = {(0x38, 0x4007, 4): 'x', (0x38, 0x4007, 5): 'y', (0x38, 0x4007, 6): 'z'}


def _write(sub: int, ua: int) -> bytes:
    return struct.pack('<BHBi', 0x23, 0x4007, sub, ua)


def _frames(last_setpoint_step: int, steps: int) -> list[tuple[int, float, bool, int, bytes]]:
    out = []
    for k in range(steps):
        if k % 10 == 0:
            out.append((k, k * 0.1, True, 0x701, b'\x05'))
        if 5 <= k <= last_setpoint_step:
            out += [(k, k * 0.1, True, 0x638, _write(sub, k - 50)) for sub in (4, 5, 6)]
            out += [(k, k * 0.1, False, 0x5B8, struct.pack('<BHBI', 0x60, 0x4007, sub, 0)) for sub in (4, 5, 6)]
    out.append((7, 0.7, True, 0x638, struct.pack('<BHBi', 0x40, 0x4000, 1, 0)))  # an upload: another SDO
    out.append((7, 0.7, False, 0x5B8, struct.pack('<BHBI', 0x80, 0x4000, 1, 0x06010002)))  # answered by an abort
    out.append((-1, steps * 0.1, True, 0x701, b'\x05'))  # after the last step's sample: no step
    return out


def test_setpoints_heartbeat_and_aborts_are_counted() -> None:
    fc = report(Path('unused'), 1, SETPOINTS, _frames(299, 300))
    assert fc.heartbeats == 30 and fc.heartbeat_steps == (0, 290)
    x = fc.setpoints['x']
    assert (x.count, x.first_step, x.last_step, x.low, x.high, x.nonzero) == (295, 5, 299, -45, 249, 294)
    assert fc.other_sdo == 1 and fc.aborts == {0x06010002: 1}
    assert fc.stopped_line(0.1, 100) is None


def test_setpoints_that_stop_while_the_heartbeat_goes_on_are_named_with_the_step() -> None:
    fc = report(Path('unused'), 1, SETPOINTS, _frames(120, 600))
    line = fc.stopped_line(0.1, 100)
    assert line == ('the flight computer (node 0x01) stopped writing setpoints at step 120 (t = 12.0 s) while its '
                    'heartbeat went on to step 590 (t = 59.0 s)')
    assert line in '\n'.join(fc.lines(0.1))


def test_the_setpoint_objects_come_from_the_mapping() -> None:
    objects = setpoint_objects(SCENARIOS / 'canopen' / 'oresat1_cards.yaml')
    assert set(objects) == {(0x38, 0x4007, 4), (0x38, 0x4007, 5), (0x38, 0x4007, 6)}
    assert objects[(0x38, 0x4007, 4)] == 'adcs 0x4007.4 current_x_setpoint'


def test_the_c3_runner_refuses_another_port_and_a_missing_environment(tmp_path: Path) -> None:
    with pytest.raises(C3Error, match=f'connects to socketcand port {C3_SOCKETCAND_PORT} only'):
        C3Process(tmp_path, port=29999, python=tmp_path / 'python').check()
    with pytest.raises(C3Error, match='no C3 environment'):
        C3Process(tmp_path, python=tmp_path / 'venv' / 'bin' / 'python').check()
    cmd = C3Process(tmp_path, python=tmp_path / 'python').command()
    assert cmd[:4] == ['unshare', '--mount', '--propagation', 'private']
    assert cmd[-13:-1] == ['-m', 'all', '-d', '-t', 'socketcand', '-H', '127.0.0.1', '-b', 'vcan0', '-a', '127.0.0.1',
                           '-p'] and cmd[-14] == str(tmp_path / 'python')
