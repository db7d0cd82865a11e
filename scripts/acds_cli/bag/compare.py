"""Replay-regression: run ONE node alone against a bag's recorded inputs and compare its outputs.

The node under test runs as its own process in its own ROS domain with the
parameters it was recorded with (``acds.params`` of the bag; or from
``--scenario FILE``; ``--set name:=value`` overrides any). Its
``graph_nodes`` is the recorded graph, so it waits for the same inputs; the
player stands in for every other node: it publishes ``/clock`` and every
recorded topic the node did not publish, step by step, never more than
:data:`WINDOW` steps ahead of the node's outputs (flow control well inside
the lockstep history depth of 1000). The node's outputs are then compared
with the recorded ones topic by topic, step by step, field by field: floats
within ``tolerance`` (absolute; 0 = bit-identical), everything else exactly.
Outputs are the topics the recorder saw the node publish
(``acds.publishers``); ``diagnostics`` is compared on the node's own status
messages.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml
from acds_common import topics
from acds_common.lockstep import LOCKSTEP_QOS, TIME_OWNER
from std_msgs.msg import String

from ..monitor import message_class
from .player import Player, ros_env
from .reader import Bag, iter_fields, open_bag
from .writer import BagError, stamped, typestore

#: How many steps the player may run ahead of the node's outputs.
WINDOW = 100
DIAGNOSTICS = topics.resolve(topics.DIAGNOSTICS)
#: Exit codes of ``acds compare``.
EXIT_SAME, EXIT_DIFFERENT, EXIT_ERROR = 0, 1, 2


@dataclass
class CompareResult:
    """Outcome of one replay-regression."""

    node: str
    tolerance: float
    compared: dict[str, int] = field(default_factory=dict)
    max_diff: float = 0.0
    max_diff_where: str = ''
    first: str | None = None

    @property
    def ok(self) -> bool:
        """Whether every output matched."""
        return self.first is None

    def report(self) -> str:
        """Human-readable verdict (first line: PASS or FAIL)."""
        total = sum(self.compared.values())
        tol = f'within tolerance {self.tolerance:g}' if self.tolerance > 0 else 'bit-identical'
        if self.ok:
            head = f'PASS {self.node}: {total} output messages on {len(self.compared)} topics {tol}'
        else:
            head = f'FAIL {self.node}: {self.first}'
        lines = [head]
        lines += [f'  {t:40s} {n} messages compared' for t, n in sorted(self.compared.items())]
        where = f' ({self.max_diff_where})' if self.max_diff_where else ''
        lines.append(f'  largest float difference: {self.max_diff:.6g}{where}')
        return '\n'.join(lines)


def check_tolerance(tolerance: float) -> float:
    """``--tolerance``: a finite number >= 0 (0: bit-identical); a one-line :class:`BagError` otherwise."""
    if not math.isfinite(tolerance) or tolerance < 0:
        raise BagError(f'--tolerance {tolerance:g}: must be a finite number >= 0 '
                       f'(absolute float difference allowed; 0 = bit-identical)')
    return tolerance


def parse_sets(items: list[str] | None) -> dict[str, Any]:
    """``['name:=value', ...]`` → {name: YAML-parsed value}."""
    out = {}
    for item in items or []:
        name, sep, value = item.partition(':=')
        if not sep or not name:
            raise BagError(f'--set {item!r}: expected NAME:=VALUE')
        out[name] = yaml.safe_load(value)
    return out


def node_parameters(bag: Bag, node: str, scenario: str | None = None,
                    sets: dict[str, Any] | None = None) -> dict[str, Any]:
    """The node's ROS parameters for the replay: as recorded (or from ``scenario``), then ``sets``."""
    from acds_common.parameters import node_parameters as graph_parameters
    from acds_common.scenario import load_scenario

    recorded = yaml.safe_load(bag.info.get('params', '') or '{}') or {}
    steps = int(bag.info.get('steps', '1') or 1)
    if scenario is not None:
        params = graph_parameters(load_scenario(scenario), steps, 0.0).get(node)
        if params is None:
            raise BagError(f'scenario {scenario} has no node {node}')
    elif node in recorded:
        params = dict(recorded[node])
    elif bag.info.get('scenario'):
        with tempfile.NamedTemporaryFile('w', suffix='.yaml', delete=False) as fh:
            fh.write(bag.info['scenario'])
        try:
            params = graph_parameters(load_scenario(fh.name), steps, 0.0).get(node)
        finally:
            os.unlink(fh.name)
        if params is None:
            raise BagError(f'bag {bag.path}: its scenario has no node {node}')
    else:
        raise BagError(f'bag {bag.path}: no recorded parameters or scenario; give --scenario FILE')
    params.pop('total_steps', None)
    params.pop('real_time_factor', None)
    params['use_sim_time'] = True
    params.update(sets or {})
    return {k: v for k, v in params.items() if v != []}


def outputs_of(bag: Bag, node: str) -> list[str]:
    """Topics the recorder saw ``node`` publish (from ``acds.publishers``)."""
    pubs = yaml.safe_load(bag.info.get('publishers', '') or '{}') or {}
    if not pubs:
        raise BagError(f'bag {bag.path}: it does not say which node published what (acds.publishers)')
    return sorted(t for t, names in pubs.items() if node in names and bag.has(t))


def _by_step(msgs: list[tuple[int, bytes]], dt_ns: int, keyed: bool) -> dict[int, bytes]:
    if not keyed:
        return dict(enumerate(d for _, d in msgs))
    return {t // dt_ns: d for t, d in msgs}


def _own(data: bytes, node: str) -> bool:
    """Whether a raw DiagnosticArray is ``node``'s own status."""
    m = typestore().deserialize_cdr(data, 'diagnostic_msgs/msg/DiagnosticArray')
    return bool(m.status) and m.status[0].name == node


def _diff(rec: Any, new: Any, tol: float, where: str) -> tuple[str | None, float, str]:
    """(first field differing beyond tol or None, largest float difference, where it is) of two messages."""
    a, b = list(iter_fields(rec)), list(iter_fields(new))
    if len(a) != len(b):
        return f'{where}: different number of fields ({len(a)} recorded, {len(b)} now)', 0.0, ''
    first, top, top_where = None, 0.0, ''
    for (path, x), (path2, y) in zip(a, b, strict=True):
        if path != path2:
            return first or f'{where}: field {path} recorded, {path2} now', top, top_where
        if isinstance(x, float) or isinstance(y, float):
            x, y = float(x), float(y)
            d = abs(x - y) if math.isfinite(x) and math.isfinite(y) else (0.0 if x == y or (x != x and y != y)
                                                                           else math.inf)
            if d > top:
                top, top_where = d, f'{where} field {path}'
            if (d > tol or (tol == 0 and x != y)) and first is None:
                first = f'{where} field {path}: recorded {x!r}, now {y!r} (difference {d:.6g})'
        elif x != y and first is None:
            first = f'{where} field {path}: recorded {x!r}, now {y!r}'
    return first, top, top_where


def compare_outputs(bag: Bag, node: str, outputs: list[str], new: dict[str, list[tuple[int, bytes]]],
                    tolerance: float) -> CompareResult:
    """Compare the recorded outputs (streamed from the bag) with the new ones, step by step.

    The earliest difference wins: steps in order, at one step a step's data topics before diagnostics,
    then by topic name; the largest float difference reported is the earliest one of that size.
    """
    ts = typestore()
    dt_ns = bag.control_period_ns or 1
    result = CompareResult(node, tolerance)
    keyed = {t: stamped(bag.types[t]) for t in outputs}
    now = {t: _by_step([(k, d) for k, d in new.get(t, []) if t != DIAGNOSTICS or _own(d, node)], dt_ns, keyed[t])
           for t in outputs}
    index = dict.fromkeys(outputs, 0)
    first: tuple[tuple[int, bool, str], str] | None = None
    top: tuple[float, tuple[int, bool, str], str] | None = None
    for topic, t, rec_raw in bag.messages(outputs):
        if topic == DIAGNOSTICS and not _own(rec_raw, node):
            continue
        if keyed[topic]:
            k = t // dt_ns
        else:
            k, index[topic] = index[topic], index[topic] + 1
        order = (k, topic == DIAGNOSTICS, topic)  # a step's data topics before diagnostics
        result.compared[topic] = result.compared.get(topic, 0) + 1
        where = f'topic {topic} step {k}' if keyed[topic] else f'topic {topic} message #{k}'
        new_raw = now[topic].get(k)
        if new_raw is None:
            text: str | None = f'{where}: recorded, but the node published nothing for it'
        elif new_raw == rec_raw:
            continue
        else:
            msgtype = bag.types[topic]
            text, d, d_where = _diff(ts.deserialize_cdr(rec_raw, msgtype), ts.deserialize_cdr(new_raw, msgtype),
                                     tolerance, where)
            if d > 0 and (top is None or d > top[0] or (d == top[0] and order < top[1])):
                top = (d, order, d_where)
        if text is not None and (first is None or order < first[0]):
            first = (order, text)
    if top is not None:
        result.max_diff, result.max_diff_where = top[0], top[2]
    result.first = first[1] if first is not None else None
    return result


class _NodeProcess:
    """The node under test: one process, its output kept for error reports."""

    def __init__(self, node: str, params_file: Path, env: dict[str, str]) -> None:
        exe = Path(sys.executable).parent / node
        if not exe.exists():
            raise BagError(f'no node executable {exe} (is {node} a node of this workspace?)')
        self.name = node
        self.tail: deque[str] = deque(maxlen=20)
        self.popen = subprocess.Popen([str(exe), '--ros-args', '--params-file', str(params_file)],
                                      stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                      text=True, env=env, start_new_session=True)
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.popen.stdout is not None
        for line in self.popen.stdout:
            self.tail.append(line.rstrip('\n'))

    def died(self) -> str | None:
        code = self.popen.poll()
        if code is None:
            return None
        self._reader.join(timeout=2.0)
        return f'node {self.name} exited (code {code}) during the replay:\n' + '\n'.join(
            f'    {line}' for line in self.tail)

    def stop(self) -> None:
        if self.popen.poll() is None:
            try:
                os.killpg(self.popen.pid, signal.SIGINT)
                self.popen.wait(timeout=10.0)
            except subprocess.TimeoutExpired:
                os.killpg(self.popen.pid, signal.SIGKILL)
                self.popen.wait()
            except ProcessLookupError:
                pass
        if self.popen.stdout is not None:
            self.popen.stdout.close()


def run_compare(bag_path: Path | str, node: str, *, tolerance: float = 0.0, scenario: str | None = None,
                sets: dict[str, Any] | None = None, ready_timeout_s: float = 30.0,
                log: Any = None) -> CompareResult:
    """Replay ``bag_path``'s inputs into ``node`` alone and compare its outputs (raises BagError on set-up)."""
    from ..launcher import DomainLease

    check_tolerance(tolerance)
    log = log or (lambda text: print(text, file=sys.stderr, flush=True))
    if node == TIME_OWNER:
        raise BagError(f'{node} is the time owner: compare replays /clock into a non-owner node')
    bag = open_bag(bag_path)
    dt_ns = bag.control_period_ns
    if not dt_ns or not bag.has(topics.CLOCK):
        raise BagError(f'bag {bag.path}: no /clock messages: nothing to step the node with')
    outputs = outputs_of(bag, node)
    if not [t for t in outputs if t != DIAGNOSTICS]:
        raise BagError(f'bag {bag.path}: no recorded outputs of node {node} '
                       f'(recorded publishers: {bag.info.get("publishers", "?").strip()})')
    inputs = [t for t in bag.types if t not in outputs and t != DIAGNOSTICS and bag.has(t)]
    params = node_parameters(bag, node, scenario, sets)
    n_clock = bag.count(topics.CLOCK)
    pacing = [t for t in outputs if t != DIAGNOSTICS and bag.count(t) >= n_clock - 2 and stamped(bag.types[t])]
    last_step = {t: bag.stats()[t].last_ns // dt_ns for t in pacing}
    tol_text = f'tolerance {tolerance:g}' if tolerance > 0 else 'bit-identical'
    log(f'[compare] {node} alone against {bag.path}: {n_clock} steps; replaying {len(inputs)} topics; '
        f'comparing {", ".join(outputs)} ({tol_text})')

    lease = DomainLease()
    work = Path(tempfile.mkdtemp(prefix=f'acds_compare_{node}_'))
    params_file = work / 'params.yaml'
    params_file.write_text(yaml.safe_dump({f'/acds/{node}': {'ros__parameters': params}}, sort_keys=True))
    ros_env(lease.domain_id)
    env = dict(os.environ, ROS_DOMAIN_ID=str(lease.domain_id), ROS_LOG_DIR=str(work / 'ros_log'),
               RCUTILS_CONSOLE_OUTPUT_FORMAT='[{severity}] {message}', RCUTILS_COLORIZED_OUTPUT='0',
               PYTHONUNBUFFERED='1')
    player = proc = None
    new: dict[str, list[tuple[int, bytes]]] = {t: [] for t in outputs}
    progress = dict.fromkeys(pacing, -1)
    lock = threading.Lock()
    ready = threading.Event()
    try:
        player = Player(bag, domain_id=lease.domain_id, select=inputs, name='acds_replay')

        def on_output(topic: str, data: bytes) -> None:
            with lock:
                new[topic].append((len(new[topic]), data))
                if topic in progress:
                    progress[topic] = max(progress[topic], _stamp_step(data, dt_ns))

        for topic in outputs:
            player.node.create_subscription(message_class(bag.types[topic]), topic,
                                            lambda d, t=topic: on_output(t, d), LOCKSTEP_QOS, raw=True)
        player.node.create_subscription(String, topics.READY,
                                        lambda m: ready.set() if m.data == node else None, LOCKSTEP_QOS)
        proc = _NodeProcess(node, params_file, env)
        deadline = time.monotonic() + ready_timeout_s
        while not ready.wait(0.05):
            if (dead := proc.died()) is not None:
                raise BagError(dead)
            if time.monotonic() > deadline:
                subs = player.node.get_subscriber_names_and_types_by_node(node, topics.NAMESPACE)
                lacking = sorted(t for t, _ in subs if t not in player.publishers and t != topics.CLOCK)
                raise BagError(f'node {node} never became ready in {ready_timeout_s:.0f} s'
                               + (f': the bag has no {", ".join(lacking)}' if lacking else ''))

        def before_step(t_ns: int) -> bool:
            k = t_ns // dt_ns
            while True:
                with lock:
                    behind = min(progress.values(), default=k)
                if k - behind <= WINDOW:
                    return True
                if (dead := proc.died()) is not None:
                    raise BagError(dead)
                time.sleep(0.002)

        player.play(before_step=before_step)
        # wait for the node's outputs of every recorded step
        timeout_s = float(params.get('input_timeout_s', 30.0))
        last = time.monotonic()
        seen = -1
        while True:
            with lock:
                counts = sum(len(v) for v in new.values())
                done = all(progress[t] >= last_step[t] for t in pacing)
            if done:
                break
            if counts != seen:
                seen, last = counts, time.monotonic()
            if (dead := proc.died()) is not None:
                raise BagError(dead)
            if time.monotonic() - last > timeout_s:
                break  # compared below: the missing step is named
            time.sleep(0.01)
        player.ack(5.0)
        time.sleep(0.2)  # occasional outputs (diagnostics) of the last step
    finally:
        if proc is not None:
            proc.stop()
        if player is not None:
            player.close()
        lease.close()
    with lock:
        new_stamped = {t: [(_stamp_ns(d) if stamped(bag.types[t]) else i, d) for i, d in v] for t, v in new.items()}
    return compare_outputs(bag, node, outputs, new_stamped, tolerance)


def _stamp_ns(data: bytes) -> int:
    from .writer import cdr_stamp_ns
    return cdr_stamp_ns(data)


def _stamp_step(data: bytes, dt_ns: int) -> int:
    return _stamp_ns(data) // dt_ns
