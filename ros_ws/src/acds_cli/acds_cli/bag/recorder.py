"""``acds record``: join a running graph (its ROS domain) and record its topics until SIGINT/SIGTERM.

A joining recorder is an observer outside the lockstep handshake: it gets the
last 1000 messages of every topic when it joins (transient-local history) and
keeps up as long as it is not more than 1000 steps behind. It follows which
steps of every per-step topic it holds (:mod:`acds_runtime.bag.coverage`; the
steps are known from the run folder's control period and graph, so give
``--run-dir``), stores the gaps in the bag's metadata (``acds.gaps``, which
``acds info`` prints) and fails (exit 1) when steps are missing between a
topic's first and last, unless ``--allow-gaps``. ``acds run --record`` records
inside the run monitor instead, in lockstep, and never misses a step.
"""

from __future__ import annotations

import sys
import threading
from pathlib import Path
from typing import Any

import rclpy
import yaml
from acds_common import topics
from acds_common.graph import build_graph
from acds_common.lockstep import message_class, release_node
from acds_runtime.bag.coverage import GAPS_KEY, UNCHECKED, StepCoverage, gaps_yaml, missing_steps
from acds_runtime.bag.writer import SKIP, BagError, BagWriter, RecordingSink, cdr_stamp_ns, check_target
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from ..arguments import ROS_DOMAINS
from . import stop_on_signals
from .player import ros_env

COMMAND_TOPICS = {topics.resolve(topics.GROUND_COMMAND), topics.resolve(topics.GROUND_ACK)}


def run_folder_info(run_dir: Path) -> tuple[int | None, dict[str, str]]:
    """(domain id, run info) from a launcher run folder (``domain_id``, ``scenario.yaml``, ``params.yaml``)."""
    run_dir = Path(run_dir)
    if not (run_dir / 'domain_id').exists():
        raise BagError(f'run folder {run_dir}: no domain_id file (is a graph running there?)')
    text = (run_dir / 'domain_id').read_text().strip()
    try:
        domain = int(text)
    except ValueError:
        domain = -1
    if domain not in ROS_DOMAINS:
        raise BagError(f'run folder {run_dir}: its domain_id file holds {text[:40]!r}, not a ROS domain id '
                       f'({ROS_DOMAINS.start}..{ROS_DOMAINS.stop - 1})')
    info: dict[str, str] = {'domain_id': str(domain)}
    if (run_dir / 'scenario.yaml').exists():
        text = (run_dir / 'scenario.yaml').read_text()
        data = yaml.safe_load(text) or {}
        info.update(scenario=text, scenario_name=str(data.get('name', '')),
                    control_period_s=repr(float(data.get('control_period_s', 0.5))),
                    nodes=','.join(data.get('nodes', [])))
    if (run_dir / 'params.yaml').exists():
        params = yaml.safe_load((run_dir / 'params.yaml').read_text()) or {}
        # by instance, as the launcher and the direct engine store them (a formation's a/em_driver and b/em_driver)
        per_node = {k.removeprefix(f'{topics.NAMESPACE}/'): v.get('ros__parameters', {}) for k, v in params.items()}
        info['params'] = yaml.safe_dump(per_node, sort_keys=True)
        info['nodes'] = ','.join(per_node)  # every node that ran, a formation vehicle's too
        steps = next((p.get('total_steps') for p in per_node.values() if 'total_steps' in p), None)
        if steps is not None:
            info['steps'] = str(steps)
    return domain, info


def step_coverage(run_dir: Path | None) -> StepCoverage | None:
    """The coverage of the run's per-step topics and /clock, from the run folder's ``params.yaml`` (its graph and
    control period); None without one."""
    if run_dir is None or not (Path(run_dir) / 'params.yaml').exists():
        return None
    params = {name.removeprefix(f'{topics.NAMESPACE}/'): p.get('ros__parameters', {})
              for name, p in (yaml.safe_load((Path(run_dir) / 'params.yaml').read_text()) or {}).items()}
    try:
        graph = build_graph(params)
        dt_ns = round(float(next(iter(params.values()))['control_period_s']) * 1e9)
    except (ValueError, KeyError, StopIteration) as exc:
        raise BagError(f'run folder {run_dir}: params.yaml does not describe a graph ({exc})') from None
    per_step = {spec.topic(out.topic) for spec, out in graph.outputs() if out.every_step}
    return StepCoverage(dt_ns, per_step | {topics.CLOCK})


class JoinedRecording:
    """The subscription callback of a joining recorder: every message into the bag, its step into the coverage."""

    def __init__(self, writer: BagWriter, node: Any, coverage: StepCoverage | None) -> None:
        self.sink = RecordingSink(writer, node)
        self.coverage = coverage
        self.gaps: dict[str, list[tuple[int, int]]] = {}

    def __call__(self, topic: str, data: bytes) -> None:
        """One raw message of ``topic`` (absolute name)."""
        self.sink(topic, data)
        if self.coverage is not None:
            self.coverage.add(topic, cdr_stamp_ns(data))

    def close(self) -> None:
        """Store the gaps (``acds.gaps``) and close the bag."""
        if self.coverage is not None:
            self.gaps = self.coverage.gaps()
        self.sink.writer.info[GAPS_KEY] = UNCHECKED if self.coverage is None else gaps_yaml(self.gaps)
        self.sink.close()


def _known(topic: str) -> bool:
    try:
        topics.type_of(topic)
    except KeyError:
        return False
    return True


def record(path: Path | str, *, storage: str = 'mcap', compression: str | None = None, select: list[str] | None = None,
           domain_id: int | None = None, run_dir: Path | None = None, stop: threading.Event | None = None,
           log: Any = None) -> JoinedRecording:
    """Record until ``stop`` is set (SIGINT/SIGTERM when run from the CLI); return the closed recording."""
    log = log or (lambda text: print(text, file=sys.stderr, flush=True))
    path = Path(path)
    check_target(path, storage, compression)
    info: dict[str, str] = {}
    if run_dir is not None:
        found, info = run_folder_info(run_dir)
        if domain_id is None:
            from acds_runtime.launcher import DomainLease
            if not DomainLease.held(found):  # the run has ended (its folder keeps domain_id): nothing would come
                raise BagError(f'run folder {run_dir}: its graph is not running (no run holds its domain {found}); '
                               'record joins a running graph')
            domain_id = found
    coverage = step_coverage(run_dir)
    if domain_id is None:
        raise BagError('record: which graph? give --domain N or --run-dir RUN_FOLDER')
    wanted = [topics.resolve(t) for t in select] if select else [topics.resolve(t) for t in topics.all_types()]
    unknown = [t for t in wanted if not _known(t)]
    if unknown:
        raise BagError(f'record: unknown topic {", ".join(unknown)} (known: {", ".join(sorted(topics.all_types()))}, '
                       'or one of them under a formation vehicle\'s namespace)')
    stop = stop or threading.Event()
    ros_env(domain_id)
    context = Context()
    rclpy.init(context=context, domain_id=domain_id, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    node = Node('acds_recorder', namespace=topics.NAMESPACE, context=context)
    writer = BagWriter(path, storage, info, compression=compression)
    sink = JoinedRecording(writer, node, coverage)
    from acds_common.lockstep import COMMAND_QOS, LOCKSTEP_QOS
    for topic in wanted:
        if topic in SKIP:
            continue
        qos = COMMAND_QOS if topic in COMMAND_TOPICS else LOCKSTEP_QOS
        node.create_subscription(message_class(topics.type_of(topic)), topic, lambda d, t=topic: sink(t, d), qos, raw=True)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    log(f'[record] recording domain {domain_id} into {path} ({storage}, {writer.compression} compression); '
        'stop with Ctrl-C or SIGTERM')
    try:
        while not stop.is_set() and context.ok() and not writer.error:
            executor.spin_once(timeout_sec=0.05)
    finally:
        sink.close()
        release_node(executor, node, context)
    if writer.error:
        raise BagError(writer.error)
    return sink


def main_record(args: Any) -> int:
    """CLI body of ``acds record``."""
    stop = stop_on_signals()
    try:
        recording = record(args.path, storage=args.storage, compression=args.compression, select=args.topics,
                           domain_id=args.domain, run_dir=Path(args.run_dir) if args.run_dir else None, stop=stop)
    except BagError as exc:
        print(f'acds record: {exc}', file=sys.stderr)
        return 2
    return report_recording(recording, args.allow_gaps)


def report_recording(recording: JoinedRecording, allow_gaps: bool) -> int:
    """Print what was recorded and the gaps; exit 1 when steps are missing (0 with ``allow_gaps``)."""
    writer = recording.sink.writer
    total = sum(writer.counts.values())
    print(f'[record] closed {writer.path}: {total} messages on {len(writer.counts)} topics', file=sys.stderr)
    if recording.coverage is None:
        print('[record] steps not checked for gaps: the control period and graph come from the run folder '
              '(give --run-dir)', file=sys.stderr)
    for topic, ranges in recording.gaps.items():
        print(f'[record] {topic}: {missing_steps(ranges)} step(s) missing between its first and last '
              f'({", ".join(f"{a}–{b}" for a, b in ranges[:5])}{", …" if len(ranges) > 5 else ""}): the recorder fell '
              'behind the history depth', file=sys.stderr)
    print(writer.path)
    if recording.gaps and not allow_gaps:
        print(f'acds record: {writer.path}: {len(recording.gaps)} topic(s) miss steps (stored in its metadata as '
              'acds.gaps; --allow-gaps accepts such a bag)', file=sys.stderr)
        return 1
    return 0
