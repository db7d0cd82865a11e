"""The OreSat detumble flight software as a plain CANopen master: the seed 003 law over the ADCS card's bus.

The same law as the ROS node (:mod:`oresat_detumble_fsw.law`: M = −(k_ω/|B|²)(B × ω), saturated per axis), fed
the way OreSat's flight computer is fed (spec §13): python-can's ``socketcand`` bus to a hub, the ADCS card (node
0x38, its dictionary oresat-configs' ``oresat1`` ``adcs``) sends the gyro (TPDO 1, COB-ID 0x1B8) and the four
magnetometers (TPDOs 4–7, 0x4B8, 0x1B9, 0x2B9, 0x3B9) as int16 counts; this master decodes them with the TPDO
mappings of that dictionary, scales them with the card firmware's units (``--gyro-per-count`` rad/s,
``--field-per-count`` T), averages the four magnetometers as the C3 does, and once a full set has come (one gyro
and four magnetometer frames, the card's sampling period) computes the dipole, turns it into coil currents with
the coils' current-to-dipole factors (``--dipole-per-amp``, A·m²/A per axis) and writes the three
``magnetorquer`` ``current_{x,y,z}_setpoint`` objects (0x4007 sub 4–6, int32 µA) by expedited SDO download, one
after the other, as the C3 does. Its heartbeat (node ``--node-id``, 0x01 by default) goes out every second.

    oresat_detumble_canopen --host 127.0.0.1 --port 29536 --orbit-period 5560.8 --inclination 0.90129 \\
        --j-min 0.00509404743 --max-moment 0.1552 --dipole-per-amp 2.2349 2.2349 3.7623

It runs until SIGINT/SIGTERM or ``--seconds``; on stop it prints one JSON line: sets computed, setpoints written,
SDO failures.
"""

from __future__ import annotations

import argparse
import json
import logging
import signal
import struct
import sys
import threading

from oresat_detumble_fsw.law import detumble_gain, detumble_moment

#: The ADCS card's node id, the magnetorquer object and its setpoint subs (oresat-configs oresat1 adcs).
ADCS_NODE_ID = 0x38
MAGNETORQUER = 0x4007
SETPOINT_SUBS = (4, 5, 6)
GYROSCOPE = 0x4000
MAGNETOMETERS = (0x4003, 0x4004, 0x4005, 0x4006)
#: µA per A: the setpoint objects count microamperes.
UA_PER_A = 1e6
INT32 = (-(1 << 31), (1 << 31) - 1)


def sensor_layout(od) -> dict[int, tuple[int, str]]:
    """COB-ID → (object index, struct format) for the ADCS card's gyro and magnetometer TPDOs, from its dictionary."""
    layout = {}
    for n in range(0x1800, 0x1A00):
        if n not in od or n + 0x200 not in od:
            continue
        mapping = od[n + 0x200]
        entries = [mapping[j].default for j in range(1, mapping[0].default + 1)]
        indices = {e >> 16 for e in entries}
        if len(indices) != 1 or (index := indices.pop()) not in (GYROSCOPE, *MAGNETOMETERS):
            continue
        if any(e & 0xFF != 16 for e in entries) or len(entries) != 3:
            raise ValueError(f'TPDO {n - 0x1800 + 1} of object {index:#06x} is not three int16: {entries}')
        layout[od[n][1].default & 0x7FF] = (index, '<hhh')
    missing = {GYROSCOPE, *MAGNETOMETERS} - {i for i, _ in layout.values()}
    if missing:
        raise ValueError(f'no TPDO maps object(s) {sorted(hex(i) for i in missing)}')
    return layout


class DetumbleMaster:
    """Collects one sensor set from the ADCS card's PDOs and answers it with three setpoint SDOs."""

    def __init__(self, network, od, k_omega: float, max_moment_am2: float, dipole_per_amp: tuple[float, float, float],
                 gyro_per_count: float, field_per_count: float) -> None:
        import canopen

        self.k_omega = k_omega
        self.max_moment = max_moment_am2
        self.dipole_per_amp = dipole_per_amp
        self.gyro_per_count = gyro_per_count
        self.field_per_count = field_per_count
        self.layout = sensor_layout(od)
        self.card = network.add_node(canopen.RemoteNode(ADCS_NODE_ID, od))
        self.latest: dict[int, tuple[int, int, int]] = {}
        self.ready = threading.Condition()
        self.stats = {'sets': 0, 'setpoints': 0, 'sdo_failures': 0}
        for cob_id in self.layout:
            network.subscribe(cob_id, self._on_pdo)

    def _on_pdo(self, cob_id: int, data: bytes, _timestamp: float) -> None:
        index, fmt = self.layout[cob_id]
        with self.ready:
            self.latest[index] = struct.unpack(fmt, bytes(data[:6]))
            if len(self.latest) == len(self.layout):
                self.ready.notify()

    def take_set(self, timeout_s: float) -> dict[int, tuple[int, int, int]] | None:
        """The next complete sensor set (gyro and four magnetometers), or None after ``timeout_s``."""
        with self.ready:
            if not self.ready.wait_for(lambda: len(self.latest) == len(self.layout), timeout_s):
                return None
            got, self.latest = self.latest, {}
            return got

    def setpoints_ua(self, sensors: dict[int, tuple[int, int, int]]) -> tuple[int, int, int]:
        """The law on one sensor set: field = mean of the four magnetometers; dipole → µA per axis."""
        omega = tuple(c * self.gyro_per_count for c in sensors[GYROSCOPE])
        b = tuple(sum(sensors[m][k] for m in MAGNETOMETERS) / len(MAGNETOMETERS) * self.field_per_count
                  for k in range(3))
        moment = detumble_moment(b, omega, self.k_omega, self.max_moment)
        out = []
        for m, per_amp in zip(moment, self.dipole_per_amp, strict=True):
            ua = round(m / per_amp * UA_PER_A)
            out.append(min(max(ua, INT32[0]), INT32[1]))
        return tuple(out)

    def fly(self, stop: threading.Event) -> None:
        """Sense, compute, write, until ``stop``."""
        while not stop.is_set():
            sensors = self.take_set(0.5)
            if sensors is None:
                continue
            self.stats['sets'] += 1
            for sub, ua in zip(SETPOINT_SUBS, self.setpoints_ua(sensors), strict=True):
                try:
                    self.card.sdo.download(MAGNETORQUER, sub, struct.pack('<i', ua))
                    self.stats['setpoints'] += 1
                except Exception:  # noqa: BLE001 — an SDO abort or timeout is counted, the loop flies on
                    self.stats['sdo_failures'] += 1


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog='oresat_detumble_canopen', description=__doc__.split('\n\n')[0])
    p.add_argument('--host', default='127.0.0.1', help='socketcand hub host')
    p.add_argument('--port', type=int, default=29536, help='socketcand hub port')
    p.add_argument('--channel', default='vcan0', help='socketcand channel name')
    p.add_argument('--node-id', type=int, default=1, help='this master’s node id (heartbeat 0x700 + id)')
    p.add_argument('--orbit-period', type=float, required=True, help='T_orb, s')
    p.add_argument('--inclination', type=float, required=True, help='ξ, rad')
    p.add_argument('--j-min', type=float, required=True, help='J_min, kg·m²')
    p.add_argument('--max-moment', type=float, required=True, help="the rods' moment (per-axis saturation), A·m²")
    p.add_argument('--dipole-per-amp', type=float, nargs=3, required=True, metavar=('X', 'Y', 'Z'),
                   help="the coils' current-to-dipole factors, A·m²/A")
    p.add_argument('--gyro-per-count', type=float, default=1e-3, help='rad/s per gyro count (card firmware: 1e-3)')
    p.add_argument('--field-per-count', type=float, default=1e-7, help='T per magnetometer count (1 mG = 1e-7 T)')
    p.add_argument('--seconds', type=float, default=None, help='stop after this many seconds')
    return p


def main(argv: list[str] | None = None) -> int:
    import canopen
    from oresat_configs import OreSatConfig

    args = build_parser().parse_args(argv)
    # python-can's socketcand client warns of every TCP read that splits a frame (it keeps the rest and goes on).
    logging.getLogger('can.interfaces.socketcand').setLevel(logging.ERROR)
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, lambda *_a: stop.set())
    od = OreSatConfig('oresat1').od_db['adcs']
    network = canopen.Network()
    network.connect(interface='socketcand', channel=args.channel, host=args.host, port=args.port)
    try:
        k_omega = detumble_gain(args.orbit_period, args.inclination, args.j_min)
        master = DetumbleMaster(network, od, k_omega, args.max_moment, tuple(args.dipole_per_amp),
                                args.gyro_per_count, args.field_per_count)
        heartbeat = network.send_periodic(0x700 + args.node_id, b'\x05', 1.0)
        if args.seconds is not None:
            threading.Timer(args.seconds, stop.set).start()
        master.fly(stop)
        heartbeat.stop()
    finally:
        network.disconnect()
    print(json.dumps({'k_omega': k_omega, **master.stats}), flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
