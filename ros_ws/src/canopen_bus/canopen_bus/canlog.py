"""The run's CAN log: every frame the cards saw or sent, with its wall time and the step it was applied at (spec §13).

The frames go to a Vector ASC file (``can.asc``: python-can's ``ASCWriter``; ``can.LogReader`` and
``can.logconvert`` read it, so do most CAN tools), Rx for a frame from the bus, Tx for one the cards sent. The
step of each frame, which ASC has no field for, goes to a sidecar in the same order (``can.asc.steps.csv``:
``frame,wall_time_s,step,direction,can_id``): for a frame from the bus the step whose sample took it in (sample
and hold), for a frame the cards sent the step that sent it. :func:`read_replay` reads both back and checks
they agree frame by frame. ``can.asc.run.json`` keeps the real-time factor the run was paced at, which the
cards' heartbeat watch counts its steps by (:func:`recorded_rtf`: a replay watches in the same steps).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import can

SIDECAR_SUFFIX = '.steps.csv'
SIDECAR_HEADER = ('frame', 'wall_time_s', 'step', 'direction', 'can_id')
RUN_SUFFIX = '.run.json'


class CanLogError(ValueError):
    """A CAN log that cannot be replayed (the message names the file and the frame)."""


class CanLog:
    """Writes frames in step order: ``write(step, wall_time, can_id, data, rx)``."""

    def __init__(self, path: Path, rtf: float) -> None:
        self.path = Path(path)
        Path(str(self.path) + RUN_SUFFIX).write_text(json.dumps({'rtf': rtf}) + '\n')
        self._asc = can.ASCWriter(str(self.path))
        self._side = open(str(self.path) + SIDECAR_SUFFIX, 'w', newline='')  # noqa: SIM115 (closed in close())
        self._csv = csv.writer(self._side)
        self._csv.writerow(SIDECAR_HEADER)
        self.frames = 0

    def write(self, step: int, wall_time: float, can_id: int, data: bytes, rx: bool) -> None:
        self._asc.on_message_received(can.Message(timestamp=wall_time, arbitration_id=can_id, data=data,
                                                  is_extended_id=False, is_rx=rx, channel=0))
        self._csv.writerow((self.frames, f'{wall_time:.6f}', step, 'Rx' if rx else 'Tx', f'0x{can_id:03X}'))
        self.frames += 1

    def close(self) -> None:
        self._asc.stop()
        self._side.close()


def read_replay(path: Path) -> dict[int, list[tuple[float, int, bytes]]]:
    """{step: [(wall_time, can_id, data), …]} of the frames the bus brought in (Rx), from the log and its sidecar."""
    path = Path(path)
    side = Path(str(path) + SIDECAR_SUFFIX)
    for p in (path, side):
        if not p.is_file():
            raise CanLogError(f'--replay-can {path}: no such file {p}')
    with open(side, newline='') as fh:
        rows = list(csv.reader(fh))
    if not rows or tuple(rows[0]) != SIDECAR_HEADER:
        raise CanLogError(f'--replay-can {path}: {side.name} does not start with {",".join(SIDECAR_HEADER)}')
    try:
        frames = list(can.LogReader(str(path)))
    except Exception as exc:  # python-can's readers raise what the file holds; name the file
        raise CanLogError(f'--replay-can {path}: not a CAN log python-can reads ({exc})') from None
    if len(frames) != len(rows) - 1:
        raise CanLogError(f'--replay-can {path}: {len(frames)} frames but {len(rows) - 1} rows in {side.name}')
    out: dict[int, list[tuple[float, int, bytes]]] = {}
    for i, (msg, row) in enumerate(zip(frames, rows[1:], strict=True)):
        try:
            step, direction, can_id, wall = int(row[2]), row[3], int(row[4], 16), float(row[1])
        except (ValueError, IndexError):
            raise CanLogError(f'--replay-can {path}: {side.name} row {i + 1} is not frame,wall,step,dir,id') from None
        if can_id != msg.arbitration_id:
            raise CanLogError(f'--replay-can {path}: frame {i} is 0x{msg.arbitration_id:03X} in the log, '
                              f'0x{can_id:03X} in {side.name}')
        if direction == 'Rx':
            out.setdefault(step, []).append((wall, can_id, bytes(msg.data)))
    return out


def recorded_rtf(path: Path) -> float | None:
    """The real-time factor a logged run was paced at (None: the log has no ``.run.json`` beside it)."""
    run = Path(str(path) + RUN_SUFFIX)
    try:
        return float(json.loads(run.read_text())['rtf'])
    except (OSError, ValueError, KeyError, TypeError):
        return None
