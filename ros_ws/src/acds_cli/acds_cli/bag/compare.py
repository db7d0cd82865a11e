"""Replay-regression: run ONE node's stepper against a bag's recorded inputs and compare its outputs.

The node under test is built exactly as its node process builds it — the same stepper, the
parameters it was recorded with (``acds.params`` of the bag; or from ``--scenario FILE``;
``--set name:=value`` overrides any) and the ports :mod:`acds_common.graph` declares for it —
and fed, in this process, step by step, the values its declared inputs carry in the bag (the
recorded outputs of the other nodes; absent sources stay absent, as in the recorded graph).
It runs in lockstep by construction: step k fires once every input of step k is read from
the bag's stream, with nothing timed and no DDS. Its outputs, encoded with the codec the
nodes publish with, are compared with the recorded ones topic by topic, step by step, field
by field: floats within ``tolerance`` (absolute; 0 = bit-identical), everything else exactly;
``diagnostics`` on the node's own statuses. Live ground commands recorded on
``ground/command`` are handed to the node before the step the recorder stamped them with.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml
from acds_common import topics
from acds_runtime.bag.reader import Bag, iter_fields, open_bag
from acds_runtime.bag.writer import BagError, stamped, typestore

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
        try:
            out[name] = yaml.safe_load(value)
        except yaml.YAMLError as exc:
            raise BagError(f'--set {item!r}: the value is not valid YAML '
                           f'({str(exc).splitlines()[0]})') from None
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
        params = graph_parameters(bag.scenario(), steps, 0.0).get(node)
        if params is None:
            raise BagError(f'bag {bag.path}: its scenario has no node {node}')
    else:
        raise BagError(f'bag {bag.path}: no recorded parameters or scenario; give --scenario FILE')
    params.pop('total_steps', None)
    params.pop('real_time_factor', None)
    params.update(sets or {})
    return {k: v for k, v in params.items() if v != []}


def _by_step(msgs: list[tuple[int, bytes]], dt_ns: int, keyed: bool) -> dict[int, bytes]:
    if not keyed:
        return dict(enumerate(d for _, d in msgs))
    return {t // dt_ns: d for t, d in msgs}


def _own(data: bytes, node: str) -> bool:
    """Whether a raw DiagnosticArray is ``node``'s own status."""
    m = typestore().deserialize_cdr(data, 'diagnostic_msgs/msg/DiagnosticArray')
    return bool(m.status) and m.status[0].name == node


def _without_wall_clock(data: bytes) -> bytes:
    """A raw DiagnosticArray with its wall-clock keys (:data:`acds_common.messages.WALL_CLOCK_PREFIX`: the
    host's step timing) left out: they describe the machine the bag was recorded on, not the node's data."""
    from acds_common.cdr import Codec
    from acds_common.messages import WALL_CLOCK_PREFIX

    codec = Codec(topics.TYPES[topics.DIAGNOSTICS])
    t_ns, statuses = codec.decode(data)
    return codec.encode(t_ns, tuple(st._replace(values=tuple(kv for kv in st.values if not kv[0].startswith(
        WALL_CLOCK_PREFIX))) for st in statuses))


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
        if topic == DIAGNOSTICS:
            if not _own(rec_raw, node):
                continue
            rec_raw = _without_wall_clock(rec_raw)
        if keyed[topic]:
            k = t // dt_ns
        else:
            k, index[topic] = index[topic], index[topic] + 1
        order = (k, topic == DIAGNOSTICS, topic)  # a step's data topics before diagnostics
        result.compared[topic] = result.compared.get(topic, 0) + 1
        where = f'topic {topic} step {k}' if keyed[topic] else f'topic {topic} message #{k}'
        new_raw = now[topic].get(k)
        if new_raw is not None and topic == DIAGNOSTICS:
            new_raw = _without_wall_clock(new_raw)
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


def run_compare(bag_path: Path | str, node: str, *, tolerance: float = 0.0, scenario: str | None = None,
                sets: dict[str, Any] | None = None, log: Any = None) -> CompareResult:
    """Replay ``bag_path``'s inputs into ``node``'s stepper and compare its outputs (raises BagError on set-up)."""
    from acds_common.cdr import Codec
    from acds_common.graph import declared_node, node_spec
    from acds_common.parameters import ConfigError, normalize
    from acds_common.stepper import load_stepper

    check_tolerance(tolerance)
    log = log or (lambda text: print(text, file=sys.stderr, flush=True))
    bag = open_bag(bag_path)
    dt_ns = bag.control_period_ns
    if not dt_ns or not bag.has(topics.CLOCK):
        raise BagError(f'bag {bag.path}: no /clock messages: nothing to step the node with')
    name = node.rpartition('/')[2]  # a formation vehicle's node is VEHICLE/NODE, its topics under /acds/VEHICLE
    try:  # the time owner is refused by its declaration, before its parameters (it has no replayable inputs)
        if declared_node(name)[1].time_owner:
            raise BagError(f'{node} is the time owner: compare replays the truth into a non-owner node')
        params = normalize(name, node_parameters(bag, node, scenario, sets))
        spec = node_spec(name, params)
        stepper = load_stepper(spec.stepper)(params, log=lambda level, text: log(f'[{node}] [{level}] {text}'))
    except (ConfigError, KeyError, ValueError) as exc:
        raise BagError(f'node {node}: {exc}') from None
    ports = {spec.topic(o.topic): o for o in spec.outputs}
    outputs = sorted(t for t in ports if bag.has(t))
    if not [t for t in outputs if t != DIAGNOSTICS]:
        raise BagError(f'bag {bag.path}: no recorded outputs of node {node}')
    present = set(params['graph_nodes'])
    inputs = {spec.topic(i.topic): Codec(topics.type_of(i.topic)) for st in spec.stages for i in st.inputs
              if i.source in present}
    lacking = sorted(t for t in inputs if not bag.has(t))
    if lacking:
        raise BagError(f'bag {bag.path}: it has no {", ".join(lacking)}, which {node} reads')
    commands = spec.topic(topics.GROUND_COMMAND)
    text = Codec(topics.TYPES[topics.GROUND_COMMAND])
    tol_text = f'tolerance {tolerance:g}' if tolerance > 0 else 'bit-identical'
    log(f'[compare] {node} alone against {bag.path}: {bag.count(topics.CLOCK)} steps; replaying '
        f'{", ".join(sorted(inputs))}; comparing {", ".join(outputs)} ({tol_text})')
    buffers: dict[str, dict[int, Any]] = {t: {} for t in inputs}
    new: dict[str, list[tuple[int, bytes]]] = {t: [] for t in outputs}
    codecs = {t: Codec(o.msg_type, o.frame_id, o.child_frame_id) for t, o in ports.items()}
    last_clock = -1
    max_lag = max((i.lag for st in spec.stages for i in st.inputs), default=0)

    def fire(k: int) -> None:
        for st in spec.stages:
            values = {}
            for i in st.inputs:
                back, topic = k - i.lag, spec.topic(i.topic)
                if i.source not in present or back < 0:
                    values[i.key] = None
                elif back in buffers[topic]:
                    values[i.key] = buffers[topic][back]
                else:
                    raise BagError(f'bag {bag.path}: no {topic} for step {back} ({node}.{st.name} of step {k} '
                                   'needs it)')
            for key, value in getattr(stepper, st.name)(k, k * dt_ns / 1e9, values).items():
                topic = spec.topic(spec.output(key).topic)
                if topic not in new:
                    continue
                out = ports[topic]
                for item in (value if out.many else (value,)):
                    data = codecs[topic].encode((k + out.stamp_offset) * dt_ns, item)
                    new[topic].append((codecs[topic].decode(data)[0] if codecs[topic].stamped else len(new[topic]),
                                       data))
        for buf in buffers.values():
            buf.pop(k - max_lag, None)

    next_k = 0
    for t_ns, group in bag.ordered([*inputs, topics.CLOCK, *([commands] if spec.ground_commands else [])]):
        for topic, data in group:
            if topic == commands:
                stepper.receive_command(text.decode(data)[1])
            elif topic == topics.CLOCK:
                last_clock = t_ns // dt_ns
            else:
                buffers[topic][t_ns // dt_ns] = inputs[topic].decode(data)[1]
        while next_k <= min(last_clock, t_ns // dt_ns):
            fire(next_k)
            next_k += 1
    return compare_outputs(bag, node, outputs, new, tolerance)
