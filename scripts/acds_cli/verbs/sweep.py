"""``acds sweep SCENARIO... [--jobs N] [--json PATH]``: run scenarios in parallel, print one table.

Each scenario runs in its own subprocess (``python -m acds_cli run NAME --quiet
--summary-json FILE``), so every run has its own rclpy contexts and its own ROS domain
(the launcher leases one per run). ``table-4-7`` stands for the eleven acquisition cases
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
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from ..arguments import check_output_file, positive_int, positive_minutes

#: Shorthands for scenario lists.
GROUPS = {
    'table-4-7': ['heao_b_acquisition', 'heao_a_acquisition', *(f'heao_b_case{i}' for i in range(3, 12))],
    'normal-mode': ['heao_a_scan_no_unloading', 'heao_a_scan_unloading',
                    'heao_b_point_no_unloading', 'heao_b_point_unloading'],
}


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

    names = expand(args.scenarios)
    for name in names:
        preflight(load_scenario(name))  # fail fast (exit 2, one line) on a bad scenario before anything runs
    if args.json:
        check_output_file('--json', Path(args.json))
    extra = ['--until-min', str(args.until_min)] if args.until_min is not None else []
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


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``sweep`` verb."""
    p = sub.add_parser('sweep', help='run scenarios in parallel and print one table (table-4-7: the eleven cases)',
                       description='Run each SCENARIO through the full graph in its own process and ROS domain, '
                                   f'--jobs at a time, and print one table. Groups: {", ".join(GROUPS)}.')
    p.add_argument('scenarios', nargs='+', metavar='SCENARIO', help='scenario names or paths, or a group name')
    p.add_argument('--jobs', '-j', type=positive_int, default=2, help='runs at a time (default 2)')
    p.add_argument('--json', metavar='PATH', help='write the list of summary objects as JSON (non-finite as null)')
    p.add_argument('--until-min', type=positive_minutes, help='cap every run at this sim time, minutes (> 0)')
    p.set_defaults(func=cmd_sweep)
