"""The user's flight software started per sample: ``montecarlo --external NODE --fsw-command 'CMD …'``.

Each sample of such a study runs through the per-process graph (:class:`~acds_runtime.launcher.GraphRun`) with
NODE left to the user, exactly as ``acds run SCENARIO --sample S:K --external NODE`` with the node started by
hand; the study starts the node itself, from a command template (:class:`FswCommand`):

* ``{domain}``: the sample's ROS_DOMAIN_ID (leased by the launcher, so samples side by side never cross-talk);
* ``{params}``: the sample's parameters file for the user's node, its contract parameters under
  ``/**/<ROS node name>`` (``--ros-args --params-file {params}``);
* ``{run_dir}``: the sample's run folder (its output goes to ``fsw.log`` there, and it may write there).

The node's process also gets the sample's domain, localhost discovery and ``ROS_LOG_DIR`` in its environment
(:func:`external_env`), so a node started on this host needs no placeholder; a command that starts it where
this environment does not reach (``ssh``, ``docker``, ``sudo``, ``env -i`` …: :data:`NO_ENVIRONMENT`) must
carry ``{domain}``. It is stopped after the sample however the sample ends (:func:`stop_process`: SIGINT to
its process group, SIGKILL after the grace period, reported), and it dies with the process that started it
(``PR_SET_PDEATHSIG``: a killed study or Dask worker leaves it behind no more than the graph's own nodes).

A sample whose node exits before the sample ends, never joins the graph, or stalls the lockstep is a failed
sample (``{'scenario', 'error', 'fsw'}``): the error's first line names why, ``fsw.last_lines`` are its last
output lines. The node's step time is the run monitor's (:mod:`acds_runtime.external`).
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import signal
import subprocess
import time
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml
from acds_common.parameters import node_parameters
from acds_common.parent_death import kill_on_parent_death
from acds_common.scenario import Scenario

from .launcher import VENV_BIN, GraphRun, LaunchError

#: The command template's placeholders and what each becomes (docs/flight_software.md, "Monte Carlo with your own
#: flight software").
PLACEHOLDERS = {'domain': "the sample's ROS_DOMAIN_ID", 'params': "the sample's parameters file for your node",
                'run_dir': "the sample's run folder"}
#: The placeholders of a flight computer on a CAN bus (a scenario with the bus cards; docs/flight_software.md
#: "Monte Carlo with your own flight software").
BUS_PLACEHOLDERS = {'can_host': "the host of the sample's socketcand bus",
                    'can_port': "its TCP port (a free one per sample)", 'run_dir': "the sample's run folder"}
#: Launchers that start the node where this process's environment does not reach: the command needs ``{domain}``.
NO_ENVIRONMENT = ('ssh', 'docker', 'podman', 'nerdctl', 'kubectl', 'sudo', 'doas', 'su', 'systemd-run', 'machinectl')
#: ``env`` options that clear the environment (``env -i``): the command needs ``{domain}`` as well.
ENV_CLEARING = ('-i', '--ignore-environment', '-')
#: Seconds the node is given to leave after SIGINT before it is killed (``--fsw-grace-s``).
STOP_GRACE_S = 5.0
#: Output lines of the node kept for a failed sample's report.
LAST_LINES = 8
#: The node's output file in the sample's run folder.
LOG_NAME = 'fsw.log'
_PLACEHOLDER = re.compile(r'\{([A-Za-z_][A-Za-z0-9_]*)\}')


class FswCommandError(ValueError):
    """The command template cannot start a node (one line naming why)."""


@dataclass(frozen=True)
class FswCommand:
    """A parsed command template: its words, each with the placeholders still in."""

    template: str
    words: tuple[str, ...]

    @classmethod
    def parse(cls, template: str | None, option: str = '--fsw-command',
              placeholders: dict[str, str] = PLACEHOLDERS) -> FswCommand:
        """Check the template (empty, no executable, an unknown placeholder, ``{domain}`` missing where the node
        needs it, ``{can_port}`` missing from a flight computer's on the bus: :class:`FswCommandError`, one line)
        before any sample starts. ``placeholders``: the study's (:data:`PLACEHOLDERS`, or on the bus
        :data:`BUS_PLACEHOLDERS`)."""
        if template is None or not template.strip():
            raise FswCommandError(f'{option}: the command template is empty; give the command that starts your node, '
                                  f'e.g. {option} \'my_node --ros-args --params-file {{params}}\'')
        try:
            words = tuple(shlex.split(template))
        except ValueError as exc:
            raise FswCommandError(f'{option} {template!r}: {exc}') from None
        for name in _PLACEHOLDER.findall(template):
            if name not in placeholders:
                raise FswCommandError(f'{option}: unknown placeholder {{{name}}} (placeholders: '
                                      + ', '.join(f'{{{k}}} {v}' for k, v in placeholders.items()) + ')')
        exe = words[0]
        if _PLACEHOLDER.search(exe):
            raise FswCommandError(f'{option}: the executable {exe!r} is a placeholder; the command must start with '
                                  'a program (a name on PATH or a path)')
        if executable(exe) is None:
            raise FswCommandError(f'{option}: no executable {exe!r} (not an executable file, nor on PATH or in '
                                  f'{VENV_BIN})')
        base = Path(exe).name
        clears = base == 'env' and any(w in ENV_CLEARING for w in words[1:])
        if 'can_port' in placeholders and '{can_port}' not in template:
            raise FswCommandError(f'{option}: each sample serves its bus on a port of its own, so the command must '
                                  'take it: put {can_port} (and {can_host}) where your flight computer is told its '
                                  'socketcand bus')
        if 'domain' in placeholders and (base in NO_ENVIRONMENT or clears) and '{domain}' not in template:
            raise FswCommandError(f'{option}: {base}{" -i" if clears else ""} starts your node without this '
                                  "study's environment, so the command must pass the sample's ROS domain itself: "
                                  'put {domain} where it goes (e.g. ROS_DOMAIN_ID={domain})')
        return cls(template, words)

    def argv(self, values: dict[str, str]) -> list[str]:
        """The command of one sample: its program found as :meth:`parse` checked it (this environment's bin, then
        PATH), each placeholder replaced by its value."""
        return [executable(self.words[0]) or self.words[0],
                *(_PLACEHOLDER.sub(lambda m: values[m.group(1)], w) for w in self.words[1:])]


def executable(name: str) -> str | None:
    """The program a command word names: a path, or a name in this environment's bin or on PATH (as the launcher
    finds the nodes' console scripts)."""
    return shutil.which(name, path=os.pathsep.join([str(VENV_BIN), os.environ.get('PATH', '')]))


def external_env(graph: GraphRun, extra: dict[str, str] | None = None) -> dict[str, str]:
    """The environment of a user's node joining ``graph``: its ROS domain, discovery on this host, nothing else of
    this project (the node needs plain ROS 2 only)."""
    assert graph.lease is not None, 'start the graph first'
    env = {k: v for k, v in os.environ.items() if k not in ('FASTRTPS_DEFAULT_PROFILES_FILE', 'ACDS_LAUNCHER_PID')}
    env.update(ROS_DOMAIN_ID=str(graph.lease.domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               ROS_LOG_DIR=str(graph.run_dir / 'ros_log'), PYTHONUNBUFFERED='1')
    env.update(extra or {})
    return env


def start_process(argv: Sequence[str], env: dict[str, str], log: Path) -> subprocess.Popen[bytes]:
    """Start a user's node in a session of its own, its output (stdout and stderr) into ``log``."""
    with log.open('wb') as out:
        return subprocess.Popen(list(argv), stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT, env=env,
                                start_new_session=True, preexec_fn=kill_on_parent_death())


def interrupt(proc: subprocess.Popen[Any]) -> float | None:
    """SIGINT to a running node's process group; when it was sent (monotonic s), None when the node had ended."""
    if proc.poll() is not None:
        return None
    try:
        os.killpg(proc.pid, signal.SIGINT)
    except ProcessLookupError:
        pass
    return time.monotonic()


def stop_process(proc: subprocess.Popen[Any], grace_s: float, interrupted_at: float | None = None) -> dict[str, Any]:
    """Stop a user's node: SIGINT to its process group (unless sent already, at ``interrupted_at``), SIGKILL
    ``grace_s`` after it; reaped. ``{'how', 'exit_code'}``, ``how`` one of 'exited by itself', 'stopped by SIGINT',
    'killed (ignored SIGINT for G s)'."""
    if interrupted_at is None:
        interrupted_at = interrupt(proc)
        if interrupted_at is None:
            return {'how': 'exited by itself', 'exit_code': proc.returncode}
    try:
        return {'how': 'stopped by SIGINT',
                'exit_code': proc.wait(timeout=max(0.0, grace_s - (time.monotonic() - interrupted_at)))}
    except subprocess.TimeoutExpired:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        return {'how': f'killed (still running {grace_s:g} s after SIGINT)', 'exit_code': proc.wait()}


def last_lines(log: Path, n: int = LAST_LINES) -> list[str]:
    """The last ``n`` lines of a node's output file."""
    try:
        with log.open(errors='replace') as fh:
            return [line.rstrip('\n') for line in deque(fh, maxlen=n)]
    except OSError:
        return []


def node_parameters_file(graph: GraphRun, path: Path) -> Path:
    """The parameters of the graph's external nodes, each under ``/**/<its ROS node name>`` (any namespace)."""
    params = node_parameters(graph.scenario, graph.steps, graph.rtf, graph.overrides, graph.external)
    path.write_text(yaml.safe_dump({f'/**/{identity.rpartition("/")[2]}': {'ros__parameters': params[inst]}
                                    for inst, identity in graph.external.items()}, sort_keys=True))
    return path


def built_in_text(text: str) -> str:
    """A sample's scenario with every node the launcher's own (its keys ``external`` and ``fsw_command`` left out):
    the built-in law flown on the same draws (``--paired``)."""
    raw = yaml.safe_load(text)
    if 'external' not in raw and 'fsw_command' not in raw:
        return text
    return yaml.safe_dump({k: v for k, v in raw.items() if k not in ('external', 'fsw_command')}, sort_keys=False)


class FswGraphRun(GraphRun):
    """A sample's graph whose external node is a process the study started: its exit before the time owner
    completed fails the sample at once, naming it (rather than the graph timing out on its missing outputs)."""

    fsw: subprocess.Popen[bytes] | None = None
    #: When the user's node was sent SIGINT with the graph's own nodes (None: not yet).
    fsw_interrupted_at: float | None = None

    def _check_health(self) -> None:
        super()._check_health()
        proc = self.fsw
        if proc is None or proc.poll() is None or self.graph is None:
            return
        if self.processes[self.graph.time_owner].popen.poll() == 0:  # the sample completed: it may leave now
            return
        step = self.monitor.clock_step if self.monitor is not None else None
        code = proc.returncode
        how = f'killed by signal {signal.Signals(-code).name}' if code < 0 else f'exit code {code}'
        where = ('before it joined the graph' if self.monitor is None or not self.monitor.ready
                 else f'at step {step}, before the sample ended')
        raise LaunchError(f'the flight software exited ({how}) {where}')

    def _stop_children(self, *args: Any, **kwargs: Any) -> dict[str, int]:
        """The user's node is asked to leave together with the graph's own nodes (every output of the run is in when
        they are), so its shutdown overlaps theirs instead of following it; :func:`stop_process` waits for it."""
        if self.fsw is not None and self.fsw_interrupted_at is None:
            self.fsw_interrupted_at = interrupt(self.fsw)
        return super()._stop_children(*args, **kwargs)


@dataclass(frozen=True)
class FswSpec:
    """What every flight-software sample of a study shares (pickled to the Dask workers)."""

    command: FswCommand
    #: ``NODE[=ROS_NODE_NAME]`` beside the scenario's ``external``.
    external: tuple[str, ...]
    #: The study's folder: sample K's run folder is ``<folder>/samples/<sample name>``.
    folder: str
    grace_s: float = STOP_GRACE_S
    #: Node parameter overrides (``--deadline-ms``: ``deadline_ms``, ``deadline_strict``).
    overrides: dict[str, dict[str, Any]] = field(default_factory=dict)


def sample_dir(folder: str | Path, scenario_name: str) -> Path:
    """A flight-software sample's run folder in its study's folder."""
    return Path(folder) / 'samples' / scenario_name


def run_fsw_sample(spec: FswSpec, text: str, steps: int | None = None) -> dict[str, Any]:
    """The task: run one sample's scenario (YAML text) through the graph with the user's node started for it; its
    run summary with ``fsw`` (the node's step timing, how it stopped, its log), or ``{'scenario', 'error', 'fsw'}``.
    A retried sample (``--resume``) starts from an empty run folder."""
    from .sampling import scenario_from_text

    scenario: Scenario = scenario_from_text(text)
    run_dir = sample_dir(spec.folder, scenario.name)
    shutil.rmtree(run_dir, ignore_errors=True)
    run_dir.mkdir(parents=True)
    log = run_dir / LOG_NAME
    fsw: dict[str, Any] = {'run_dir': str(run_dir), 'log': str(log)}
    with (run_dir / 'graph.log').open('w') as graph_log:
        graph = FswGraphRun(scenario, run_dir, steps=steps, echo=lambda line: print(line, file=graph_log),
                            overrides=spec.overrides or None, external=spec.external)
        proc = None
        try:
            with graph:
                values = {'domain': str(graph.lease.domain_id), 'run_dir': str(run_dir),  # type: ignore[union-attr]
                          'params': str(node_parameters_file(graph, run_dir / 'fsw_params.yaml'))}
                argv = spec.command.argv(values)
                fsw['argv'] = argv
                try:
                    proc = graph.fsw = start_process(argv, external_env(graph), log)
                    result = graph.wait()
                finally:
                    if proc is not None:
                        fsw['stop'] = stop_process(proc, spec.grace_s, graph.fsw_interrupted_at)
            summary = dict(result.summary)
            fsw['timing'] = {inst: result.timing.get(inst) for inst in graph.external}
            fsw['warnings'] = result.warnings
        except (LaunchError, OSError) as exc:
            summary = {'scenario': scenario.name, 'error': str(exc)}
            fsw['last_lines'] = last_lines(log)
    summary['fsw'] = fsw
    return summary
