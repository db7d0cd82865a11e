"""``montecarlo SCENARIO --runs N --external NODE[=ROS_NAME] --fsw-command 'CMD …' [--paired]``: the dispersion study
flown by the user's flight software (docs/flight_software.md, "Monte Carlo with your own flight software").

Each sample runs through the per-process graph with NODE left to the user's node, which the study starts for it
from the command template and stops after it (:mod:`acds_runtime.flight_software`); J samples side by side on
ROS domains of their own (``--jobs``, a local Dask cluster, or ``--scheduler``). ``--paired`` also runs the same
draws with the built-in node on the direct engine; the report sets them side by side
(:mod:`acds_runtime.fsw_report`), with the node's step time per sample and over the study. A failed sample (its
node exits, never joins, stalls the lockstep) is one line naming why with the node's last lines; the study goes
on up to ``--max-failures`` of them, and ``--resume`` runs again only the samples that did not finish (the
failed ones included). The scenario keys ``external`` and ``fsw_command`` give the same as the options.

A scenario whose cards serve a CAN bus is flown by a flight computer on that bus instead (no ``--external``; the
command's placeholders ``{can_host}``, ``{can_port}``, ``{run_dir}``; paced at ``--rtf``): :mod:`.fsw_bus`.
"""

from __future__ import annotations

import argparse
import functools
import shlex
import sys
import time
from types import SimpleNamespace
from typing import Any

from acds_common.scenario import Scenario

from .arguments import UsageError, non_negative_int, positive_number
from .verbs.montecarlo import (
    _execution_text,
    _run_length,
    _steps,
    draw_samples,
    mark_complete,
    open_journal,
    rerun_command,
    run_journaled,
    study_command,
    study_folder,
)

#: The journal's cases: the user's node through the graph, the built-in node on the direct engine (``--paired``).
FSW, BUILT_IN = 'flight_software', 'built_in'
#: Failed samples after which the study stops (``--max-failures``).
MAX_FAILURES = 5


class _TooManyFailures(Exception):
    """More samples failed than ``--max-failures`` allows."""


def add_fsw_options(p: argparse.ArgumentParser) -> None:
    """The options of a study flown by the user's flight software."""
    from acds_runtime.flight_software import STOP_GRACE_S

    from .verbs.run import deadline

    p.add_argument('--external', action='append', default=[], metavar='NODE[=ROS_NODE_NAME]',
                   help='fly every sample with your own node as NODE (repeatable; as acds run --external): each sample '
                        'runs through the process graph and the study starts your node for it with --fsw-command')
    p.add_argument('--fsw-command', metavar="'CMD ...'",
                   help='the command that starts your node for a sample (scenario key fsw_command); placeholders '
                        '{domain} (its ROS_DOMAIN_ID, also in the environment), {params} (its parameters file for your '
                        'node) and {run_dir} (its run folder, where its output goes: fsw.log)')
    p.add_argument('--rtf', type=positive_number, metavar='R',
                   help="a study on a CAN bus: the real-time factor its samples are paced at (default the scenario's "
                        'can_bus.rtf); the command then takes {can_host} and {can_port} (the sample\'s bus) and '
                        '{run_dir}')
    p.add_argument('--can-port', type=int, metavar='PORT',
                   help='a study on a CAN bus: serve every sample\'s bus on this TCP port (default: a free one per '
                        'sample), for a flight computer that connects to one port only, e.g. a fixed port of its own; '
                        'one sample at a time (--jobs 1)')
    p.add_argument('--paired', action='store_true',
                   help='also run the same draws with the built-in node (direct engine) and report them side by side')
    p.add_argument('--deadline-ms', type=deadline, action='append', metavar='NODE=MS',
                   help="a node's wall-time budget per step, ms (repeatable): its steps over it, per sample and in all")
    p.add_argument('--deadline-strict', action='store_true', help='fail a sample at its first step over a deadline')
    p.add_argument('--max-failures', type=non_negative_int, default=MAX_FAILURES, metavar='M',
                   help=f'stop the study when more than M samples failed (default {MAX_FAILURES}); --resume runs '
                        'the failed and unrun ones again')
    p.add_argument('--fsw-grace-s', type=positive_number, default=STOP_GRACE_S, metavar='S',
                   help=f'seconds your node has to leave after SIGINT before it is killed (default {STOP_GRACE_S:g})')


def flown_by_user(args: argparse.Namespace, base: Scenario) -> bool:
    """Whether the study is flown by the user's node (the options, or the scenario's ``external``); its options
    without one: one line (UsageError)."""
    if args.external or args.fsw_command is not None or base.get('', 'external'):
        return True
    given = [o for o, v in (('--paired', args.paired), ('--rtf', args.rtf), ('--can-port', args.can_port is not None),
                            ('--deadline-ms', args.deadline_ms), ('--deadline-strict', args.deadline_strict),
                            ('--max-failures', args.max_failures != MAX_FAILURES)) if v]
    if given:
        raise UsageError(f'{given[0]}: an option of a study flown by your own node; give --external NODE and '
                         '--fsw-command \'CMD ...\'')
    return False


def _check(args: argparse.Namespace, base: Scenario) -> tuple[dict[str, str], Any, dict[str, Any], bool]:
    """The external nodes, the command, the node parameter overrides, whether the flight computer is on a bus; a
    bad one: UsageError, before any sample."""
    from pathlib import Path

    from acds_runtime.flight_software import BUS_PLACEHOLDERS, FswCommand, FswCommandError

    from .fsw_bus import bus_sessions, serves_bus
    from .verbs.run import _deadlines

    try:
        on_bus = serves_bus(base) and bool(bus_sessions(base, Path('.'), args.rtf, args.can_port or 0))
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    if on_bus:
        if args.external:
            raise UsageError(f'--external: scenario {base.name} is flown by a flight computer on its CAN bus, not by a '
                             "ROS node; give its command alone: --fsw-command 'CMD ... {can_host} {can_port}'")
        if args.can_port and (args.jobs > 1 or args.scheduler):
            raise UsageError(f'--can-port {args.can_port}: one bus on one port serves one sample at a time; give '
                             '--jobs 1 (or leave --can-port out: a free port per sample)')
        if args.deadline_ms or args.deadline_strict:
            raise UsageError('--deadline-ms: a ROS node\'s step budget; on the bus the cards report the flight '
                             "computer's timing (setpoint age, late steps) per sample")
        template = args.fsw_command if args.fsw_command is not None else base.get('', 'fsw_command')
        try:
            return {}, FswCommand.parse(template, '--fsw-command', BUS_PLACEHOLDERS), {}, True
        except FswCommandError as exc:
            raise UsageError(str(exc)) from None
    for option, value in (('--rtf', args.rtf), ('--can-port', args.can_port)):
        if value is not None:
            raise UsageError(f'{option}: scenario {base.name} has no CAN bus; a study flown by your ROS node has none')
    if args.engine == 'direct':
        raise UsageError('--external: the direct engine runs every node in this process, so it cannot fly your node; '
                         'a study flown by your node runs the process graph (leave --engine out, or --engine graph)')
    try:
        external = base.external(args.external)
    except ValueError as exc:
        raise UsageError(f'--external: {exc}') from None
    if not external:
        raise UsageError('--fsw-command: starts your node for each sample; give --external NODE[=ROS_NODE_NAME] (or the '
                         'scenario key external) to say which node of the graph it is')
    template = args.fsw_command if args.fsw_command is not None else base.get('', 'fsw_command')
    option = '--fsw-command' if args.fsw_command is not None else f'scenario {base.name} key fsw_command'
    if args.fsw_command is None and not template:
        raise UsageError(f'--external {", ".join(external)}: a study starts your node for each sample, so it needs the '
                         "command: --fsw-command 'CMD ...' (or the scenario key fsw_command)")
    try:
        command = FswCommand.parse(template, option)
    except FswCommandError as exc:
        raise UsageError(str(exc)) from None
    return external, command, _deadlines(args, base, False) or {}, False


def _replay(rerun: str, index: int, items: list[str]) -> str:
    return rerun.replace('{index}', str(index)) + ''.join(f' --external {shlex.quote(e)}' for e in items)


def cmd_fsw_study(args: argparse.Namespace, base: Scenario) -> int:
    """Draw, fly each sample with the user's node (and the built-in, ``--paired``), report (module doc)."""
    from acds_runtime import fsw_report
    from acds_runtime.dispersion_report import write_json
    from acds_runtime.flight_software import FswSpec, built_in_text, run_fsw_sample, sample_dir
    from acds_runtime.montecarlo import run_sample

    from . import fsw_bus

    external, command, overrides, on_bus = _check(args, base)
    args.engine = 'direct' if on_bus else 'graph'
    out = study_folder('montecarlo', base.name, args)
    steps = _steps(base, args.until_min)
    rerun = rerun_command(args.scenario, args.seed, '{index}', args.vary, args.until_min)
    _sampler, samples = draw_samples(base, args.seed, args.runs, args.vary, rerun, args.jobs)
    items = [f'{i}={r.rpartition("/")[2]}' for i, r in external.items()]
    run_length = _run_length(base, steps, samples)
    extra = [a for e in args.external for a in ('--external', e)]
    if args.fsw_command is not None:
        extra += ['--fsw-command', args.fsw_command]
    extra += ['--rtf', f'{args.rtf:g}'] if args.rtf is not None else []
    extra += ['--can-port', str(args.can_port)] if args.can_port is not None else []
    extra += ['--paired'] * args.paired + [a for n, ms in args.deadline_ms or [] for a in ('--deadline-ms', f'{n}={ms:g}')]
    extra += ['--deadline-strict'] * args.deadline_strict
    command_line = study_command(['montecarlo', args.scenario], args) + ''.join(f' {shlex.quote(a)}' for a in extra)
    keyed: dict[tuple[str, int], Any] = {(FSW, s.index): s for s in samples}
    if args.paired:  # the built-in side first (seconds per sample on the direct engine)
        pair = fsw_bus.built_in_text if on_bus else built_in_text
        keyed = {**{(BUILT_IN, s.index): SimpleNamespace(text=pair(s.text)) for s in samples}, **keyed}
    journal = open_journal(out, {'verb': 'montecarlo', 'scenario': base.name, 'seed': args.seed, 'runs': args.runs,
                                 'vary': args.vary, 'engine': args.engine, 'until_min': args.until_min, 'steps': steps,
                                 'external': external, 'fsw_command': command.template, 'paired': args.paired,
                                 'overrides': overrides, 'rtf': args.rtf, 'command': command_line}, keyed, bool(args.resume))
    retried = [key for key, summary in journal.done.items() if 'error' in summary]
    for key in retried:  # a failed sample did not finish: a resumed study runs it again
        del journal.done[key]
    print(f'[montecarlo] {base.name}: {args.runs} samples of seed {args.seed}, {run_length}, flown by '
          f'`{command.template}` ' + (f'on each sample\'s CAN bus, paced at R = {args.rtf or base.get("can_bus", "rtf"):g}'
                                      if on_bus else f'as {", ".join(items)} through the process graph')
          + (', paired with the built-in node on the direct engine' if args.paired else '')
          + f'; output {out}' + (f'; {len(retried)} failed sample(s) run again' if retried else ''),
          file=sys.stderr, flush=True)
    if on_bus:
        fly = functools.partial(fsw_bus.run_bus_sample, fsw_bus.BusSpec(command, str(out.resolve()), args.rtf,
                                                                         args.fsw_grace_s, args.can_port or 0),
                                steps=steps)
    else:
        fly = functools.partial(run_fsw_sample, FswSpec(command, tuple(args.external), str(out.resolve()),
                                                        args.fsw_grace_s, overrides), steps=steps)
    tasks = {FSW: fly,
             BUILT_IN: functools.partial(run_sample, engine='direct', steps=steps)}
    failures = [key for key, summary in journal.done.items() if 'error' in summary]

    def after(key: tuple[str, int], summary: dict[str, Any]) -> None:
        if 'error' not in summary:
            if _killed(summary):
                print(f'[montecarlo] sample {key[1]}: the flight software was {_killed(summary)}', file=sys.stderr)
            return
        failures.append(key)
        print(failure_line(key, summary), file=sys.stderr, flush=True)
        if len(failures) > args.max_failures:
            raise _TooManyFailures

    t0 = time.monotonic()
    kept = len(journal.done)
    try:
        execution = run_journaled(journal, keyed, args, lambda _key: steps, 'montecarlo',
                                  task_of=lambda key, _steps: tasks[key[0]], after=after)
    except _TooManyFailures:
        print(f'[montecarlo] stopped: {len(failures)} samples failed, more than --max-failures {args.max_failures}; '
              f'{sum("error" not in v for v in journal.done.values())} of {len(keyed)} finished, kept in {journal.path}; '
              f'once the node is fixed, run the failed and unrun samples with:\n  {command_line} --resume {out}',
              file=sys.stderr)
        return 1
    wall = time.monotonic() - t0
    records = []
    for s in samples:
        ours = journal.done[(FSW, s.index)]
        rec = {'index': s.index, 'name': s.name, 'drawn': s.drawn, 'flight_software': ours,
               'timing': ours.get('fsw', {}).get('timing'), 'replay': _replay(rerun, s.index, args.external)}
        if on_bus:  # the sample again from its CAN log, without the flight computer: the same truth digest
            rec['replay'] = (rerun.replace('{index}', str(s.index)) + ' --engine direct --replay-can '
                             + shlex.quote(str(sample_dir(out, s.name) / 'can.asc')))
        if args.paired:
            rec['built_in'] = journal.done[(BUILT_IN, s.index)]
        records.append(rec)
    where = _execution_text(execution) if execution is not None else 'nothing left to run'
    if kept:
        where += f'; {kept} sample(s) kept from an interrupted session'
    study = {'scenario': base.name, 'scenario_path': str(base.path.resolve()), 'seed': args.seed, 'runs': args.runs,
             'user_vary': args.vary, 'engine': args.engine, 'until_min': args.until_min, 'steps': steps,
             'run_length': run_length, 'external': external, 'fsw_command': command.template, 'paired': args.paired,
             'execution': where, 'wall_seconds': wall, 'command': command_line, 'rerun': rerun}
    mark_complete(out, study, False)
    pairs = fsw_report.paired([(r['index'], r['flight_software'], r['built_in']) for r in records], args.seed) \
        if args.paired else None
    timing = fsw_report.timing(records)
    write_json(out / 'samples.json', records)
    write_json(out / 'report.json', {'paired': pairs, 'timing': timing})
    flown = (f'the flight computer on the bus (R = {args.rtf or base.get("can_bus", "rtf"):g})' if on_bus
             else ', '.join(items))
    lines = [f'== {base.name}: {args.runs} samples (seed {args.seed}) flown by {flown}, {run_length}; '
             f'{where}; {wall:.0f} s wall ==']
    if pairs is not None:
        lines += ['', 'paired with the built-in node (same draws), percentiles over the samples:',
                  *fsw_report.paired_table(pairs)]
        if not pairs['differ_most']:
            lines.append('no sample differs from its built-in pair (nothing to replay)')
        for d in pairs['differ_most']:
            lines.append(f'differs most: sample {d["index"]} ({d["key"]} Δ {_delta(d["difference"])}); replay: '
                         f'{records[d["index"]]["replay"]}')
    lines += ['', *fsw_report.timing_table(timing)]
    failed = [((case, r['index']), r[side]) for r in records for case, side in ((BUILT_IN, 'built_in'),
                                                                                (FSW, 'flight_software'))
              if 'error' in r.get(side, {})]
    lines += [failure_line(key, summary) for key, summary in failed]
    print('\n'.join(lines))
    (out / 'report.md').write_text('```\n' + '\n'.join(lines) + '\n```\n\nper sample:\n\n' + '\n'.join(
        _sample_line(r) for r in records) + '\n')
    mark_complete(out, study, True)
    kept = 'fsw.log, can.asc, flight_computer.json, run.log' if on_bus else 'fsw.log, graph.log'
    print(f'[montecarlo] report.md, report.json, samples.json, samples.jsonl and each sample\'s run folder '
          f'(samples/<name>: {kept}) in {out}', file=sys.stderr)
    return 1 if failed else 0


def _delta(d: float | None) -> str:
    return 'reached by one side only' if d is None else f'{d:+.4g}'


def _killed(summary: dict[str, Any]) -> str:
    """'killed (still running G s after SIGINT)' when the study had to kill the sample's node, else ''."""
    how = summary.get('fsw', {}).get('stop', {}).get('how', '')
    return how if how.startswith('killed') else ''


def failure_line(key: tuple[str, int], summary: dict[str, Any]) -> str:
    """A failed sample: one line naming why, then the node's last lines (indented), where its output is and
    whether it had to be killed."""
    why = summary['error'].splitlines()[0]
    tail = summary.get('fsw', {}).get('last_lines') or []
    side = 'built-in ' if key[0] == BUILT_IN else ''
    killed = f'; the flight software was {_killed(summary)}' if _killed(summary) else ''
    return (f'[montecarlo] {side}sample {key[1]} failed: {why}' + ''.join(f'\n    | {line}' for line in tail)
            + (f'\n    (its output: {summary["fsw"]["log"]}{killed})' if 'fsw' in summary else ''))


def _sample_line(rec: dict[str, Any]) -> str:
    """One sample in report.md: its digest (and the built-in's), its timing, or why it failed."""
    ours = rec['flight_software']
    if 'error' in ours:
        return f'- sample {rec["index"]}: failed: {ours["error"].splitlines()[0]}'
    same = ''
    if 'built_in' in rec:
        same = (', the built-in failed' if 'error' in rec['built_in'] else ', identical to the built-in'
                if rec['built_in'].get('truth_digest') == ours.get('truth_digest') else ', differs from the built-in')
    timing = '; '.join(f'{i} p50 {t["p50_ms"]:.3f} / p99 {t["p99_ms"]:.3f} / max {t["max_ms"]:.3f} ms'
                       + (f', {t["over_deadline"]} over {t["deadline_ms"]:g} ms' if 'deadline_ms' in t else '')
                       for i, t in (rec['timing'] or {}).items() if t)
    return f'- sample {rec["index"]}: truth digest `{ours.get("truth_digest", "")[:12]}`{same}; {timing}'
