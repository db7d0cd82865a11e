"""What the flight computer did on the bus, read from the run's CAN log (spec §13, "Faults that flight software
must survive").

From ``can.asc`` and its step sidecar (:mod:`canopen_bus.canlog`): the flight computer's heartbeat (COB-ID
0x700 + its node id: first and last step, count), the setpoints it wrote (SDO download requests to a card,
COB-ID 0x600 + the card's id, to the ``setpoint`` objects the mapping names: per object how many, the first and
last step, the smallest and largest value), every other SDO request to a card, the aborts the cards answered, and,
when the setpoints stop while the heartbeat goes on, the line saying so (frames logged after the last step's
sample, step −1, are left out): "stopped writing setpoints at step K
(t = …) while its heartbeat went on to step H".
"""

from __future__ import annotations

import struct
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from canopen_bus.canlog import read_frames

#: SDO client command specifier: initiate download (ccs = 1) in the top three bits; abort transfer 0x80.
SDO_DOWNLOAD, SDO_ABORT = 0x20, 0x80


@dataclass
class ObjectWrites:
    """The writes of one object: how many, first and last step, smallest and largest value (the raw integer)."""

    count: int = 0
    first_step: int | None = None
    last_step: int | None = None
    low: int | None = None
    high: int | None = None
    nonzero: int = 0

    def add(self, step: int, value: int) -> None:
        self.count += 1
        self.first_step = step if self.first_step is None else self.first_step
        self.last_step = step
        self.low = value if self.low is None else min(self.low, value)
        self.high = value if self.high is None else max(self.high, value)
        self.nonzero += value != 0


@dataclass
class FlightComputerReport:
    node_id: int
    last_step: int
    heartbeats: int = 0
    heartbeat_steps: tuple[int | None, int | None] = (None, None)
    setpoints: dict[str, ObjectWrites] = field(default_factory=dict)
    other_sdo: int = 0
    aborts: dict[int, int] = field(default_factory=dict)

    def stopped_line(self, dt_s: float, quiet_steps: int) -> str | None:
        """The one line when the setpoints ended more than ``quiet_steps`` before the run while the heartbeat went on."""
        last = max((w.last_step for w in self.setpoints.values() if w.last_step is not None), default=None)
        hb_last = self.heartbeat_steps[1]
        if last is None or hb_last is None or self.last_step - last <= quiet_steps or hb_last - last <= quiet_steps:
            return None
        return (f'the flight computer (node 0x{self.node_id:02X}) stopped writing setpoints at step {last} '
                f'(t = {last * dt_s:.1f} s) while its heartbeat went on to step {hb_last} (t = {hb_last * dt_s:.1f} s)')

    def lines(self, dt_s: float) -> list[str]:
        """The run's account of the flight computer, one line each."""
        hb0, hb1 = self.heartbeat_steps
        out = [f'flight computer node 0x{self.node_id:02X}: ' + (
            f'{self.heartbeats} heartbeats, steps {hb0}..{hb1}' if self.heartbeats else 'no heartbeat on the bus')]
        for name, w in self.setpoints.items():
            out.append(f'  {name}: ' + ('never written' if not w.count else
                       f'{w.count} writes ({w.nonzero} non-zero), steps {w.first_step}..{w.last_step}, '
                       f'values {w.low}..{w.high}'))
        if self.other_sdo or self.aborts:
            out.append(f'  other SDO requests to the cards: {self.other_sdo}; aborts answered: '
                       + (', '.join(f'0x{c:08X} × {n}' for c, n in self.aborts.items()) or 'none'))
        stopped = self.stopped_line(dt_s, quiet_steps=max(1, round(10.0 / dt_s)))
        if stopped:
            out.append('  ' + stopped)
        return out

    def as_dict(self) -> dict[str, Any]:
        return {'node_id': self.node_id, 'heartbeats': self.heartbeats,
                'heartbeat_first_step': self.heartbeat_steps[0], 'heartbeat_last_step': self.heartbeat_steps[1],
                'setpoints': {k: vars(v) for k, v in self.setpoints.items()}, 'other_sdo_requests': self.other_sdo,
                'aborts': {f'0x{code:08X}': n for code, n in self.aborts.items()}}


def setpoint_objects(mapping: Path) -> dict[tuple[int, int, int], str]:
    """{(card node id, index, sub): name} of the mapping's command objects (the quantities in ``mapping.COMMANDS``)."""
    from canopen_bus.mapping import COMMANDS, load_mapping

    out = {}
    for dev in load_mapping(Path(mapping)):
        for o in dev.objects:
            if o.quantity in COMMANDS:
                for sub in o.subs:
                    out[(dev.node_id, o.index, sub)] = f'{dev.name} 0x{o.index:04X}.{sub} {dev.od[o.index][sub].name}'
    return out


def report(can_log: Path, fc_node_id: int, setpoint_objects: dict[tuple[int, int, int], str],
           frames: Iterable[tuple[int, float, bool, int, bytes]] | None = None) -> FlightComputerReport:
    """Read the log; ``setpoint_objects``: {(card node id, index, sub): name} of the objects that are setpoints."""
    rows = list(read_frames(Path(can_log)) if frames is None else frames)
    out = FlightComputerReport(fc_node_id, max((r[0] for r in rows), default=0))
    out.setpoints = {name: ObjectWrites() for name in setpoint_objects.values()}
    cards = {node for node, _, _ in setpoint_objects}
    hb_first = hb_last = None
    for step, _wall, rx, can_id, data in rows:
        if step < 0:  # after the last step's sample: applied at no step
            continue
        if rx and can_id == 0x700 + fc_node_id:
            out.heartbeats += 1
            hb_first = step if hb_first is None else hb_first
            hb_last = step
        elif rx and can_id - 0x600 in cards and len(data) == 8 and data[0] & 0xE0 == SDO_DOWNLOAD:
            index, sub = struct.unpack_from('<HB', data, 1)
            name = setpoint_objects.get((can_id - 0x600, index, sub))
            if name is None or not data[0] & 0x02:
                out.other_sdo += 1
                continue
            size = 4 - ((data[0] >> 2) & 3) if data[0] & 0x01 else 4
            out.setpoints[name].add(step, int.from_bytes(data[4:4 + size], 'little', signed=True))
        elif rx and can_id - 0x600 in cards:
            out.other_sdo += 1
        elif not rx and can_id - 0x580 in cards and len(data) == 8 and data[0] == SDO_ABORT:
            code = struct.unpack_from('<I', data, 4)[0]
            out.aborts[code] = out.aborts.get(code, 0) + 1
    out.heartbeat_steps = (hb_first, hb_last)
    return out
