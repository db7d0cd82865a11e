"""A dispersion study flown by a flight computer on a CAN bus: ``montecarlo SCENARIO --fsw-command 'CMD {can_host}
{can_port} …' [--rtf R] [--paired]`` for a scenario whose cards serve a bus (docs/flight_software.md "Monte Carlo with your
own flight software", docs/bus.md).

Each sample is ``acds run SCENARIO --sample S:K --engine direct --can-port 0 --rtf R`` with the flight computer
started by the study: the run's plug-in session (entry-point group ``acds.run_options``) serves the sample's bus on
a free port, the study starts the command with that port (``{can_host}``, ``{can_port}``, ``{run_dir}``) once it
listens, the session waits for the flight computer's heartbeat and the cards pace the steps at R; after the sample
(however it ends) the flight computer is stopped (SIGINT, SIGKILL after the grace period). The sample's folder keeps
the CAN log (``can.asc``, ``can.asc.run.json``), the flight computer's account (``flight_computer.json``), its
output (``fsw.log``) and the run's lines (``run.log``: the bus, the heartbeat, the account); ``acds run …
--replay-can samples/<name>/can.asc`` flies the sample again from its log to the same truth digest. ``--paired``:
the plug-in's ``built_in`` gives the same draws flown by the built-in law.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import yaml
from acds_common.scenario import Scenario
from acds_runtime.flight_software import (
    LOG_NAME,
    STOP_GRACE_S,
    FswCommand,
    last_lines,
    sample_dir,
    start_process,
    stop_process,
)

from .verbs.run import run_plugins

#: The cards' timing figures of a sample's summary (ms; p50/p99/max) and what each is, for the study's timing table.
BUS_TIMING = {'can_sensor_lateness_ms': "the cards' sensor frames' wall lateness against the step's schedule",
              'can_sdo_latency_ms': "the flight computer's SDO round trip", 'can_setpoint_age_ms':
              'the age of each setpoint when the cards applied it'}
#: The bus host a study serves its samples on (loopback: CAN has no authentication).
BUS_HOST = '127.0.0.1'


def bus_sessions(scenario: Scenario, run_dir: Path, rtf: float | None, port: int = 0) -> list[Any]:
    """The run plug-ins' sessions of ``scenario`` as ``acds run --can-port PORT --rtf R`` would hold them (port 0:
    a free one); empty: the scenario serves no bus. A ValueError is the plug-in's one line."""
    ns = SimpleNamespace(can_port=port, can_host=BUS_HOST, replay_can=None, rtf=rtf)
    return [s for s in (p.prepare(scenario, ns, run_dir) for p in run_plugins()) if s is not None]


def serves_bus(scenario: Scenario) -> bool:
    """Whether a run plug-in serves a bus for ``scenario`` (asked as ``acds run`` without any of their options)."""
    ns = SimpleNamespace(can_port=None, can_host=None, replay_can=None, rtf=None)
    return any(p.prepare(scenario, ns, Path('.')) is not None for p in run_plugins())


def built_in_text(text: str) -> str:
    """A bus sample's YAML text flown by the built-in law (the plug-in's ``built_in``), for ``--paired``."""
    raw = yaml.safe_load(text)
    for plugin in run_plugins():
        pair = getattr(plugin, 'built_in', None)
        out = pair(raw) if pair is not None else None
        if out is not None:
            return yaml.safe_dump(out, sort_keys=False)
    raise ValueError('no run plug-in names the built-in law of this bus scenario')


@dataclass(frozen=True)
class BusSpec:
    """What every sample of a bus study shares (pickled to the Dask workers)."""

    command: FswCommand
    #: The study's folder: sample K's run folder is ``<folder>/samples/<sample name>``.
    folder: str
    #: The real-time factor the cards pace the samples at (None: the scenario's).
    rtf: float | None
    grace_s: float = STOP_GRACE_S
    #: The port every sample's bus listens on (0: a free one per sample; a fixed one: one sample at a time).
    port: int = 0


def run_bus_sample(spec: BusSpec, text: str, steps: int | None = None) -> dict[str, Any]:
    """The task: one sample on its own bus with the flight computer started for it (module doc); its run summary
    with ``fsw`` (how the flight computer stopped, its log, its account from the CAN log), or ``{'scenario',
    'error', 'fsw'}``. A retried sample (``--resume``) starts from an empty run folder."""
    from acds_runtime.direct import DirectRun
    from acds_runtime.launcher import LaunchError
    from acds_runtime.sampling import scenario_from_text

    scenario = scenario_from_text(text)
    run_dir = sample_dir(spec.folder, scenario.name)
    shutil.rmtree(run_dir, ignore_errors=True)
    run_dir.mkdir(parents=True)
    log = run_dir / LOG_NAME
    fsw: dict[str, Any] = {'run_dir': str(run_dir), 'log': str(log), 'can_log': str(run_dir / 'can.asc')}
    procs: list[Any] = []

    def start(where: dict[str, str]) -> Any:
        argv = spec.command.argv({**where, 'run_dir': str(run_dir)})
        fsw['argv'] = argv
        proc = start_process(argv, {**os.environ, 'PYTHONUNBUFFERED': '1'}, log)
        procs.append(proc)
        return lambda: None if proc.poll() is None else f'the flight computer exited ({_how(proc.returncode)})'

    summary: dict[str, Any]
    try:
        sessions = bus_sessions(scenario, run_dir, spec.rtf, spec.port)
        with contextlib.ExitStack() as held:
            # the run's own lines (the bus, the heartbeat, the flight computer's account) into the sample's folder
            held.enter_context(contextlib.redirect_stderr(held.enter_context((run_dir / 'run.log').open('w'))))
            for session in sessions:
                session.served = start
                scenario = held.enter_context(session)
            try:
                summary = dict(DirectRun(scenario, steps=steps, run_id=run_dir.name).run().summary)
            finally:
                if procs:
                    fsw['stop'] = stop_process(procs[0], spec.grace_s)
        if fsw.get('stop', {}).get('how') == 'exited by itself':
            raise RuntimeError(f'the flight computer exited ({_how(fsw["stop"]["exit_code"])}) before the sample '
                               'ended')
        fsw['timing'] = {key[4:-3]: {**{f'{q}_ms': figures[q] for q in ('p50', 'p99', 'max')}, 'what': what,
                                     'steps': summary.get('steps', steps)}
                         for key, what in BUS_TIMING.items() if (figures := summary.get(key))}
        account = run_dir / 'flight_computer.json'
        if account.is_file():
            fsw['flight_computer'] = json.loads(account.read_text())
    except (LaunchError, RuntimeError, ValueError, OSError) as exc:
        if procs and 'stop' not in fsw:
            fsw['stop'] = stop_process(procs[0], spec.grace_s)
        summary = {'scenario': scenario.name, 'error': str(exc)}
        fsw['last_lines'] = last_lines(log)
    summary['fsw'] = fsw
    return summary


def _how(code: int) -> str:
    return f'killed by signal {signal.Signals(-code).name}' if code < 0 else f'exit code {code}'
