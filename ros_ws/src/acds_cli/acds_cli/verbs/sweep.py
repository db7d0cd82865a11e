"""``acds sweep SCENARIO... [--jobs N] [--json PATH]``: run scenarios in parallel, print one table.

With ``--runs N`` it is a paired perturbation study instead (:func:`cmd_paired`): every scenario
runs on the same N drawn open conditions (``acds montecarlo``'s sampler and seed: sample i of every
case is the same draw — common random numbers), and the table gives per case the median and the
10–90 % range of the time on magnetics only and of the acquisition time, and the paired median
ratio to the first scenario (case 1) with a seeded bootstrap 90 % interval
(``acds_runtime.dispersion_report``). Table 4-7 case 4 is defined by a geometry, not an attitude
(the body momentum along B at t0), so in a paired study its attitude is each sample's drawn attitude
turned by the smallest rotation that puts I·ω0 on B (``h_parallel_b()``). A ``--vary`` key that a
case itself sets differently from case 1 (case 11's rates) keeps the case's value for that case.

Without ``--runs``, each scenario runs in its own subprocess (``python -m acds_cli run NAME --engine E
--quiet --summary-json FILE``; ``--engine`` direct by default, as for the paired study), so every run has
its own process and, on the graph, its own rclpy contexts and ROS domain (the launcher leases one per run).
A paired study appends each finished sample to its journal in ``--out`` (``acds_runtime.journal``) and
continues an interrupted one with ``--resume DIR``. ``table-4-7`` stands for the eleven acquisition cases
of Table 4-7. ``--json`` writes the list of summary objects (a failed run appears as
``{"scenario": NAME, "error": "..."}``; non-finite numbers as null). Every scenario is
loaded and pre-flighted, and every option checked, before the first run starts.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from acds_common.plugins import STUDY_BUDGETS, plugins
from acds_common.scenario import shipped_role

from ..arguments import UsageError, check_output_file, positive_int, positive_minutes
from .montecarlo import (
    Keyed,
    add_execution_options,
    add_sample_options,
    draw_samples,
    open_journal,
    records_of,
    rows_of,
    run_journaled,
    study_command,
    study_folder,
)

#: Shorthands for scenario lists (``sweep_groups`` of ``scenarios/roles.json``: Table 4-7's eleven acquisition cases,
#: the normal-mode cases, and the acquisition trade of seed 002 §3.1, magnetic against the other design on the same
#: separations, paired with --runs N).
GROUPS = shipped_role('sweep_groups')
#: Draws a paired study adds for a case, beyond the default open conditions (module doc; ``paired_case_vary`` of
#: ``scenarios/roles.json``).
CASE_VARY = shipped_role('paired_case_vary')
#: The paired study's quantities: (row key, column title).
PAIRED = (('time_magnetics_only_min', 'time on magnetics only'), ('acquisition_time_min', 'acquisition time'))


def expand(names: list[str]) -> list[str]:
    """Replace group names by their scenarios, keeping order and dropping repeats."""
    out: list[str] = []
    for name in names:
        for n in GROUPS.get(name, [name]):
            if n not in out:
                out.append(n)
    return out


def run_one(name: str, workdir: Path, extra: list[str]) -> dict[str, Any]:
    """Run one scenario in a subprocess; its summary, or {'scenario', 'error'}."""
    out = workdir / f'{Path(name).stem}.json'
    log = workdir / f'{Path(name).stem}.log'
    cmd = [sys.executable, '-m', 'acds_cli', 'run', name, '--quiet', '--summary-json', str(out), *extra]
    t0 = time.monotonic()
    with open(log, 'w') as fh:
        code = subprocess.run(cmd, stdout=fh, stderr=subprocess.STDOUT, env=dict(os.environ), check=False).returncode
    if code == 0 and out.exists():
        summary = json.loads(out.read_text())
        print(f'[sweep] {name}: done in {time.monotonic() - t0:.0f} s', file=sys.stderr, flush=True)
        return summary
    tail = log.read_text().strip().splitlines()[-3:] if log.exists() else []
    print(f'[sweep] {name}: FAILED (exit {code}); log {log}', file=sys.stderr, flush=True)
    return {'scenario': name, 'error': f'exit code {code}: ' + ' | '.join(tail)}


def _fmt(x: Any, spec: str = '.1f') -> str:
    return '—' if x is None else format(x, spec)


def table(summaries: list[dict[str, Any]]) -> str:
    """The sweep's one table: Table 4-7 columns plus the peaks, sim and wall time."""
    head = (f'{"scenario":28s} {"mag only":>8s} {"wheels+mag":>10s} {"acq time":>8s} {"final |h|":>9s} '
            f'{"peak |h| rss":>12s} {"peak M":>7s} {"wheel sat":>9s} {"sim min":>8s} {"wall s":>7s}')
    lines = ['times in minutes, momentum in ft-lb-sec, moment in A·m² (— = not reached / not applicable)',
             head, '-' * len(head)]
    for s in summaries:
        if 'error' in s:
            lines.append(f'{s["scenario"]:28s} FAILED: {s["error"]}')
            continue
        peak_h = (s.get('peak_wheel_momentum_ftlbs') or {}).get('rss')
        peak_m = max((s.get('peak_moment_am2') or {}).values(), default=None)
        lines.append(
            f'{s["scenario"]:28s} {_fmt(s.get("time_magnetics_only_min")):>8s} '
            f'{_fmt(s.get("time_wheels_magnetics_min")):>10s} {_fmt(s.get("acquisition_time_min")):>8s} '
            f'{_fmt(s.get("final_wheel_momentum_ftlbs"), ".2f"):>9s} {_fmt(peak_h, ".2f"):>12s} '
            f'{_fmt(peak_m, ".0f"):>7s} {_fmt(s.get("wheel_saturation_time_min")):>9s} '
            f'{_fmt(s.get("sim_minutes")):>8s} {_fmt(s.get("wall_seconds"), ".0f"):>7s}')
    return '\n'.join(lines)


def cmd_sweep(args: argparse.Namespace) -> int:
    """Run the scenarios, ``--jobs`` at a time; print the table; write ``--json``."""
    from acds_common.scenario import load_scenario
    from acds_runtime.preflight import preflight

    if args.runs is not None:
        return cmd_paired(args)
    for flag in ('vary', 'scheduler', 'out', 'resume'):
        if getattr(args, flag):
            raise UsageError(f'--{flag} belongs to a paired study: give --runs N with it')
    names = expand(args.scenarios)
    for name in names:
        preflight(load_scenario(name))  # fail fast (exit 2, one line) on a bad scenario before anything runs
    if args.json:
        check_output_file('--json', Path(args.json))
    extra = ['--engine', args.engine] + (['--until-min', str(args.until_min)] if args.until_min is not None else [])
    t0 = time.monotonic()
    with tempfile.TemporaryDirectory(prefix='acds_sweep_') as tmp:
        print(f'[sweep] {len(names)} scenario(s), {args.jobs} at a time; logs in {tmp} while running',
              file=sys.stderr, flush=True)
        with ThreadPoolExecutor(max_workers=args.jobs) as pool:
            summaries = list(pool.map(lambda n: run_one(n, Path(tmp), extra), names))
    print(table(summaries))
    print(f'\n[sweep] {len(names)} run(s) in {time.monotonic() - t0:.0f} s wall', file=sys.stderr)
    if args.json:
        from acds_runtime.summary import write_summary_json
        write_summary_json(Path(args.json), summaries)
    return 0 if all('error' not in s for s in summaries) else 1


def _case_vary(case: Any, reference: Any, vary: list[str]) -> tuple[list[str], list[str]]:
    """A case's draws: its own (CASE_VARY) and the user's, less those of keys the case sets itself; and the
    skipped ones."""
    from acds_runtime.sampling import parse_vary

    own = CASE_VARY.get(case.name, [])
    kept, skipped = list(own), []
    for text in vary:
        key = parse_vary(text).key
        if case.get(key.section, key.name) != reference.get(key.section, key.name) or \
                any(parse_vary(o).key.stream == key.stream for o in own):
            skipped.append(text)
        else:
            kept.append(text)
    return kept, skipped


def paired_table(cases: list[dict[str, Any]], runs: int, seed: int,
                 paired: tuple[tuple[str, str], ...] = PAIRED) -> str:
    """The paired study's table (study units: minutes)."""
    def cell(c: dict[str, Any]) -> str:
        def fmt(v: float | None) -> str:
            return '>' + format(c['censored_above'], '.4g') if v is None else f'{v:.1f}'

        def rfmt(v: float | None) -> str:
            return ('∞' if c['pairs'] else '—') if v is None else f'{v:.2f}'
        ci = c['ratio_ci90']
        interval = f'[{rfmt(ci[0])}, {rfmt(ci[1])}]'
        return (f'{c["censored"]:>4d} {fmt(c["median"]):>7s} {fmt(c["p10"]):>7s}–{fmt(c["p90"]):<7s} '
                f'{fmt(c["worst"]):>7s} {rfmt(c["ratio_median"]):>5s} {interval:<14s}')
    lines = [f'paired perturbation study: {runs} draws of the open conditions (seed {seed}); sample i of every case '
             'is the same draw; times in minutes; ratio = paired median ratio to the first case, [bootstrap 90 %]; '
             '>T = censored (not reached when the runs ended), ∞ = a ratio among censored pairs']
    head = f'{"case":28s} {"n":>3s} ' + ' '.join(f'| {t:^57s}' for _k, t in paired)
    sub = f'{"":28s} {"":>3s} ' + ' '.join(f'| {"cens":>4s} {"median":>7s} {"p10–p90":^15s} {"worst":>7s} '
                                            f'{"ratio [90 %]":<20s}' for _ in paired)
    lines += [head, sub, '-' * len(sub)]
    for case in cases:
        lines.append(f'{case["scenario"]:28s} {case["n"]:>3d} ' +
                     ' '.join(f'| {cell(case["quantities"][k])}' for k, _t in paired))
        if case['failed']:
            lines.append(f'{"":28s} {case["failed"]} sample(s) FAILED (see --out samples.csv)')
    return '\n'.join(lines)


def cmd_paired(args: argparse.Namespace) -> int:
    """Every scenario on the same ``--runs`` draws; the paired table (module doc)."""
    from acds_common.scenario import load_scenario
    from acds_runtime import dispersion_report as dr
    from acds_runtime.sampling import SamplingError

    names = expand(args.scenarios)
    scenarios = [load_scenario(n) for n in names]
    budgets = plugins(STUDY_BUDGETS)  # a case's budget over its draws, kept under the plug-in's name
    own = [p for p in budgets if any(p.module.applies(sc) for sc in scenarios)]
    paired = own[0].module.PAIRED_QUANTITIES if own else PAIRED
    out = study_folder('sweep', names[0] if len(names) == 1 else f'{len(names)}cases', args)
    if args.json:
        check_output_file('--json', Path(args.json))
    steps_by_case, samples_by_case = [], []
    for sc in scenarios:
        try:
            vary, skipped = _case_vary(sc, scenarios[0], args.vary)
        except SamplingError as exc:
            raise UsageError(str(exc)) from None
        for text in skipped:
            print(f'[sweep] {sc.name}: --vary {text} not applied (the case sets that key itself)', file=sys.stderr)
        _sampler, samples = draw_samples(sc, args.seed, args.runs, vary, '', args.jobs)
        samples_by_case.append(samples)
        steps_by_case.append(None if args.until_min is None else max(1, round(args.until_min * 60 /
                                                                               sc.control_period_s)))
    command = study_command(['sweep', *args.scenarios], args)
    keyed = Keyed(dict(zip(names, samples_by_case, strict=True)))
    journal = open_journal(out, {'verb': 'sweep', 'scenarios': names, 'seed': args.seed, 'runs': args.runs,
                                 'vary': args.vary, 'engine': args.engine, 'until_min': args.until_min,
                                 'command': command}, keyed, bool(args.resume))
    steps_of = dict(zip(names, steps_by_case, strict=True))
    print(f'[sweep] paired study: {len(names)} case(s) × {args.runs} draws (seed {args.seed}), engine {args.engine}; '
          f'output {out}', file=sys.stderr, flush=True)
    t0 = time.monotonic()
    execution = run_journaled(journal, keyed, args, lambda key: steps_of[key[0]], 'sweep')
    wall = time.monotonic() - t0

    def records(i: int) -> Iterator[dict[str, Any]]:  # case i's, read from disk one sample at a time
        return records_of(samples_by_case[i], (journal.done[(names[i], k)] for k in range(args.runs)))
    rows_by_case = [rows_of(records(i)) for i in range(len(names))]
    cases = []
    ref_rows = rows_by_case[0]
    for name, rows in zip(names, rows_by_case, strict=True):
        both = [i for i in range(args.runs) if 'error' not in rows[i] and 'error' not in ref_rows[i]]
        quantities = {}
        for key, title in paired:
            quantity = dr.Quantity(key, title, 'min', 'all', True)
            vals, censor_at = dr.values_of(rows, quantity)
            q = {'median': dr.percentile(vals, 50), 'p10': dr.percentile(vals, 10), 'p90': dr.percentile(vals, 90),
                 'worst': dr.percentile(vals, 100),
                 'censored': len(censor_at), 'censored_above': min(censor_at) if censor_at else None}
            q.update(dr.paired_ratio(dr.values_of([rows[i] for i in both], quantity)[0],
                                     dr.values_of([ref_rows[i] for i in both], quantity)[0], args.seed))
            quantities[key] = q
        failed = sum('error' in r for r in rows)
        case = {'scenario': name, 'n': len(rows) - failed, 'failed': failed, 'quantities': quantities}
        sc = scenarios[names.index(name)]
        case.update({p.name: p.module.study_budget(rows, sc) for p in budgets if p.module.applies(sc)})
        cases.append(case)
    text = paired_table(cases, args.runs, args.seed, paired) + ''.join(
        '\n\n' + p.module.study_budget_table(c['scenario'], c[p.name]) for c in cases for p in budgets if p.name in c)
    print(text)
    print(f'\n[sweep] {len(names)} case(s) × {args.runs} draws in {wall:.0f} s wall ({_execution(execution)})',
          file=sys.stderr)
    result = {'command': command, 'seed': args.seed, 'runs': args.runs,
              'engine': args.engine, 'until_min': args.until_min, 'wall_seconds': wall,
              'execution': _execution(execution), 'cases': cases}
    if args.json:
        dr.write_json(Path(args.json), result)
    dr.write_json(out / 'sweep.json', result)
    all_rows = [{'case': name, **row} for name, rows in zip(names, rows_by_case, strict=True) for row in rows]
    all_records = ({'case': name, **rec} for i, name in enumerate(names) for rec in records(i))
    dr.write_rows(out, all_rows, all_records)
    (out / 'report.md').write_text(f'# Paired perturbation study\n\n`{result["command"]}`\n\n```\n{text}\n```\n')
    return 0 if all(c['failed'] == 0 for c in cases) else 1


def _execution(execution: Any) -> str:
    return ('nothing left to run' if execution is None
            else f'{execution.where}, {execution.workers} worker(s){execution.mixed()}')


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``sweep`` verb."""
    p = sub.add_parser('sweep', help='run scenarios in parallel and print one table (table-4-7: the eleven cases)',
                       description='Run each SCENARIO in its own process on --engine (direct by default; graph: '
                                   'one process per node in its own ROS domain), --jobs at a time, and print one '
                                   f'table. Groups: {", ".join(GROUPS)}.')
    p.add_argument('scenarios', nargs='+', metavar='SCENARIO', help='scenario names or paths, or a group name')
    p.add_argument('--jobs', '-j', type=positive_int, default=2, help='runs at a time (default 2)')
    p.add_argument('--json', metavar='PATH', help='write the list of summary objects as JSON (non-finite as null)')
    p.add_argument('--until-min', type=positive_minutes, help='run every case for this sim time instead of its '
                   'scenario\'s duration, minutes (> 0; longer or shorter)')
    p.add_argument('--runs', type=positive_int,
                   help='paired study: run every scenario on the same N drawn open conditions (module doc)')
    add_execution_options(p)
    add_sample_options(p, run=False)
    p.add_argument('--out', metavar='DIR', help='paired study: write its journal (samples.jsonl), sweep.json, '
                                                 'samples.csv/json and report.md here (default runs/sweep_...)')
    p.add_argument('--quiet', action='store_true', help='paired study: no progress bar')
    p.set_defaults(func=cmd_sweep)
