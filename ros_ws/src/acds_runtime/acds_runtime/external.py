"""External nodes, as the run monitor sees them (issue 20 §1, §4): when they have joined, what they send, how long
they take.

An external node is a node of the graph that the user runs (any ROS 2 node, any language, this host or another);
the launcher does not start it and asks it for nothing but plain ROS 2 (:func:`acds_common.graph.external_nodes`).
The run monitor, which subscribes to every output of the graph anyway, holds one :class:`ExternalWatch`:

* **joined**: the graph starts once every external node publishes each of its per-step outputs (matched with the
  monitor's readers, so with the lockstep QoS) and, for each stage, subscribes to one of its inputs at least
  (which it reads is its own business; ``/clock`` for a stage none of whose inputs is of the same step; the
  inputs are transient-local, so a reader that matches late still gets every step);
  :meth:`ExternalWatch.missing` names what is not there yet;
* **sequence**: each of its per-step outputs must carry every step once, in order, stamped with the step's time
  (:func:`acds_common.lockstep.sequence_error`: one line naming the topic, the step and what was expected);
* **timing**: the wall time from the arrival of the last input of step k to that of its outputs of step k, as the
  monitor receives them (DDS delivery included both ways; the node processes measure themselves, from inside).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from acds_common import topics
from acds_common.cdr import Codec, frame_id_of, stamp_ns
from acds_common.graph import Graph
from acds_common.lockstep import publisher_name, sequence_error
from acds_common.timing import StepTimes, overrun


@dataclass
class _External:
    """One external node: its ROS identity, topics, and the arrival times of its steps' inputs and outputs."""

    identity: str
    outputs: list[str]
    #: Per stage, the topics it may read (its present inputs; /clock when none is of the same step).
    stage_inputs: list[list[str]]
    triggers: list[str]
    #: {topic: 'pkg/msg/Type'} of its outputs and inputs, as the contract declares them.
    types: dict[str, str]
    times: StepTimes
    strict: bool
    #: {output topic: header.frame_id the contract declares} of its per-step outputs with a header.
    frames: dict[str, str] = field(default_factory=dict)
    inputs_at: dict[int, list[float]] = field(default_factory=dict)
    outputs_at: dict[int, list[float]] = field(default_factory=dict)
    last: dict[str, int] = field(default_factory=dict)


def _own(ext: _External, infos: Any, topic: str, wrong: dict[str, list[str]]) -> list[Any]:
    """The endpoints of ``ext`` among ``infos`` (discovery's, on ``topic``) of the contract's type; the other types
    it has there are added to ``wrong[topic]``."""
    mine = [i for i in infos if publisher_name(i) == ext.identity]
    for i in mine:
        if i.topic_type != ext.types[topic] and i.topic_type not in wrong.setdefault(topic, []):
            wrong[topic].append(i.topic_type)
    return [i for i in mine if i.topic_type == ext.types[topic]]


class ExternalWatch:
    """The external nodes of one run: ``external`` {instance: ROS identity}; ``deadlines`` {instance: (ms, strict)}."""

    def __init__(self, graph: Graph, external: dict[str, str], dt_ns: int,
                 deadlines: dict[str, tuple[float, bool]] | None = None) -> None:
        self.dt_ns = dt_ns
        self.nodes: dict[str, _External] = {}
        for inst, identity in external.items():
            spec = graph.nodes[inst]
            stage_inputs: list[list[str]] = []
            triggers: list[str] = []
            types = {topics.CLOCK: topics.TYPES[topics.CLOCK], **{spec.topic(o.topic): o.msg_type for o in spec.outputs}}
            for st in spec.stages:
                present = [i for i in st.inputs if i.source in graph.nodes]
                types.update({spec.topic(i.topic): topics.type_of(i.topic) for i in present})
                same_step = [spec.topic(i.topic) for i in present if i.lag == 0]
                triggers += same_step or [topics.CLOCK]
                stage_inputs.append([spec.topic(i.topic) for i in present] + ([] if same_step else [topics.CLOCK]))
            ms, strict = (deadlines or {}).get(inst, (0.0, False))
            self.nodes[inst] = _External(identity, [spec.topic(o.topic) for o in spec.outputs if o.every_step],
                                         stage_inputs, sorted(set(triggers)), types, StepTimes(ms / 1e3), strict,
                                         {spec.topic(o.topic): o.frame_id for o in spec.outputs
                                          if o.every_step and Codec(o.msg_type).stamped})

    def reads(self) -> set[str]:
        """Absolute names of the topics the watch reads: the external nodes' outputs and inputs (not /clock)."""
        return {t for ext in self.nodes.values() for t in (*ext.outputs, *(t for ins in ext.stage_inputs for t in ins))
                if t != topics.CLOCK}

    def publisher(self, instance: str) -> str:
        """The ROS identity that publishes for ``instance`` (itself for a node the launcher starts)."""
        ext = self.nodes.get(instance)
        return instance if ext is None else ext.identity

    def missing(self, node: Any, matched: dict[str, int]) -> list[str]:
        """What the external nodes do not serve yet, one phrase per node; ``node``: an rclpy node for the graph
        queries, ``matched``: {output topic: publishers matched with the monitor's reader}."""
        out: list[str] = []
        for inst, ext in self.nodes.items():
            parts: list[str] = []
            unread: list[str] = []
            absent = []
            # An endpoint of another type than the contract's never matches the graph's: named as such, not as QoS
            # nor as a missing endpoint. {topic: the types it has there}, its publishers and its subscriptions.
            mistyped: tuple[dict[str, list[str]], dict[str, list[str]]] = ({}, {})
            for topic in ext.outputs:
                seen = _own(ext, node.get_publishers_info_by_topic(topic), topic, mistyped[0])
                if not seen and not mistyped[0].get(topic):
                    absent.append(topic)
                elif seen and matched.get(topic, 0) < 1:
                    qos = seen[0].qos_profile
                    unread.append(f'{topic} ({qos.reliability.name}/{qos.durability.name})')
            if absent:
                parts.append('no publisher of ' + ', '.join(absent))
            if unread:
                parts.append('publishers the graph cannot read, QoS not RELIABLE/TRANSIENT_LOCAL as the contract '
                             'says: ' + ', '.join(unread))
            for inputs in ext.stage_inputs:  # which of its inputs it reads is its own business; at least one
                if not [t for t in inputs if _own(ext, node.get_subscriptions_info_by_topic(t), t, mistyped[1])]:
                    parts.append('no subscription to any of its inputs ' + ', '.join(inputs))
            for verb, wrong in zip(('publishes', 'subscribes to'), mistyped, strict=True):
                named = [f'{t} as {", ".join(types)} (the contract: {ext.types[t]})'
                         for t, types in wrong.items() if types]
                if named:
                    parts.append(f'{verb} another message type than the contract\'s: ' + ', '.join(named))
            if parts:
                out.append(f'external node {inst} (ROS node {ext.identity}): ' + '; '.join(parts))
        return out

    def on_message(self, topic: str, data: bytes, now: float) -> str:
        """Account a message (CDR) received at ``now`` (monotonic s); '' or the one line that fails the run."""
        t_ns = stamp_ns(data)
        for ext in self.nodes.values():
            if topic in ext.outputs:
                problem = sequence_error(topic, ext.identity, t_ns, ext.last.get(topic, -1), self.dt_ns)
                if problem:
                    return problem
                frame = ext.frames.get(topic)
                if frame is not None and frame_id_of(data) != frame:  # its values would be read in the wrong axes
                    return (f'{topic}: {ext.identity} sent step {t_ns // self.dt_ns} in frame '
                            f'{frame_id_of(data)!r}; the contract says {frame!r} (header.frame_id: the axes of its '
                            'components)')
                k = ext.last[topic] = t_ns // self.dt_ns
                problem = self._arrived(ext, ext.outputs_at, k, now)
                if problem:
                    return problem
            if topic in ext.triggers:
                problem = self._arrived(ext, ext.inputs_at, t_ns // self.dt_ns, now)
                if problem:
                    return problem
        return ''

    def _arrived(self, ext: _External, at: dict[int, list[float]], k: int, now: float) -> str:
        """One more of step k's inputs or outputs; when both sides are complete, step k's wall time is recorded."""
        at.setdefault(k, []).append(now)
        ins, outs = ext.inputs_at.get(k, []), ext.outputs_at.get(k, [])
        if len(ins) < len(ext.triggers) or len(outs) < len(ext.outputs):
            return ''
        wall = max(0.0, max(outs) - max(ins))
        del ext.inputs_at[k], ext.outputs_at[k]
        if ext.times.add(k, wall) and ext.strict:
            return f'{ext.identity}: ' + overrun(k, wall, ext.times.deadline_s * 1e3)
        return ''

    def timing(self) -> dict[str, dict[str, Any]]:
        """{instance: p50/p99/max report} of the external nodes."""
        return {inst: ext.times.report() for inst, ext in self.nodes.items()}
