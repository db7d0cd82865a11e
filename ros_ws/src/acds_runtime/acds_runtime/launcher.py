"""The Python launcher: one OS process per node, an isolated ROS domain, no orphans.

``GraphRun`` starts each node of a scenario from its console-script entry
point with parameters from the scenario (a generated ``--params-file``), in
its own ``ROS_DOMAIN_ID`` (an exclusive lock per domain, so parallel runs
never cross-talk) with localhost-only discovery. It forwards each child's
output with a ``[node]`` prefix, hosts the :class:`RunMonitor`, reports
progress, and stops every child on completion, on SIGINT/SIGTERM, or as soon
as any node dies (naming it, with its exit code and last lines).
"""

from __future__ import annotations

import fcntl
import math
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import yaml
from acds_common import numeric_config, topics
from acds_common.graph import Graph, build_graph, monitor_allows
from acds_common.lockstep import (
    CPU_ENV,
    EXIT_LOCKSTEP,
    FAILURE_LINES,
    LAUNCHER_PID_ENV,
    READY_TIMEOUT_S,
    STACK_SIGNAL,
    STOP_GRACE_S,
    clock_step_waited_for,
    completed_step,
    is_stopped,
)
from acds_common.parameters import node_parameters, parameters_yaml
from acds_common.scenario import Scenario
from acds_common.timing import DEADLINE_FAILURE, parse_line

from . import shm
from .external import ExternalWatch
from .monitor import RunMonitor
from .placement import describe, node_placement
from .summary import RunObserver

VENV_BIN = Path(sys.executable).parent
FASTDDS_PROFILE = Path(__file__).with_name('fastdds_profile.xml')
DOMAIN_LOCK_DIR = Path(os.environ.get('ACDS_DOMAIN_LOCK_DIR', '/tmp/acds_domains'))
#: Domain IDs handed out to runs (0 stays free for a user's own ROS graph).
DOMAIN_RANGE = range(11, 100)
#: Wall seconds the run monitor may go without taking in a single message while it drains a completed run's last
#: steps; a slow monitor on a starved machine keeps going as long as it advances (issue 18 §1).
DRAIN_STALL_S = 30.0


class LaunchError(RuntimeError):
    """The graph could not run to completion; the message names the node and the reason."""


@dataclass
class NodeProcess:
    """One child process and the tail of its output."""

    name: str
    popen: subprocess.Popen[str]
    tail: deque[str] = field(default_factory=lambda: deque(maxlen=40))
    reader: threading.Thread | None = None
    #: Seconds it was given to stop after SIGINT when the launcher had to SIGKILL it (None: it stopped, or died).
    killed_after_s: float | None = None
    #: The last step of the run, as the time owner announced it on leaving a completed run.
    completed_step: int | None = None
    #: The node's step timing, as it announced it on leaving (:mod:`acds_common.timing`); None until then.
    timing: dict[str, Any] | None = None
    #: When the node announced its lockstep failure (monotonic s; None: it did not). A failed node may still be
    #: leaving while the nodes waiting on it time out: the first to fail is the one the run names.
    failed_at: float | None = None


@dataclass
class RunResult:
    """What a completed run leaves: its summary (computed while it ran), exit codes, wall time, the bag."""

    scenario: Scenario
    steps: int
    wall_seconds: float
    summary: dict[str, Any]
    exit_codes: dict[str, int] = field(default_factory=dict)
    bag: Path | None = None
    #: The run's monitor (its kept messages, when the run was started with ``keep=True``).
    monitor: RunMonitor | None = None
    #: What went wrong without costing the run anything (a node that hung on its way out).
    warnings: list[str] = field(default_factory=list)
    #: Each node's step wall times (p50/p99/max ms, steps over its deadline), by instance: the machine's, never
    #: the data's, so kept out of the summary (and of its truth digest); None for a node that left no report.
    timing: dict[str, dict[str, Any] | None] = field(default_factory=dict)


#: How long a node that printed its failure is given to exit before it is reported as failed but still running.
FAILED_EXIT_S = 3.0


class DomainLease:
    """An exclusive ROS_DOMAIN_ID for one run: an ``flock`` on a file in /tmp.

    The lock belongs to the open file, which every node process inherits
    (:attr:`fd`, passed to the children): the domain stays leased until the launcher
    *and* its last child have exited, so a run that lands on the domain next can never
    meet an orphan of this one.
    """

    def __init__(self, domain: int | None = None) -> None:
        """The first free domain from one the pid picks, or exactly ``domain`` (LaunchError when another run holds it:
        an external node joins a run on the domain its user chose, ``acds run --domain``)."""
        DOMAIN_LOCK_DIR.mkdir(parents=True, exist_ok=True)
        start = os.getpid() % len(DOMAIN_RANGE)
        choices = [domain] if domain is not None else [DOMAIN_RANGE[(start + i) % len(DOMAIN_RANGE)]
                                                       for i in range(len(DOMAIN_RANGE))]
        for candidate in choices:
            fh = open(DOMAIN_LOCK_DIR / f'domain_{candidate}.lock', 'w')  # noqa: SIM115 (held for the run)
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                fh.close()
                continue
            self.domain_id, self._fh = candidate, fh
            os.set_inheritable(fh.fileno(), True)
            #: The zombie shared-memory ports of the domain removed as it was leased (:func:`shm.clean_domain`).
            self.shm_cleared = shm.clean_domain(candidate)
            return
        if len(choices) == 1:
            raise LaunchError(f'ROS domain {choices[0]} is in use by another run or acds play (lock {DOMAIN_LOCK_DIR})')
        raise LaunchError(f'no free ROS domain in {DOMAIN_RANGE.start}..{DOMAIN_RANGE.stop - 1}: '
                          f'too many runs at once (locks in {DOMAIN_LOCK_DIR})')

    @staticmethod
    def held(domain: int) -> bool:
        """Whether a run (or a child of one), or an ``acds play``, holds ``domain`` now."""
        path = DOMAIN_LOCK_DIR / f'domain_{domain}.lock'
        return path.exists() and shm.lock_held(path, probe=True)

    @property
    def fd(self) -> int:
        """The lock file's descriptor (children inherit it, and with it the lease)."""
        return self._fh.fileno()

    def close(self) -> None:
        """Release this process's hold on the domain (children still holding it keep it leased)."""
        self._fh.close()


def _last_lines(proc: NodeProcess) -> str:
    """A node's last output lines, indented under its name, for a failure report."""
    return f'\n  last lines of {proc.name}:\n' + '\n'.join(f'    {line}' for line in proc.tail)


class GraphRun:
    """Run a scenario's node graph to completion (use as a context manager)."""

    def __init__(self, scenario: Scenario, run_dir: Path, *, steps: int | None = None, rtf: float = 0.0,
                 echo: Callable[[str], None] | None = None, progress: Callable[[int, int, float], None] | None = None,
                 overrides: dict[str, dict[str, Any]] | None = None,
                 record: Path | None = None, record_storage: str = 'mcap', record_compression: str | None = None,
                 keep: bool = False, live: Callable[[dict[str, dict[str, Any]]], Any] | None = None,
                 external: Iterable[str] = (), domain: int | None = None, peers: Iterable[str] = (),
                 notice: Callable[[str], None] | None = None, place: bool = False):
        self.scenario = scenario
        #: Place the node processes on the machine's two CPUs (:mod:`acds_runtime.placement`; only with exactly two, and
        #: never in a run paced to the wall clock: there a node's deadline matters, and a bound process cannot move
        #: away from other load). Off unless asked (``acds run``, ``acds bench``): graphs run side by side (a study's
        #: samples, the tests' workers) would all put their chains on the same CPU.
        self.place = place and rtf == 0
        #: {instance: CPU} of the node processes placed (empty: the operating system places them).
        self.placement: dict[str, int] = {}
        self.run_dir = Path(run_dir)
        self.steps = steps if steps is not None else scenario.total_steps()
        self.rtf = rtf
        self.echo = echo or (lambda line: print(line, file=sys.stderr, flush=True))
        #: The launcher's own lines for the user (what an external node must do to join), beside the nodes' output.
        self.notice = notice or self.echo
        self.progress = progress
        self.overrides = overrides
        #: Record every topic into this rosbag2 bag (written by the run monitor, in lockstep).
        self.record = Path(record) if record is not None else None
        self.record_storage = record_storage
        #: zstd | none (None: the storage's default, zstd chunks for MCAP).
        self.record_compression = record_compression
        self.bag_writer: Any = None
        #: Keep every message in the run monitor (tests; a long run would grow without bound).
        self.keep = keep
        #: Live view: called with the node parameters at start, returns a sink the monitor feeds (and closes at stop).
        self.live = live
        self.live_sink: Any = None
        self.graph: Graph | None = None
        self.observer: RunObserver | None = None
        self.processes: dict[str, NodeProcess] = {}
        self._shm_before: set[str] | None = None
        #: Zombie shared-memory files of this run's killed processes, removed when it stopped.
        self.shm_removed: list[str] = []
        self.lease: DomainLease | None = None
        self.monitor: RunMonitor | None = None
        self._t0 = 0.0
        #: The SIGTSTP handler this run replaced (restored when it stops); None when not installed.
        self._tstp_before: Any = None
        #: ``NODE[=ROS_NODE_NAME]`` of the nodes the user runs, beside the scenario's ``external`` (issue 20 §1).
        self.external_items = list(external)
        #: {instance: ROS identity} of the external nodes (once started).
        self.external: dict[str, str] = {}
        #: The ROS domain asked for (None: the first free one).
        self.domain = domain
        #: Hosts whose participants discovery also contacts (ROS_STATIC_PEERS): an external node on another machine.
        self.peers = list(peers)
        #: How long the graph may take to start, external nodes included (the nodes' own readiness timeout).
        self.ready_timeout_s = max(scenario.get('', 'input_timeout'), READY_TIMEOUT_S)

    # ---- lifecycle ----------------------------------------------------------------------------------
    def __enter__(self) -> GraphRun:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def env(self) -> dict[str, str]:
        """Environment of every child: isolated domain, localhost discovery, plain log lines, and this process's
        numeric configuration, which each node process compares with its own before it starts
        (:func:`acds_common.lockstep.numeric_mismatch`)."""
        assert self.lease is not None
        env = dict(os.environ)
        env.update(
            ROS_DOMAIN_ID=str(self.lease.domain_id),
            ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
            ROS_LOG_DIR=str(self.run_dir / 'ros_log'),
            FASTRTPS_DEFAULT_PROFILES_FILE=str(FASTDDS_PROFILE),
            RCUTILS_CONSOLE_OUTPUT_FORMAT='[{severity}] {message}',
            RCUTILS_COLORIZED_OUTPUT='0',
            PYTHONUNBUFFERED='1',
            **{LAUNCHER_PID_ENV: str(os.getpid()), numeric_config.ENV: numeric_config.to_env()},
        )
        env.pop('ROS_LOCALHOST_ONLY', None)
        env.pop(CPU_ENV, None)  # set per node process by its placement
        if self.peers:  # discovery stays off the subnet but reaches these hosts (an external node's, issue 20 §6)
            env['ROS_STATIC_PEERS'] = ';'.join(self.peers)
        else:
            env.pop('ROS_STATIC_PEERS', None)
        return env

    def start(self) -> None:
        """Lease a domain, write the parameters, start the monitor and every node."""
        if self.record is not None:
            from .bag.writer import BagError, check_target
            try:
                check_target(self.record, self.record_storage, self.record_compression)
            except BagError as exc:
                raise LaunchError(str(exc)) from None
        try:
            self.external = self.scenario.external(self.external_items)
        except ValueError as exc:
            raise LaunchError(str(exc)) from None
        self.run_dir.mkdir(parents=True, exist_ok=True)
        self._shm_before = shm.snapshot()
        self.lease = DomainLease(self.domain)
        (self.run_dir / 'domain_id').write_text(f'{self.lease.domain_id}\n')
        (self.run_dir / 'scenario.yaml').write_text(yaml.safe_dump(self.scenario.raw, sort_keys=False))
        env = self.env()
        os.environ['FASTRTPS_DEFAULT_PROFILES_FILE'] = env['FASTRTPS_DEFAULT_PROFILES_FILE']
        os.environ.setdefault('ROS_LOG_DIR', env['ROS_LOG_DIR'])
        os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
        if self.peers:
            os.environ['ROS_STATIC_PEERS'] = env['ROS_STATIC_PEERS']
        else:
            os.environ.pop('ROS_STATIC_PEERS', None)
        params = node_parameters(self.scenario, self.steps, self.rtf, self.overrides, self.external)
        self.graph = build_graph(params)
        # Each node's console script: this environment's, else the first on PATH (a node package installed elsewhere).
        search = os.pathsep.join([str(VENV_BIN), env.get('PATH', '')])
        executables = {name: shutil.which(spec.name, path=search) for name, spec in self.graph.nodes.items()
                       if name not in self.external}
        missing = sorted(f'{name} (package {self.graph.nodes[name].package})' for name, exe in executables.items() if not exe)
        if missing:
            self.lease.close()
            self.lease = None
            raise LaunchError(f'no executable for node(s) {", ".join(missing)} in {VENV_BIN} or on PATH: is the package '
                              'installed?')
        self.observer = RunObserver(self.scenario, self.graph)
        params_file = self.run_dir / 'params.yaml'
        params_file.write_text(parameters_yaml(params))
        if self.live is not None:
            try:
                self.live_sink = self.live(params)
            except Exception:
                self.lease.close()
                self.lease = None
                raise
        record = None
        if self.record is not None:
            from .bag.writer import BagError, BagWriter, RecordingSink, run_info
            try:
                self.bag_writer = BagWriter(self.record, self.record_storage,
                                            run_info(self.scenario, self.steps, params, self.lease.domain_id,
                                                     self.run_dir.name),
                                            compression=self.record_compression)
            except BagError as exc:
                self.lease.close()
                self.lease = None
                if self.live_sink is not None:
                    self.live_sink.close()
                    self.live_sink = None
                raise LaunchError(str(exc)) from None

            def record(node: Any) -> Any:
                return RecordingSink(self.bag_writer, node)
        dt_ns = round(self.scenario.control_period_s * 1e9)
        watch = ExternalWatch(self.graph, self.external, dt_ns,
                              {i: (params[i]['deadline_ms'], params[i]['deadline_strict']) for i in self.external
                               if 'deadline_ms' in params[i]}) if self.external else None
        self.monitor = RunMonitor(self.lease.domain_id, dt_ns, self.graph, on_clock=self._on_clock, record=record,
                                  observer=self.observer, keep=self.keep, sink=self.live_sink, external=watch)
        self._t0 = time.monotonic()
        for name, identity in self.external.items():
            spec = self.graph.nodes[name]
            self.notice(f'[acds] external node {name}: waiting (at most {self.ready_timeout_s:g} s) for ROS node '
                      f'{identity.rpartition("/")[2]} in namespace {spec.namespace} on ROS_DOMAIN_ID='
                      f'{self.lease.domain_id} (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST on this host); its contract: '
                      f'./scripts/acds contract {self.scenario.name} --node {name}')
        self.placement = node_placement(self.graph, self.external) if self.place else {}
        if self.placement:
            self.notice(f'[acds] node processes placed on the two CPUs ({describe(self.placement)})')
        for name, spec in self.graph.nodes.items():
            if name in self.external:
                continue
            exe = executables[name]
            node_env = dict(env, **{CPU_ENV: str(self.placement[name])}) if name in self.placement else env
            namespace = [] if spec.namespace == topics.NAMESPACE else ['-r', f'__ns:={spec.namespace}']
            popen = subprocess.Popen(
                [str(exe), '--ros-args', *namespace, '--params-file', str(params_file)],
                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                text=True, env=node_env, start_new_session=True, pass_fds=(self.lease.fd,))
            proc = NodeProcess(name, popen)
            proc.reader = threading.Thread(target=self._forward, args=(proc, popen.stdout), daemon=True)
            proc.reader.start()
            self.processes[name] = proc
        if threading.current_thread() is threading.main_thread():
            self._tstp_before = signal.signal(signal.SIGTSTP, self._suspend)

    def _suspend(self, _signum: int, _frame: Any) -> None:
        """Ctrl-Z (SIGTSTP): stop every node with the launcher, and continue them when it is continued (issue 18
        §4). The nodes run in sessions of their own, so the terminal's signal reaches only the launcher; a graph
        whose nodes ran on would wait on a stopped run monitor and time out."""
        self._signal_nodes(signal.SIGSTOP)
        # SIGSTOP, not the default action of SIGTSTP, which the kernel discards in an orphaned process group (a
        # launcher started in a session of its own); the shell sees the job stopped either way.
        os.kill(os.getpid(), signal.SIGSTOP)  # returns on SIGCONT (fg, bg)
        self._signal_nodes(signal.SIGCONT)

    def _signal_nodes(self, sig: signal.Signals) -> None:
        for proc in self.processes.values():
            if proc.popen.poll() is None:
                try:
                    os.killpg(proc.popen.pid, sig)
                except ProcessLookupError:
                    pass

    def _forward(self, proc: NodeProcess, stream: IO[str] | None) -> None:
        assert stream is not None
        try:
            self._forward_lines(proc, stream)
        except ValueError:  # closed by stop() after its wait (a process outside the group kept the pipe open)
            pass

    def _forward_lines(self, proc: NodeProcess, stream: IO[str]) -> None:
        for line in stream:
            line = line.rstrip('\n')
            proc.completed_step = completed_step(line) if proc.completed_step is None else proc.completed_step
            timing = parse_line(line)
            if timing is not None:
                proc.timing = timing
                continue
            if proc.failed_at is None and any(mark in line for mark in FAILURE_LINES):
                proc.failed_at = time.monotonic()
            proc.tail.append(line)
            self.echo(f'[{proc.name}] {line}')

    def _on_clock(self, t_ns: int) -> None:
        if self.progress is not None:
            self.progress(round(t_ns / (self.scenario.control_period_s * 1e9)), self.steps,
                          time.monotonic() - self._t0)

    def wait(self) -> RunResult:
        """Wait until the time owner completes; raise LaunchError naming the node that failed first (a node that
        announced a lockstep failure before the others timed out waiting on it, or the first to die)."""
        assert self.graph is not None
        owner = self.processes[self.graph.time_owner]
        while True:
            self._check_health()
            ended = {name: proc.popen.poll() for name, proc in self.processes.items()}
            if ended[owner.name] == 0:
                return self._complete()
            failed = [proc for name, proc in self.processes.items()
                      if ended[name] is not None or proc.failed_at is not None]
            if failed:
                first = min(failed, key=lambda p: p.failed_at if p.failed_at is not None else math.inf)
                code = ended[first.name]
                if code is None:  # it said it failed: its exit code, when it leaves within a moment
                    try:
                        code = first.popen.wait(timeout=FAILED_EXIT_S)
                    except subprocess.TimeoutExpired:
                        code = EXIT_LOCKSTEP
                raise LaunchError(self._death_report(first, code))
            try:
                owner.popen.wait(timeout=0.05)
            except subprocess.TimeoutExpired:
                pass

    def exit_report(self) -> str | None:
        """The death report of the first node process that has exited, or None while every node runs."""
        for proc in self.processes.values():
            code = proc.popen.poll()
            if code is not None:
                return self._death_report(proc, code)
        return None

    def _check_health(self) -> None:
        """Fail the run at once on a bag write error or on data from outside the graph."""
        if self.bag_writer is not None and self.bag_writer.error:
            raise LaunchError(self.bag_writer.error)
        if self.monitor is not None and self.monitor.failure:
            raise LaunchError(self.monitor.failure)
        if self.monitor is not None and self.monitor.intrusion:
            raise LaunchError(f'data from outside the graph: {self.monitor.intrusion}; the run is not valid')
        if self.external and self.monitor is not None and not self.monitor.ready \
                and time.monotonic() - self._t0 > self.ready_timeout_s:
            raise LaunchError(f'the graph never started: after {self.ready_timeout_s:g} s (scenario key input_timeout): '
                              + ' | '.join(self.monitor.waiting_for or ['the run monitor is not ready']))

    def _death_report(self, proc: NodeProcess, code: int) -> str:
        if proc.reader is not None and proc.popen.poll() is not None:
            proc.reader.join(timeout=2.0)
        how = f'killed by signal {signal.Signals(-code).name}' if code < 0 else f'exit code {code}'
        failure = [line for line in proc.tail if 'FAILURE' in line or 'ERROR' in line]
        if proc.killed_after_s is not None:
            head = f'node {proc.name} did not stop within {proc.killed_after_s:g} s of SIGINT (the launcher killed it)'
        elif proc.popen.poll() is None:
            head = f'node {proc.name} failed'
        else:
            head = f'node {proc.name} died ({how})'
        if failure:
            head += f': {failure[-1]}'
        over_deadline = any(DEADLINE_FAILURE in line for line in failure)
        report = _last_lines(proc)
        on_monitor = [p for p in self.processes.values() if self._waited_on_monitor(p)]
        if on_monitor and self.monitor is not None:
            # a node waited on the launcher's own run monitor (it paces the time owner): no node is to blame
            head = (f'the run monitor (in this launcher) stopped acknowledging /clock: it had taken in /clock up to '
                    f'step {self.monitor.clock_step}, {self.monitor.received()} messages in all; ' + head)
            for waiting in on_monitor:
                if waiting is not proc:
                    report += _last_lines(waiting)
            return head + report + "\n  the run monitor's thread now:\n" + '\n'.join(
                f'    {line}' for line in self.monitor.spin_stack())
        blame = self.monitor.blame(self._stopped) if self.monitor is not None and code == 3 and not over_deadline \
            else None
        if blame:
            culprit, text = blame
            head = f'{text} (the graph stopped waiting for it); ' + head
            if culprit != proc.name and culprit in self.processes:
                report += self._stack_of(self.processes[culprit])
        return head + report

    def _stopped(self, name: str) -> bool:
        """Whether node ``name``'s process is alive and stopped (SIGSTOP, a debugger; never one the user runs)."""
        proc = self.processes.get(name)
        return proc is not None and proc.popen.poll() is None and is_stopped(proc.popen.pid)

    def _waited_on_monitor(self, proc: NodeProcess) -> bool:
        """Whether a node failed waiting on the run monitor: the time owner on its acknowledgement, or another node on
        a /clock step the monitor's acknowledgements withhold from the time owner (it fires step k only when
        :func:`~acds_common.graph.monitor_allows` it, then announces k + 1). The second holds whichever of the two
        timeouts, started a moment apart, a loaded machine ends first."""
        if self.monitor is None:
            return False
        ack = topics.resolve(topics.MONITOR_ACK)
        for line in list(proc.tail):
            if 'FAILURE' not in line:
                continue
            step = clock_step_waited_for(line)
            if ack in line or (step is not None and not monitor_allows(step - 1, self.monitor.acked_step)):
                return True
        return False

    def _stack_of(self, proc: NodeProcess) -> str:
        """The last lines of a node the graph waited on, with its Python stack (:meth:`_ask_stack`)."""
        self._ask_stack(proc)
        return _last_lines(proc)

    def _ask_stack(self, proc: NodeProcess) -> None:
        """Add a running node's Python stack to its tail (:data:`~acds_common.lockstep.STACK_SIGNAL`, a faulthandler
        dump, awaited at most 5 s); a stopped process is said to be stopped."""
        if proc.popen.poll() is None and is_stopped(proc.popen.pid):
            proc.tail.append('(the process is stopped: SIGSTOP, a debugger or a Ctrl-Z outside the launcher)')
        elif proc.popen.poll() is None and proc.failed_at is None:
            before = len(proc.tail)
            proc.tail.append('(its Python stack, asked for by the launcher:)')
            try:
                os.kill(proc.popen.pid, STACK_SIGNAL)
            except ProcessLookupError:
                pass
            deadline = time.monotonic() + 5.0
            while time.monotonic() < deadline and not any('File "' in line for line in list(proc.tail)[before:]):
                if proc.reader is not None:
                    proc.reader.join(timeout=0.1)

    def _complete(self) -> RunResult:
        """The time owner finished: drain the monitor (and so the recorder) through the owner's last step, stop the
        nodes, summarise. Completion is the step the time owner announced, never how far the monitor got."""
        assert self.monitor is not None and self.observer is not None and self.graph is not None
        wall = time.monotonic() - self._t0
        owner = self.processes[self.graph.time_owner]
        if owner.reader is not None:
            owner.reader.join(timeout=5.0)
        final = owner.completed_step
        if final is None:
            raise LaunchError(f'{owner.name} exited 0 without announcing its last step; the run is not valid')
        self._drain(final)
        codes = self._stop_children()
        # Every output of every step is in (above): a node that hung on its way out cost nothing but is reported.
        warnings = [self._death_report(proc, codes[name]) for name, proc in self.processes.items()
                    if proc.killed_after_s is not None]
        bad = {n: c for n, c in codes.items() if c != 0 and self.processes[n].killed_after_s is None}
        if bad:
            name = next(iter(bad))
            raise LaunchError(self._death_report(self.processes[name], bad[name]))
        self._check_health()
        summary = self.observer.summary(final, wall)
        for proc in self.processes.values():  # each node's last line (its timing) is read once its output closes
            if proc.reader is not None:
                proc.reader.join(timeout=2.0)
        timing = {name: proc.timing for name, proc in self.processes.items()}
        if self.monitor.external is not None:
            timing.update(self.monitor.external.timing())
        return RunResult(self.scenario, final, wall, summary, codes, self.record, self.monitor, warnings, timing)

    def _drain(self, final: int) -> None:
        """Wait until the monitor holds every step 0…``final`` of /clock and of every per-step topic, as long as it
        advances (:data:`DRAIN_STALL_S` without a message ends the wait); a step it lacks then fails the run."""
        mon = self.monitor
        assert mon is not None
        while mon.behind(final) and not mon.gaps():
            seen = mon.received()
            if not mon.wait_for(lambda s=seen: not mon.behind(final) or mon.received() != s, timeout_s=DRAIN_STALL_S):
                break
        self._check_health()
        missing = mon.behind(final) + mon.gaps()
        if missing:
            raise LaunchError(f'the run ended at step {final} but the run monitor lacks ' + ', '.join(missing) +
                              ': the summary and the bag would miss them, so the run is not valid')

    def _stop_children(self, grace_s: float = STOP_GRACE_S) -> dict[str, int]:
        self._signal_nodes(signal.SIGINT)
        deadline = time.monotonic() + grace_s
        codes: dict[str, int] = {}
        for name, proc in self.processes.items():
            try:
                codes[name] = proc.popen.wait(timeout=max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                self._ask_stack(proc)  # where it hangs, into the tail the report of the kill shows
                os.killpg(proc.popen.pid, signal.SIGKILL)
                proc.killed_after_s = grace_s
                codes[name] = proc.popen.wait()
        return codes

    def stop(self) -> None:
        """Stop every child (SIGINT, then SIGKILL after a grace period) and release the domain."""
        if self._tstp_before is not None:
            signal.signal(signal.SIGTSTP, self._tstp_before)
            self._tstp_before = None
        if any(p.popen.poll() is None for p in self.processes.values()):
            self._stop_children()
        for proc in self.processes.values():
            if proc.popen.stdout is not None:
                if proc.reader is not None:  # its last lines into the tail (the pipe ends with the process group)
                    proc.reader.join(timeout=2.0)
                proc.popen.stdout.close()
        if self.monitor is not None:
            self.monitor.close()  # also closes the bag, if recording
            self.monitor = None
        if self.live_sink is not None:
            self.live_sink.close()
            self.live_sink = None
        if self.lease is not None:
            self.lease.close()
            self.lease = None
        if self._shm_before is not None:  # what this run's killed processes left in /dev/shm
            self.shm_removed = shm.clean_run(self._shm_before)
            self._shm_before = None
