"""One emulated CANopen device: an object dictionary served on the bus, paced by the lockstep steps (spec §13).

``canopen.LocalNode`` is the device's SDO server (expedited and segmented uploads and downloads; the standard
abort codes: 0x06020000 object not in the dictionary, 0x06090011 no such subindex, 0x06010002 read-only,
0x06070010 wrong size) and its NMT slave; this module adds what a card's firmware does on a clock, done here on
the step's wall time instead: the TPDOs at their event timers (or the mapping's period), the heartbeat at 0x1017,
the boot-up message. Frames reach the device through :meth:`receive` (any thread) and leave through ``send``;
every frame the device applies is kept with the step that sampled it (sample and hold), so a replay can feed
the same frames at the same steps.
"""

from __future__ import annotations

import dataclasses
import threading
from collections.abc import Callable

import canopen
from canopen import objectdictionary as odict

from canopen_bus.dictionary import Pdo, pdos

#: SDO abort codes the device counts (CiA 301 §7.2.4.3.17), by name.
ABORT_CODES = {0x06020000: 'object not in the dictionary', 0x06090011: 'no such subindex',
               0x06010002: 'read-only object', 0x06010001: 'write-only object', 0x06070010: 'wrong size',
               0x06070012: 'wrong size (too long)', 0x06070013: 'wrong size (too short)',
               0x05040001: 'bad command specifier', 0x08000000: 'general error'}
#: NMT state byte in the heartbeat (CiA 301).
HEARTBEAT_STATE = {'INITIALISING': 0x00, 'STOPPED': 0x04, 'OPERATIONAL': 0x05, 'PRE-OPERATIONAL': 0x7F}


class _Periodic:
    """What ``canopen``'s NMT slave asks the network for when 0x1017 is written: kept, sent on steps instead."""

    def __init__(self, can_id: int, data: bytes, period_s: float) -> None:
        self.can_id, self.data, self.period_s = can_id, bytes(data), period_s

    def update(self, data: bytes) -> None:
        self.data = bytes(data)

    def stop(self) -> None:
        self.period_s = 0.0


class _DeviceNetwork(canopen.Network):
    """The device's side of the bus: frames out through ``send``; periodic tasks left to the step loop."""

    def __init__(self, send: Callable[[int, bytes], None]) -> None:
        super().__init__(None)
        self._send = send
        self.periodic: dict[int, _Periodic] = {}

    def send_message(self, can_id: int, data: bytes, remote: bool = False) -> None:
        self._send(can_id, bytes(data))

    def send_periodic(self, can_id: int, data: bytes, period: float, remote: bool = False) -> _Periodic:
        task = _Periodic(can_id, data, period)
        self.periodic[can_id] = task
        return task


@dataclasses.dataclass
class SdoStats:
    """SDO traffic the device served: transfers, aborts by code, and each transfer's request→reply time (s)."""

    requests: int = 0
    aborts: dict[int, int] = dataclasses.field(default_factory=dict)
    latencies_s: list[float] = dataclasses.field(default_factory=list)


class EmulatedDevice:
    """A CANopen device built from ``od`` with node id ``node_id``; ``send(can_id, data)`` puts a frame on the bus.

    ``tpdo_period_s``: {PDO number: period} overriding the dictionary's event timers (0 or absent and no event
    timer: the PDO is not sent).
    """

    def __init__(self, name: str, od: odict.ObjectDictionary, node_id: int, send: Callable[[int, bytes], None],
                 tpdo_period_s: dict[int, float] | None = None, wall: Callable[[], float] | None = None) -> None:
        import time
        self.name, self.od, self.node_id = name, od, node_id
        self._wall = wall or time.time
        self._send = send
        self.network = _DeviceNetwork(self._emit)
        self.node = canopen.LocalNode(node_id, od)
        self.network.add_node(self.node)
        self.node.sdo.abort = self._abort  # count aborts, then send them as the server would
        self._server_abort = canopen.sdo.SdoServer.abort.__get__(self.node.sdo)
        self.lock = threading.RLock()
        self.sdo = SdoStats()
        self._request_wall: float | None = None
        self.tpdos: list[Pdo] = pdos(od, name, 'tpdo')
        self.rpdos: list[Pdo] = pdos(od, name, 'rpdo')
        for pdo in self.rpdos:
            self.network.subscribe(pdo.cob_id, self._on_rpdo)
        self.rpdo_errors = 0
        overrides = tpdo_period_s or {}
        self.tpdo_period_s = {p.number: overrides.get(p.number, p.event_timer_ms / 1000.0) for p in self.tpdos}
        self._tpdo_next = {p.number: 0.0 for p in self.tpdos}
        self._heartbeat_next = 0.0
        self.pending: list[tuple[float, int, bytes]] = []
        #: Faults (spec §13, "Faults that flight software must survive"): no TPDOs; SDO replies dropped; SDO
        #: replies sent this many wall seconds late (a timer thread, as a slow card's firmware would).
        self.silenced = False
        self.sdo_lost = False
        self.sdo_delay_s = 0.0
        self.sdo_dropped = 0
        #: Frames addressed to the device that its CANopen services cannot read (an NMT command of one byte, an
        #: empty SDO request): counted, each reported through ``on_malformed`` (one line), ignored; the SDO aborts
        #: too (once per object and abort code).
        self.malformed = 0
        self.on_malformed: Callable[[str], None] | None = None
        self._aborts_named: set[tuple[int, tuple]] = set()
        self.booted = False

    # -- frames in ------------------------------------------------------------------------------------------
    def receive(self, can_id: int, data: bytes, wall_time: float) -> None:
        """A frame from the bus (any thread): applied to the dictionary now (SDO replies go out at once), kept
        until the next step samples it."""
        with self.lock:
            self.pending.append((wall_time, can_id, bytes(data)))
            if can_id == 0x600 + self.node_id:
                self.sdo.requests += 1
                self._request_wall = wall_time
            try:
                self.network.notify(can_id, bytearray(data), wall_time)
            except Exception as exc:  # noqa: BLE001 (canopen's services unpack without a length check)
                self.malformed += 1
                if self.on_malformed is not None:
                    self.on_malformed(f'device {self.name}: frame 0x{can_id:03X} [{bytes(data).hex() or "empty"}] is '
                                      f'not a valid CANopen message for it ({type(exc).__name__}: {exc}); ignored')

    def _on_rpdo(self, can_id: int, data: bytearray, _timestamp: float) -> None:
        """An RPDO (OPERATIONAL only): its bytes into the mapped objects, in mapping order; a frame shorter than the
        mapping is counted and left out."""
        if self.nmt_state != 'OPERATIONAL':
            return
        pdo = next(p for p in self.rpdos if p.cob_id == can_id)
        if len(data) * 8 < pdo.bits:
            self.rpdo_errors += 1
            return
        offset = 0
        for index, sub, bits in pdo.mapped:
            store = self.node.data_store.setdefault(index, {})
            store[sub] = bytes(data[offset:offset + bits // 8])
            offset += bits // 8

    def take_pending(self) -> list[tuple[float, int, bytes]]:
        """The frames applied since the last call (call with :attr:`lock` held, at the step that samples them)."""
        out, self.pending = self.pending, []
        return out

    def _emit(self, can_id: int, data: bytes) -> None:
        if can_id == 0x580 + self.node_id:
            if self.sdo_lost:
                self.sdo_dropped += 1
                return
            if self.sdo_delay_s > 0:
                timer = threading.Timer(self.sdo_delay_s, self._reply_late, (can_id, data))
                timer.daemon = True
                timer.start()
                return
            if self._request_wall is not None:
                self.sdo.latencies_s.append(self._wall() - self._request_wall)
                self._request_wall = None
        self._send(can_id, data)

    def _reply_late(self, can_id: int, data: bytes) -> None:
        with self.lock:
            if self._request_wall is not None:
                self.sdo.latencies_s.append(self._wall() - self._request_wall)
                self._request_wall = None
            self._send(can_id, data)

    def _abort(self, abort_code: int = 0x08000000) -> None:
        self.sdo.aborts[abort_code] = self.sdo.aborts.get(abort_code, 0) + 1
        where = (self.node.sdo._index, self.node.sdo._subindex)
        if (abort_code, where) not in self._aborts_named and self.on_malformed is not None:
            self._aborts_named.add((abort_code, where))
            obj = 'an unread object' if where[0] is None else f'0x{where[0]:04X}:{where[1]}'
            self.on_malformed(f'device {self.name}: SDO abort 0x{abort_code:08X} '
                              f'({ABORT_CODES.get(abort_code, "other")}) for {obj} (named once per object and code; '
                              f'counted)')
        self._server_abort(abort_code)

    # -- the dictionary ---------------------------------------------------------------------------------
    def set_raw(self, index: int, subindex: int, raw: int) -> None:
        """Write an object as the firmware does (no access check): the value the next PDO or upload sends."""
        var = self.node.object_dictionary[index]
        var = var if isinstance(var, odict.ODVariable) else var[subindex]
        self.node.data_store.setdefault(index, {})[subindex] = var.encode_raw(raw)

    def get_raw(self, index: int, subindex: int) -> int:
        """An object's current value (what an SDO upload would return)."""
        var = self.node.object_dictionary[index]
        var = var if isinstance(var, odict.ODVariable) else var[subindex]
        return int(var.decode_raw(self.node.get_data(index, subindex)))

    @property
    def nmt_state(self) -> str:
        return self.node.nmt.state

    # -- the clock edge -------------------------------------------------------------------------------------
    def boot(self) -> None:
        """Boot-up message, then OPERATIONAL (the OreSat cards start operational on their own)."""
        self._emit(0x700 + self.node_id, b'\x00')
        self.node.nmt.state = 'OPERATIONAL'
        self.booted = True

    def tick(self, t_s: float) -> list[int]:
        """Send what is due at sim time ``t_s``: the heartbeat (0x1017) and, when OPERATIONAL, each TPDO whose
        period has come; returns the COB-IDs sent."""
        sent = []
        period_ms = int(self.node.sdo[0x1017].raw) if 0x1017 in self.od else 0
        if period_ms > 0 and t_s + 1e-9 >= self._heartbeat_next:
            self._emit(0x700 + self.node_id, bytes([HEARTBEAT_STATE.get(self.nmt_state, 0x7F)]))
            self._heartbeat_next = t_s + period_ms / 1000.0
            sent.append(0x700 + self.node_id)
        if self.nmt_state != 'OPERATIONAL' or self.silenced:
            return sent
        for pdo in self.tpdos:
            period = self.tpdo_period_s[pdo.number]
            if period <= 0 or t_s + 1e-9 < self._tpdo_next[pdo.number] or not pdo.mapped:
                continue
            self._tpdo_next[pdo.number] = t_s + period
            payload = b''.join(self.node.get_data(i, s)[: b // 8] for i, s, b in pdo.mapped)
            self._emit(pdo.cob_id, payload)
            sent.append(pdo.cob_id)
        return sent
