"""``acds record``: join a running graph (its ROS domain) and record its topics until SIGINT/SIGTERM.

A joining recorder is an observer outside the lockstep handshake: it gets the
last 1000 messages of every topic when it joins (transient-local history) and
keeps up as long as it is not more than 1000 steps behind; at the end it
reports any steps it missed. ``acds run --record`` records inside the run
monitor instead, in lockstep, and never misses a step.
"""

from __future__ import annotations

import sys
import threading
from pathlib import Path
from typing import Any

import rclpy
import yaml
from acds_common import topics
from acds_common.lockstep import message_class, release_node
from acds_runtime.bag.writer import SKIP, BagError, BagWriter, RecordingSink, cdr_stamp_ns, check_target, stamped
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from . import stop_on_signals
from .player import ros_env

COMMAND_TOPICS = {topics.resolve(topics.GROUND_COMMAND), topics.resolve(topics.GROUND_ACK)}


def run_folder_info(run_dir: Path) -> tuple[int | None, dict[str, str]]:
    """(domain id, run info) from a launcher run folder (``domain_id``, ``scenario.yaml``, ``params.yaml``)."""
    run_dir = Path(run_dir)
    if not (run_dir / 'domain_id').exists():
        raise BagError(f'run folder {run_dir}: no domain_id file (is a graph running there?)')
    domain = int((run_dir / 'domain_id').read_text().strip())
    info: dict[str, str] = {'domain_id': str(domain)}
    if (run_dir / 'scenario.yaml').exists():
        text = (run_dir / 'scenario.yaml').read_text()
        data = yaml.safe_load(text) or {}
        info.update(scenario=text, scenario_name=str(data.get('name', '')),
                    control_period_s=repr(float(data.get('control_period_s', 0.5))),
                    nodes=','.join(data.get('nodes', [])))
    if (run_dir / 'params.yaml').exists():
        params = yaml.safe_load((run_dir / 'params.yaml').read_text()) or {}
        per_node = {k.rsplit('/', 1)[-1]: v.get('ros__parameters', {}) for k, v in params.items()}
        info['params'] = yaml.safe_dump(per_node, sort_keys=True)
        steps = next((p.get('total_steps') for p in per_node.values() if 'total_steps' in p), None)
        if steps is not None:
            info['steps'] = str(steps)
    return domain, info


def _known(topic: str) -> bool:
    try:
        topics.type_of(topic)
    except KeyError:
        return False
    return True


def record(path: Path | str, *, storage: str = 'mcap', compression: str | None = None, select: list[str] | None = None,
           domain_id: int | None = None, run_dir: Path | None = None, stop: threading.Event | None = None,
           log: Any = None) -> BagWriter:
    """Record until ``stop`` is set (SIGINT/SIGTERM when run from the CLI); return the closed writer."""
    log = log or (lambda text: print(text, file=sys.stderr, flush=True))
    path = Path(path)
    check_target(path, storage, compression)
    info: dict[str, str] = {}
    if run_dir is not None:
        found, info = run_folder_info(run_dir)
        domain_id = domain_id if domain_id is not None else found
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
    sink = RecordingSink(writer, node)
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
    return writer


def gaps(bag_path: Path) -> dict[str, int]:
    """Per stamped topic: steps missing between its first and last message (a recorder that fell behind).

    Streamed: messages come in stamp order, so each topic needs only its first step, last step and the
    number of distinct steps seen.
    """
    from .reader import open_bag
    bag = open_bag(bag_path)
    dt = bag.control_period_ns
    if not dt:
        return {}
    watched = [t for t, ty in bag.types.items() if not t.endswith('/diagnostics') and bag.has(t) and stamped(ty)]
    seen: dict[str, list[int]] = {}  # topic → [first step, last step, distinct steps]
    for topic, _, data in bag.messages(watched):
        step = cdr_stamp_ns(data) // dt
        s = seen.get(topic)
        if s is None:
            seen[topic] = [step, step, 1]
        elif step != s[1]:
            s[1], s[2] = step, s[2] + 1
    return {topic: missing for topic, (first, last, n) in seen.items() if (missing := last - first + 1 - n)}


def main_record(args: Any) -> int:
    """CLI body of ``acds record``."""
    stop = stop_on_signals()
    try:
        writer = record(args.path, storage=args.storage, compression=args.compression, select=args.topics, domain_id=args.domain,
                        run_dir=Path(args.run_dir) if args.run_dir else None, stop=stop)
    except BagError as exc:
        print(f'acds record: {exc}', file=sys.stderr)
        return 2
    total = sum(writer.counts.values())
    print(f'[record] closed {writer.path}: {total} messages on {len(writer.counts)} topics', file=sys.stderr)
    missing = gaps(writer.path)
    for topic, n in missing.items():
        print(f'[record] WARNING: {topic}: {n} steps missing (the recorder fell behind the history depth)',
              file=sys.stderr)
    print(writer.path)
    return 0
