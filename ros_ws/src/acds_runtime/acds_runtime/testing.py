"""launch_testing-style pytest harness for the ACDS graph: a pytest plugin (entry point ``pytest11``, issue 20 §5).

``launch_graph`` starts a scenario's processes in their own ROS domain (so
parallel tests never cross-talk), gives the test the running
:class:`~acds_runtime.launcher.GraphRun` and its :class:`RunMonitor`, and on exit
stops every process and asserts that none is left behind. Waits are on
messages, with timeouts that name what is missing.

A user's package tests its own node against the emulator with it: ``launch_graph(scenario,
external=['acds_controller=my_node'])`` leaves that node of the graph to the user, and
:func:`external_node` starts the user's process on the graph's domain (and stops it, however the
test ends). Installed with ``acds_runtime``, the fixtures need no ``conftest.py``.
"""

from __future__ import annotations

import os
import signal
import subprocess
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from acds_common import topics
from acds_common.scenario import Scenario, load_scenario

from .flight_software import external_env, stop_process
from .launcher import GraphRun, LaunchError


def failure_of_hung(graph: GraphRun, node: str) -> str:
    """Stop ``node``'s process (SIGSTOP, as a hung node) and return the line the run fails with; the process is
    continued (SIGCONT) however the wait ends, so the harness can stop it."""
    pid = graph.processes[node].popen.pid
    os.kill(pid, signal.SIGSTOP)
    try:
        with pytest.raises(LaunchError) as err:
            graph.wait()
    finally:
        os.kill(pid, signal.SIGCONT)
    return str(err.value)


def alive(pid: int) -> bool:
    """Whether a process (or a zombie not yet reaped) with this pid exists."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def wait_for_messages(graph: GraphRun, topic: str, count: int, timeout_s: float = 60.0) -> list[Any]:
    """Wait until ``count`` messages of ``topic`` arrived; fail naming the topic and what did arrive, or the
    node that ended first."""
    monitor = graph.monitor
    assert monitor is not None
    name = topics.resolve(topic)
    monitor.wait_for(lambda: monitor.count(name) >= count or graph.exit_report() is not None, timeout_s)
    if monitor.count(name) < count:
        got = {t: len(v) for t, v in monitor.snapshot().items()}
        ended = graph.exit_report()
        why = f'; a node ended first: {ended}' if ended is not None else _not_started(graph)
        pytest.fail(f'waited for {count} messages on {name}; received per topic: {got}{why}')
    return monitor.messages(topic)


def _not_started(graph: GraphRun) -> str:
    """'' once the graph has started; before, what it still waits for (an external node's missing endpoints)."""
    monitor = graph.monitor
    if monitor is None or monitor.ready:
        return ''
    return '; the graph has not started, it waits for: ' + ' | '.join(
        monitor.waiting_for or ['the run monitor to match every declared publisher'])


def ground_command(graph: GraphRun, text: str, timeout_s: float = 60.0) -> str:
    """Send one live ground command to the running graph and return the mode manager's answer to it (the
    ``ground/ack`` line that names it). The command is published once, after the publisher has matched the
    mode manager's subscription (reliable QoS: it then arrives); fail naming what was missing."""
    from acds_common.lockstep import COMMAND_QOS
    from std_msgs.msg import String

    monitor = graph.monitor
    assert monitor is not None
    pub = monitor.node.create_publisher(String, topics.GROUND_COMMAND, COMMAND_QOS)
    try:
        if not monitor.wait_for(lambda: pub.get_subscription_count() > 0 or graph.exit_report() is not None,
                                timeout_s) or pub.get_subscription_count() == 0:
            pytest.fail(f'no node subscribed to {topics.resolve(topics.GROUND_COMMAND)} within {timeout_s:g} s; '
                        f'{graph.exit_report() or "every node still runs"}{_not_started(graph)}')
        pub.publish(String(data=text))

        def answers() -> list[str]:
            return [m.data for m in monitor.messages(topics.GROUND_ACK) if text in m.data]

        monitor.wait_for(lambda: bool(answers()) or graph.exit_report() is not None, timeout_s)
        if not answers():
            acks = [m.data for m in monitor.messages(topics.GROUND_ACK)]
            pytest.fail(f'no answer to the ground command {text!r} within {timeout_s:g} s; answers seen: {acks}; '
                        f'{graph.exit_report() or "every node still runs"}{_not_started(graph)}')
        return answers()[0]
    finally:
        monitor.node.destroy_publisher(pub)


def stream_digests(monitor: Any) -> dict[str, str]:
    """SHA-256 of each topic's kept message stream (for comparing two runs topic by topic).

    ``/diagnostics`` has several publishers, so only each node's own order is defined, and the time
    owner's statuses carry its wall time: its digest is over each node's statuses in that node's
    order, wall-clock keys (:data:`acds_common.messages.WALL_CLOCK_PREFIX`) left out.
    """
    import hashlib

    from acds_common.cdr import Codec
    from acds_common.messages import WALL_CLOCK_PREFIX

    out = {}
    for topic, msgs in sorted(monitor.snapshot().items()):
        h = hashlib.sha256()
        if topic == topics.resolve(topics.DIAGNOSTICS):
            codec = Codec(topics.TYPES[topics.DIAGNOSTICS])
            by_node: dict[str, list[Any]] = {}
            for raw in msgs:
                t_ns, statuses = codec.decode(raw)
                for st in statuses:
                    values = tuple(kv for kv in st.values if not kv[0].startswith(WALL_CLOCK_PREFIX))
                    by_node.setdefault(st.name, []).append((t_ns, st._replace(values=values)))
            h.update(repr(sorted(by_node.items())).encode())
        else:
            for raw in msgs:
                h.update(raw)
        out[topic] = h.hexdigest()
    return out


@contextmanager
def _launch(tmp_path: Path, scenario: str | Scenario, **kwargs: Any) -> Iterator[GraphRun]:
    sc = load_scenario(scenario) if isinstance(scenario, str) else scenario
    lines: list[str] = []
    kwargs.setdefault('keep', True)  # tests read the messages back; their runs are short
    graph = GraphRun(sc, tmp_path / f'run_{sc.name}_{len(list(tmp_path.glob("run_*")))}',
                     echo=lines.append, **kwargs)
    graph.output = lines  # type: ignore[attr-defined]
    try:
        graph.start()
        yield graph
    finally:
        graph.stop()
        pids = [p.popen.pid for p in graph.processes.values()]
        left = [pid for pid in pids if alive(pid)]
        assert not left, f'processes left behind: {left}'


@pytest.fixture
def launch_graph(tmp_path: Path) -> Callable[..., Any]:
    """``with launch_graph('scenario', steps=N, overrides={...}) as graph: result = graph.wait()``."""
    def factory(scenario: str | Scenario, **kwargs: Any) -> Any:
        return _launch(tmp_path, scenario, **kwargs)
    return factory


@contextmanager
def external_node(graph: GraphRun, argv: Sequence[str], env: dict[str, str] | None = None,
                  stop_timeout_s: float = 10.0) -> Iterator[subprocess.Popen[str]]:
    """Run ``argv`` (a user's node) as an external node of ``graph`` (:func:`external_env`; ``env`` adds to it).

    Its output goes to ``<run folder>/external_<n>.log``. On exit it gets SIGINT, then SIGKILL after
    ``stop_timeout_s``, and is reaped: no test leaves it behind.
    """
    log = graph.run_dir / f'external_{len(list(graph.run_dir.glob("external_*.log")))}.log'
    with log.open('w') as out:
        proc = subprocess.Popen(list(argv), stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT, text=True,
                                env=external_env(graph, env), start_new_session=True)
        try:
            yield proc
        finally:
            stop_process(proc, stop_timeout_s)


def read_until(proc: subprocess.Popen[str], wanted: Callable[[str], bool]) -> str:
    """Read ``proc``'s stderr line by line until a line ``wanted`` accepts (a wait on the process's own output, not
    on a timer) and return what it said so far; fail the test with all it said when it ended first (why a run
    ended early is in those lines)."""
    assert proc.stderr is not None, 'start the process with stderr=subprocess.PIPE'
    said = []
    for line in proc.stderr:
        said.append(line)
        if wanted(line):
            return ''.join(said)
    pytest.fail(f'the process ended (exit {proc.wait()}) before the line waited for; it said:\n{"".join(said)}')


def install_outside(source: Path, tmp: Path) -> Path:
    """Install the package folder ``source`` (a fixture package outside the workspace) as a user would, into
    ``tmp/site`` (``pip install --target``: its dist-info with its entry points, its console scripts in
    ``bin/``), from a copy of it in ``tmp/src``; the site folder, to put on ``PYTHONPATH`` of a fresh process."""
    import shutil
    import sys

    src = tmp / 'src'
    shutil.copytree(source, src, ignore=shutil.ignore_patterns('build', '*.egg-info', '__pycache__'))
    site = tmp / 'site'
    proc = subprocess.run([sys.executable, '-m', 'pip', 'install', '--quiet', '--disable-pip-version-check',
                           '--no-deps', '--no-build-isolation', '--no-index', '--target', str(site), str(src)],
                          capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return site
