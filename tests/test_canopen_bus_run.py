"""Flight software on the bus, end to end: a scripted CANopen master flies oresat_c3_detumble through the emulated
cards (paced at a high real-time factor), and ``--replay-can`` of its CAN log gives the same truth bit for bit.

The master is the test's own few lines (python-can's socketcand client + canopen's SDO client): it sends its
heartbeat as node 0x01, reads the ADCS card's gyro TPDO and writes the three magnetorquer current setpoints by
expedited SDO download, a rate-damping law I = −g·ω clamped at ±100 mA (beyond the rods' 69.44 mA, so the
driver's clamp is exercised too).
"""

from __future__ import annotations

import json
import os
import re
import socket
import subprocess
import sys
import threading
from pathlib import Path

import can
import canopen
import pytest
from acds_common.scenario import load_scenario
from acds_runtime.direct import DirectRun
from canopen_bus.dictionary import load_dictionary

ROOT = Path(__file__).resolve().parents[1]
ACDS = [sys.executable, '-m', 'acds_cli']
STEPS = 300
RTF = 10.0
#: Damping gain of the test master, µA per mrad/s.
GAIN_UA_PER_MRAD_S = 1000


class Master:
    """Heartbeat 0x701 every 0.1 s; on each gyro TPDO (0x1B8), three SDO downloads to 0x4007:4..6."""

    def __init__(self, port: int) -> None:
        self.net = canopen.Network()
        self.net.connect(interface='socketcand', channel='vcan0', host='127.0.0.1', port=port)
        self.adcs = self.net.add_node(0x38, load_dictionary('oresat1/adcs'))
        self.adcs.sdo.RESPONSE_TIMEOUT = 2.0
        self.stop = threading.Event()
        self.writes = 0
        self.timeouts = 0
        #: SDO request frames (the card's SDO request COB-ID, canopen's ``rx_cobid``: 0x638) handed to the bus:
        #: each download's, a retry's, an abort's.
        self.sdo_frames = 0
        send = self.net.send_message

        def counted(can_id: int, data: bytes, remote: bool = False) -> None:
            send(can_id, data, remote)
            self.sdo_frames += can_id == self.adcs.sdo.rx_cobid
        self.net.send_message = counted
        self.rates: list[tuple[int, int, int]] = []
        self.first_pdo = threading.Event()
        self.net.subscribe(0x1B8, self._gyro)
        self.threads = [threading.Thread(target=self._heartbeat), threading.Thread(target=self._law)]
        for t in self.threads:
            t.start()

    def _gyro(self, _id: int, data: bytes, _t: float) -> None:
        self.rates.append(tuple(int.from_bytes(data[i:i + 2], 'little', signed=True) for i in (0, 2, 4)))
        self.first_pdo.set()

    def _heartbeat(self) -> None:
        while not self.stop.wait(0.1):
            try:
                self.net.send_message(0x701, b'\x05')
            except (can.CanError, OSError):
                return  # the run ended and took the bus with it

    def _law(self) -> None:
        seen = 0
        while not self.stop.wait(0.005):
            if len(self.rates) == seen:
                continue
            seen = len(self.rates)
            for sub, w in zip((4, 5, 6), self.rates[-1], strict=True):
                try:
                    self.adcs.sdo.download(0x4007, sub, int(max(-100_000, min(100_000, -GAIN_UA_PER_MRAD_S * w)))
                                           .to_bytes(4, 'little', signed=True))
                    self.writes += 1
                except canopen.SdoCommunicationError:
                    self.timeouts += 1  # a reply later than the client's timeout on a loaded machine: try the next
                except (can.CanError, OSError):
                    return  # the run ended and took the bus with it

    def close(self) -> None:
        self.stop.set()
        for t in self.threads:
            t.join()
        try:
            self.net.disconnect()  # re-raises what its receive thread met: the hub closing with the run
        except (can.CanError, OSError):
            pass  # the run ended and took the bus with it (a reset when the hub closed with frames unread)


def _run(tmp: Path, name: str, *extra: str) -> subprocess.Popen:
    env = {**os.environ, 'ACDS_WORKSPACE': str(tmp)}
    return subprocess.Popen([*ACDS, 'run', 'oresat_c3_detumble', '--engine', 'direct', '--steps', str(STEPS),
                             '--no-record', '--run-dir', str(tmp / name), '--summary-json', str(tmp / f'{name}.json'),
                             *extra], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def test_a_scripted_master_flies_the_cards_and_the_replay_gives_the_same_truth(tmp_path):
    run = _run(tmp_path, 'live', '--rtf', str(RTF), '--can-port', '0')  # a free port, read from what the run prints
    lines: list[str] = []
    waiting = threading.Event()

    def read() -> None:
        for line in run.stdout:
            lines.append(line)
            if 'waiting up to' in line:
                waiting.set()
    reader = threading.Thread(target=read)
    reader.start()
    assert waiting.wait(60), 'the run never said it waits for the heartbeat:\n' + ''.join(lines)
    port = int(re.search(r'CAN bus \(socketcand protocol\) on 127\.0\.0\.1:(\d+)', ''.join(lines)).group(1))
    master = Master(port)
    # Bad input on the live bus: a malformed line (the hub names it), a frame for a COB-ID the ADCS card does not
    # serve (0x238: an RPDO it has not), a frame in the ADCS card's own heartbeat COB-ID (a node id claimed twice).
    # Sent once the cards are on the bus (the master has their first gyro TPDO).
    rogue = socket.create_connection(('127.0.0.1', port), timeout=5.0)
    rogue.sendall(b'< open vcan0 >< rawmode >')
    assert master.first_pdo.wait(60), 'no gyro TPDO from the cards:\n' + ''.join(lines)
    rogue.sendall(b'< send 7FF 9 0 >< send 238 1 1 >< send 738 1 5 >')
    try:
        run.wait(timeout=120)
    finally:
        master.close()
        rogue.close()
        reader.join()
    out = ''.join(lines)
    assert run.returncode == 0, out
    assert f'CAN bus (socketcand protocol) on 127.0.0.1:{port}' in out and 'flight computer heartbeat after' in out
    live = json.loads((tmp_path / 'live.json').read_text())
    # The master's setpoints drove the rods: they changed, the largest was clamped at the rods' 69.44 mA.
    assert master.writes > 20 and live['can_setpoint_changes'] > 0, (master.writes, master.timeouts, out)
    assert live['can_peak_setpoint_ma'] == pytest.approx(69.44, abs=1e-6)
    assert 'clamped at the limit' in out
    assert "bad line '< send 7FF 9 0 >' (length 9 outside 0..8)" in out
    assert 'COB-ID 0x238 is addressed to emulated device adcs' in out and 'COB-ID 0x738, which is emulated' in out
    assert live['peak_current_ma'] > 10.0
    assert live['can_sensor_lateness_ms']['p50'] < 1e3 * 0.1 / RTF
    assert live['can_sdo_latency_ms'] is not None and live['can_setpoint_age_ms'] is not None
    # The log: python-can reads it, its sidecar has one step per frame.
    log = tmp_path / 'live' / 'can.asc'
    frames = list(can.LogReader(str(log)))
    rows = (tmp_path / 'live' / 'can.asc.steps.csv').read_text().splitlines()
    assert len(rows) == len(frames) + 1
    # Every SDO request the cards answered is in the log, and nothing the master did not send; the download the run
    # ended on may be missing (its request, its retry, its abort: loaded CI logged 91 against 90 answered).
    logged = sum(f.arbitration_id == master.adcs.sdo.rx_cobid for f in frames)
    assert master.writes <= logged <= master.sdo_frames <= logged + 3, (master.writes, logged, master.sdo_frames)
    # Replay without the flight computer: the same truth, bit for bit; without the setpoints it differs.
    replay = _run(tmp_path, 'replay', '--replay-can', str(log))
    out2, _ = replay.communicate(timeout=120)
    assert replay.returncode == 0, out2
    assert f'heartbeat watched in the steps of R = {RTF:g}' in out2  # the recorded run's, from can.asc.run.json
    again = json.loads((tmp_path / 'replay.json').read_text())
    assert again['truth_digest'] == live['truth_digest']
    assert again['can_setpoint_changes'] == live['can_setpoint_changes']
    off = DirectRun(load_scenario('oresat_c3_detumble'), steps=STEPS).run().summary  # off the bus: setpoints 0
    assert off['truth_digest'] != live['truth_digest'] and off['peak_current_ma'] == 0.0


def test_bad_bus_options_are_one_line_and_exit_2(tmp_path):
    env = {**os.environ, 'ACDS_WORKSPACE': str(tmp_path)}
    kernel = tmp_path / 'kernel_can.yaml'
    kernel.write_text(f'extends: {ROOT / "scenarios" / "oresat_c3_detumble.yaml"}\nname: kernel_can\n'
                      'can_bus:\n  interface: socketcan\n  channel: nosuchcan7\n')
    (tmp_path / 'map.yaml').write_text('devices:\n  adcs:\n    dictionary: oresat1/adcs\n    objects:\n      - {index: 0x4000, '
                                       'subs: [1, 2, 3], quantity: body_rate, si_per_count: 1.0e-4, unit: rad/s, '
                                       'full_scale: 8.73}\n')
    misfit = tmp_path / 'misfit.yaml'
    misfit.write_text(f'extends: {ROOT / "scenarios" / "oresat_c3_detumble.yaml"}\nname: misfit\n'
                      'can_bus:\n  mapping: map.yaml\n')
    for args, needle in ((['heao_b_acquisition_short', '--can-port', '1234'], 'has no CAN bus'),
                         ([str(kernel)], 'this machine has no network interface nosuchcan7'),
                         ([str(misfit)], '0x4000:1 holds -32768..32767 counts; full_scale 8.73 rad/s'),
                         (['oresat_c3_detumble', '--replay-can', str(tmp_path / 'none.asc')], 'no such file'),
                         (['oresat_c3_detumble', '--can-port', '70000'], 'not a TCP port')):
        r = subprocess.run([*ACDS, 'run', *args, '--engine', 'direct', '--no-record'], env=env, capture_output=True,
                           text=True, timeout=60)
        assert r.returncode == 2 and needle in r.stderr, r.stderr
        assert len(r.stderr.strip().splitlines()) == 1, r.stderr


@pytest.mark.skipif(not Path('/sys/class/net/vcan0').exists(),
                    reason='no SocketCAN interface vcan0 on this machine (ip link add dev vcan0 type vcan is refused here)')
def test_the_cards_on_a_kernel_can_interface(tmp_path):
    kernel = tmp_path / 'kernel_can.yaml'
    kernel.write_text(f'extends: {ROOT / "scenarios" / "oresat_c3_detumble.yaml"}\nname: kernel_can\n'
                      'input_timeout_s: 5\ncan_bus:\n  interface: socketcan\n  channel: vcan0\n')
    bus = can.Bus(interface='socketcan', channel='vcan0')
    stop = threading.Event()
    beat = threading.Thread(target=lambda: [bus.send(can.Message(arbitration_id=0x701, data=[5], is_extended_id=False))
                                            for _ in iter(lambda: stop.wait(0.1), True)])
    beat.start()
    try:
        r = subprocess.run([*ACDS, 'run', str(kernel), '--engine', 'direct', '--steps', '30', '--rtf', '10',
                            '--no-record', '--run-dir', str(tmp_path / 'run')], capture_output=True, text=True,
                           timeout=120, env={**os.environ, 'ACDS_WORKSPACE': str(tmp_path)})
    finally:
        stop.set()
        beat.join()
        bus.shutdown()
    assert r.returncode == 0, r.stderr
    assert 'the kernel interface vcan0' in r.stderr and 'flight computer heartbeat after' in r.stderr
    assert any(f.arbitration_id == 0x1B8 for f in can.LogReader(str(tmp_path / 'run' / 'can.asc')))


def test_a_flight_computer_that_never_comes_fails_the_run_in_one_line_when_the_scenario_says_so(tmp_path):
    never = tmp_path / 'never.yaml'
    never.write_text(f'extends: {ROOT / "scenarios" / "oresat_c3_detumble.yaml"}\nname: never\ninput_timeout_s: 0.5\n'
                     'can_bus:\n  on_heartbeat_loss: fail\n')
    r = subprocess.run([*ACDS, 'run', str(never), '--engine', 'direct', '--steps', '5', '--no-record', '--can-port', '0',
                        '--run-dir', str(tmp_path / 'run')], capture_output=True, text=True, timeout=120,
                       env={**os.environ, 'ACDS_WORKSPACE': str(tmp_path)})
    assert r.returncode == 1, r.stderr
    failed = [line for line in r.stderr.splitlines() if 'run failed' in line]
    assert len(failed) == 1 and 'no heartbeat from the flight computer (node 0x01, COB-ID 0x701) within 0.5 s' in failed[0]
    assert 'clients on the bus: none' in failed[0]
