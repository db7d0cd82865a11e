"""canopen_cards stepper: the emulated CANopen cards, the lockstep graph's wall-clock edge (spec §13).

Stage ``exchange`` of step k, in this order:

1. paced (on the bus): waits until the step's wall time t_wall(0) + t_k / R (R: ``can_bus.rtf``);
2. samples the bus: every frame that came in since step k − 1's sample (already applied to the devices'
   dictionaries: SDO replies go out at once, like a card's) is taken in *at step k* (sample and hold), its
   step recorded; in a replay (``can_bus.replay_can``) the recorded frames of step k are applied instead;
3. reads the actuator objects (the rods' current setpoints, A) → clamps each at the driver's limit
   (``setpoint_limit``; counted, named once per axis) → the moment command of step k, dipole_per_amp × I;
4. writes the sensor objects from the truth of step k (body rate; each magnetometer through its mounting
   and noise; the ECEF position and velocity from the truth orbit; the rods' current and duty of step k − 1),
   quantised to counts, saturating at the objects' limits;
5. sends what is due at t_k: the heartbeat, and the TPDOs at their periods; records the wall lateness.

Off the bus (no ``can_bus.endpoint``, as in the truth-digest test and sweeps) the cards still compute every
object but send nothing and are not paced, and the setpoints keep their dictionary values (0 µA).
The flight computer's heartbeat (node ``flight_computer_node_id``) is watched in steps: none sampled for
``heartbeat_timeout`` (wall, × R in sim time) is named with the step, and ``on_heartbeat_loss`` fails the run
or flies on with the setpoints held.
"""

from __future__ import annotations

import math
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
from acds_common import units
from acds_common.messages import ERROR, OK, WALL_CLOCK_PREFIX, WARN, diagnostic
from acds_common.stepper import StepError, Stepper
from acds_common.timing import StepTimes

from canopen_bus.canlog import CanLog, CanLogError, read_replay
from canopen_bus.device import EmulatedDevice
from canopen_bus.dictionary import DictionaryError
from canopen_bus.mapping import IDENTITY, DeviceMap, ObjectMap, load_mapping

NAN3 = (math.nan, math.nan, math.nan)


def ecef_state(r_eci: tuple, v_eci: tuple, greenwich_rad: float) -> tuple[tuple, tuple]:
    """ECI position (m) and velocity (m/s) → ECEF, the Earth turned by the Greenwich angle (spec §3)."""
    c, s = math.cos(greenwich_rad), math.sin(greenwich_rad)
    w = units.EARTH_RATE_RAD_S
    rx, ry, rz = r_eci
    vx, vy, vz = v_eci[0] + w * ry, v_eci[1] - w * rx, v_eci[2]  # v − ω_E ẑ × r
    return (c * rx + s * ry, -s * rx + c * ry, rz), (c * vx + s * vy, -s * vx + c * vy, vz)


class CardsStep(Stepper):
    """The devices of the mapping, on the bus at ``can_bus.endpoint`` (or replayed, or off the bus)."""

    node = 'canopen_cards'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        cfg = self.cfg = self.section('can_bus')
        try:
            self.maps: tuple[DeviceMap, ...] = load_mapping(Path(cfg['mapping']))
        except DictionaryError as exc:
            raise StepError(str(exc)) from None
        self.greenwich0 = self.section('earth')['greenwich_angle0']
        self.rtf = cfg['rtf']
        self.on_bus = bool(cfg['endpoint']) and not cfg['replay_can']
        try:
            self.replay = read_replay(Path(cfg['replay_can'])) if cfg['replay_can'] else None
        except CanLogError as exc:
            raise StepError(str(exc)) from None
        self.lock = threading.RLock()
        self.devices: dict[str, EmulatedDevice] = {}
        for m in self.maps:
            dev = EmulatedDevice(m.name, m.od, m.node_id, self._send, m.tpdo_period_s)
            dev.lock = self.lock
            dev.on_malformed = self._malformed
            self.devices[m.name] = dev
        self.own_ids = {cid: name for name, d in self.devices.items()
                        for cid in (0x580 + d.node_id, 0x700 + d.node_id, *(p.cob_id for p in d.tpdos))}
        #: (device, object, per-subindex encoder) of every sensor object, in mapping order.
        self._sensor_objects = [(self.devices[m.name], o, [m.od[o.index][sub].encode_raw for sub in o.subs])
                                for m in self.maps for o in m.objects if not o.command]
        self.rng = {(m.name, o.index): np.random.default_rng([self.seed, m.node_id, o.index])
                    for m in self.maps for o in m.objects}
        self.k_am2_per_a = cfg['dipole_per_amp']
        self.limit_a = cfg['setpoint_limit']
        self.fc_id = cfg['flight_computer_node_id']
        self.hb_steps = max(1, math.ceil(cfg['heartbeat_timeout'] * self.rtf / self.control_period_s))
        self.journal: list[list] = []
        self.bus = None
        self.notifier = None
        self.canlog = CanLog(Path(cfg['can_log']), self.rtf) if cfg['can_log'] and self.on_bus else None
        self.wall0: float | None = None
        self.step_now = -1
        self.last_hb_step: int | None = None
        self.hb_lost = False
        self.clamped: set[int] = set()
        self.clamp_count = 0
        self.claimed: set[int] = set()
        self.lateness = StepTimes()
        self.sdo_latency = StepTimes()
        self.setpoint_age = StepTimes()
        self.late_steps: list[int] = []
        #: COB-IDs that carry the flight computer's commands to the cards: SDO requests and RPDOs.
        self._command_rx = {cid for d in self.devices.values() for cid in (0x600 + d.node_id, *(p.cob_id for p in d.rpdos))}
        self._node_ids = {d.node_id: name for name, d in self.devices.items()}
        self.unknown: set[int] = set()
        self.unknown_frames = 0
        self.last_write_step: int | None = None
        self.writes_stopped = False
        self._fault_pending = cfg['fault'] != 'none'
        self._fault_sensor: tuple[str, int, tuple[int, ...]] | None = None  # (device, index, axes) once active
        self._stuck: dict[int, int] = {}
        if self.on_bus:  # on the bus before the first step (its handshake is not the first step's time)
            self._connect()

    # -- the bus ----------------------------------------------------------------------------------------
    def _connect(self) -> None:
        import can
        kind, _, where = self.cfg['endpoint'].partition(':')
        try:
            if kind == 'socketcan':  # a kernel interface (can_bus.interface: socketcan)
                self.bus = can.Bus(interface='socketcan', channel=where)
            else:
                host, _, port = where.rpartition(':')
                self.bus = can.Bus(interface='socketcand', channel='vcan0', host=host, port=int(port))
        except (OSError, ValueError, can.CanError, TimeoutError) as exc:
            raise StepError(f'canopen_cards: cannot join the CAN bus at {self.cfg["endpoint"]}: {exc}') from None
        self.notifier = can.Notifier(self.bus, [self._on_message], timeout=0.1)

    def _on_message(self, msg: Any) -> None:
        """A frame from the bus (the notifier's thread): journaled, then applied to every device."""
        if msg.is_error_frame or msg.is_remote_frame:
            return
        with self.lock:
            cid, data = msg.arbitration_id, bytes(msg.data)
            self.journal.append([msg.timestamp, cid, data, True, None])
            if cid in self.own_ids and cid not in self.claimed:
                self.claimed.add(cid)
                self.log('warn', f'another client sends COB-ID 0x{cid:03X}, which is emulated device '
                                 f'{self.own_ids[cid]}\'s (a node id claimed twice), first near step {self.step_now}')
            elif cid not in self.own_ids and cid not in self._command_rx and cid & 0x7F in self._node_ids \
                    and cid > 0x80:
                self.unknown_frames += 1
                if cid not in self.unknown:
                    self.unknown.add(cid)
                    self.log('warn', f'COB-ID 0x{cid:03X} is addressed to emulated device '
                                     f'{self._node_ids[cid & 0x7F]} (node 0x{cid & 0x7F:02X}), which serves no such '
                                     f'object: ignored and counted, first near step {self.step_now}')
            for dev in self.devices.values():
                dev.receive(cid, data, msg.timestamp)

    def _malformed(self, line: str) -> None:
        self.log('warn', f'{line} (near step {self.step_now})')

    def _send(self, can_id: int, data: bytes) -> None:
        """A frame from a device (with :attr:`lock` held): journaled; on the bus when there is one."""
        wall = time.time()
        self.journal.append([wall, can_id, data, False, None])
        if self.bus is not None:
            import can
            self.bus.send(can.Message(arbitration_id=can_id, data=data, is_extended_id=False))

    # -- the step ---------------------------------------------------------------------------------------
    def exchange(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        events: list[str] = []
        target = None
        if self.on_bus:
            if self.wall0 is None:
                self.wall0 = time.time()
            target = self.wall0 + t_s / self.rtf
            delay = target - time.time()
            if delay > 0:
                time.sleep(delay)  # pacing to the wall clock (the cards are the wall-clock edge), not a sync wait
        with self.lock:
            sample_wall = time.time()
            self.step_now = k
            if self.replay is not None:
                for wall, cid, data in self.replay.get(k, ()):
                    self.journal.append([wall, cid, data, True, None])
                    for dev in self.devices.values():
                        dev.receive(cid, data, wall)
            taken = []
            for dev in self.devices.values():
                taken += dev.take_pending()
            for entry in self.journal:
                if entry[4] is None:
                    entry[4] = k
            events += self._heartbeat(k, taken)
            events += self._writes(k, taken)
            ages = [sample_wall - w for w, cid, _d in taken if cid in self._command_rx] if self.on_bus else []
            for age in ages:
                self.setpoint_age.add(k, age)
            if self._fault_pending and t_s >= self.cfg['fault_time']:
                events.append(self._inject_fault(k, t_s))
            setpoint = self._setpoints(events)
            sent = self._sensors(k, t_s, inp)
            if k == 0:
                for dev in self.devices.values():
                    dev.boot()
            for dev in self.devices.values():
                dev.tick(t_s)
            for entry in self.journal:
                if entry[4] is None:
                    entry[4] = k
            self._flush()
            lat_sdo = []
            for dev in self.devices.values():
                lat_sdo += dev.sdo.latencies_s
                dev.sdo.latencies_s = []
        lateness = math.nan
        if target is not None:
            lateness = sample_wall - target
            self.lateness.add(k, lateness)
            if lateness > self.control_period_s / self.rtf:
                self.late_steps.append(k)
        for v in lat_sdo:
            self.sdo_latency.add(k, v)
        moment = tuple(self.k_am2_per_a[i] * setpoint[i] for i in range(3))
        out: dict[str, Any] = {
            'command': moment,
            'setpoint': setpoint,
            'body_rate': sent.get('body_rate', NAN3),
            'magnetic_field': sent.get('magnetic_field', NAN3),
            'ecef_position': sent.get('ecef_position', NAN3),
            'timing': (lateness, max(lat_sdo) if lat_sdo else math.nan, max(ages) if ages else math.nan),
        }
        if events or (self.telemetry_wanted and k % self.cfg['telemetry_every'] == 0):
            out['diagnostics'] = self._telemetry(events)
            for line in events:
                self.log('warn' if any(w in line for w in ('lost', 'clamped', 'stopped', 'fault')) else 'info', line)
        return out

    def _heartbeat(self, k: int, taken: list) -> list[str]:
        """The flight computer's heartbeat, watched in steps (the same in a replay)."""
        if not (self.on_bus or self.replay is not None):
            return []
        hb = 0x700 + self.fc_id
        if any(cid == hb for _w, cid, _d in taken):
            if self.hb_lost:
                self.hb_lost = False
                return [f'flight computer 0x{self.fc_id:02X}: heartbeat back at step {k} (t={self.step_time_s(k):g} s)']
            self.last_hb_step = k
            return []
        since = self.last_hb_step if self.last_hb_step is not None else 0
        if not self.hb_lost and k - since > self.hb_steps:
            self.hb_lost = True
            last = 'none yet' if self.last_hb_step is None else f'last at step {self.last_hb_step}'
            line = (f'flight computer 0x{self.fc_id:02X}: heartbeat lost at step {k} (t={self.step_time_s(k):g} s; '
                    f'{last}, timeout {self.cfg["heartbeat_timeout"]:g} s)')
            if self.cfg['on_heartbeat_loss'] == 'fail':
                raise StepError(line + '; can_bus.on_heartbeat_loss: fail')
            return [line + '; flying on with the setpoints held']
        return []

    def _writes(self, k: int, taken: list) -> list[str]:
        """Whether the flight computer stopped (or resumed) its SDO requests to the cards, named with the step."""
        if any(cid in self._command_rx for _w, cid, _d in taken):
            line = [] if self.last_write_step is None or not self.writes_stopped else [
                f'flight computer resumed its SDO requests at step {k} (t={self.step_time_s(k):g} s)']
            self.last_write_step, self.writes_stopped = k, False
            return line
        if self.last_write_step is not None and not self.writes_stopped and k - self.last_write_step > self.hb_steps:
            self.writes_stopped = True
            beat = 'lost too' if self.hb_lost else 'still on'
            return [f'flight computer stopped its SDO requests (setpoints): none since step {self.last_write_step} '
                    f'(t={self.step_time_s(self.last_write_step):g} s), named at step {k}; its heartbeat is {beat}']
        return []

    def _inject_fault(self, k: int, t_s: float) -> str:
        """Start the scenario's bus fault at step k; the line that names it."""
        self._fault_pending = False
        c = self.cfg
        dev = self.devices[c['fault_device']]
        kind = c['fault']
        if kind == 'stop_pdos':
            dev.silenced = True
        elif kind == 'sdo_lost':
            dev.sdo_lost = True
        elif kind == 'sdo_delay':
            dev.sdo_delay_s = c['fault_delay']
        else:
            axes = (0, 1, 2) if kind == 'dead_sensor' else (c['fault_axis'],)
            self._fault_sensor = (dev.name, c['fault_object'], axes)
        what = {'stop_pdos': 'stops sending its TPDOs (heartbeat and SDO go on)', 'sdo_lost': 'drops its SDO replies',
                'sdo_delay': f'replies to SDO {c["fault_delay"] * 1e3:g} ms late (wall)',
                'zero_axis': f'object 0x{c["fault_object"]:04X} reads 0 on axis {c["fault_axis"]}',
                'stuck_axis': f'object 0x{c["fault_object"]:04X} holds its axis {c["fault_axis"]} value',
                'dead_sensor': f'object 0x{c["fault_object"]:04X} reads 0 on every axis'}[kind]
        return f'bus fault at step {k} (t={t_s:g} s): device {dev.name} {what}'

    def _objects(self, quantity: str) -> list[tuple[EmulatedDevice, ObjectMap]]:
        return [(self.devices[m.name], o) for m in self.maps for o in m.objects if o.quantity == quantity]

    def _setpoints(self, events: list[str]) -> tuple[float, float, float]:
        """The held current setpoints (A, per axis), clamped at the driver's limits."""
        out = [0.0, 0.0, 0.0]
        for dev, o in self._objects('coil_current_setpoint'):
            for axis, sub in enumerate(o.subs):
                amps = dev.get_raw(o.index, sub) * o.si_per_count
                limit = self.limit_a[axis]
                if abs(amps) > limit:
                    self.clamp_count += 1
                    if axis not in self.clamped:
                        self.clamped.add(axis)
                        events.append(f'{dev.name} 0x{o.index:04X}:{sub}: setpoint {amps * 1e3:.3f} mA outside the '
                                      f'driver\'s ±{limit * 1e3:.3f} mA, clamped at the limit (named once per axis; '
                                      f'counted in the summary)')
                    amps = math.copysign(limit, amps)
                out[axis] = amps
        return (out[0], out[1], out[2])

    def _quantity(self, quantity: str, t_s: float, inp: dict[str, Any]) -> tuple[float, float, float] | None:
        odom = inp.get('odometry')
        if quantity == 'body_rate':
            return None if odom is None else tuple(odom.angular)
        if quantity == 'magnetic_field':
            return None if inp.get('b_true') is None else tuple(inp['b_true'][0])
        if quantity == 'sensed_magnetic_field':  # magnetometer_sim's, its faults included
            return None if inp.get('sensed_field') is None else tuple(inp['sensed_field'][0])
        if quantity in ('ecef_position', 'ecef_velocity'):
            if odom is None:
                return None
            r, v = ecef_state(odom.position, odom.velocity, self.greenwich0 + units.EARTH_RATE_RAD_S * t_s)
            return r if quantity == 'ecef_position' else v
        if quantity == 'coil_current':
            d = inp.get('dipole')
            return None if d is None else tuple(d[i] / self.k_am2_per_a[i] for i in range(3))
        if quantity == 'coil_duty':
            return None if inp.get('duty') is None else tuple(inp['duty'])
        return None

    def _sensors(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, tuple]:
        """Write every sensor object from the truth of step k; {quantity: the SI value sent (mean over objects)}."""
        sums: dict[str, list] = {}
        values: dict[str, Any] = {}
        for dev, o, packers in self._sensor_objects:
            if o.quantity not in values:
                values[o.quantity] = self._quantity(o.quantity, t_s, inp)
            value = values[o.quantity]
            if value is None:
                continue
            if o.mounting is not IDENTITY:
                value = [sum(m * v for m, v in zip(row, value, strict=True)) for row in o.mounting]
            if o.noise_std > 0:
                value = [v + n for v, n in zip(value, self.rng[(dev.name, o.index)].normal(0.0, o.noise_std, 3).tolist(),
                                               strict=True)]
            store = dev.node.data_store.setdefault(o.index, {})
            sent = []
            fault = self._fault_sensor is not None and self._fault_sensor[:2] == (dev.name, o.index)
            for axis, ((lo, hi), sub, encode, v) in enumerate(zip(o.limits, o.subs, packers, value, strict=True)):
                counts = min(hi, max(lo, round(v / o.si_per_count)))
                if fault and axis in self._fault_sensor[2]:
                    counts = self._stuck.setdefault(axis, counts) if self.cfg['fault'] == 'stuck_axis' else 0
                store[sub] = encode(counts)
                sent.append(counts * o.si_per_count)
            acc = sums.setdefault(o.quantity, [0.0, 0.0, 0.0, 0])
            acc[0] += sent[0]
            acc[1] += sent[1]
            acc[2] += sent[2]
            acc[3] += 1
        return {q: (a[0] / a[3], a[1] / a[3], a[2] / a[3]) for q, a in sums.items()}

    def _flush(self) -> None:
        if self.canlog is not None:
            for wall, cid, data, rx, step in self.journal:
                self.canlog.write(step, wall, cid, data, rx)
        self.journal = []

    def _telemetry(self, events: list[str]) -> Any:
        level, message = OK, 'ok'
        if self.hb_lost:
            level, message = WARN, f'flight computer 0x{self.fc_id:02X} heartbeat lost'
        if any('fail' in e for e in events):
            level = ERROR
        values: dict[str, object] = {
            'mode': 'on the bus' if self.on_bus else 'replay' if self.replay is not None else 'off the bus',
            'sdo_requests': sum(d.sdo.requests for d in self.devices.values()),
            'sdo_aborts': sum(sum(d.sdo.aborts.values()) for d in self.devices.values()),
            'sdo_replies_dropped': sum(d.sdo_dropped for d in self.devices.values()),
            'last_setpoint_request_step': self.last_write_step if self.last_write_step is not None else 'none',
            'setpoints_clamped': self.clamp_count,
            'unknown_cob_id_frames': self.unknown_frames,
            'malformed_frames': sum(d.malformed for d in self.devices.values()),
            f'{WALL_CLOCK_PREFIX}late_steps': len(self.late_steps),
        }
        for name, times in (('sensor_lateness', self.lateness), ('sdo_latency', self.sdo_latency),
                            ('setpoint_age', self.setpoint_age)):
            if times.count:  # wall-clock keys: the machine's, not the data's (digests and compare leave them out)
                values.update({f'{WALL_CLOCK_PREFIX}{name}_{q}': f'{v:.3f}' for q, v in times.report().items()
                               if q != 'steps'})
        values.update({f'event_{i}': e for i, e in enumerate(events)})
        return diagnostic(self.node, values, message, level)

    def close(self) -> None:
        """Leave the bus and close the log (the host calls it at the run's end)."""
        if self.notifier is not None:
            self.notifier.stop()
        if self.bus is not None:
            self.bus.shutdown()
        with self.lock:  # frames that came after the last step's sample: logged, applied at no step (-1)
            for entry in self.journal:
                if entry[4] is None:
                    entry[4] = -1
            self._flush()
        if self.canlog is not None:
            self.canlog.close()
