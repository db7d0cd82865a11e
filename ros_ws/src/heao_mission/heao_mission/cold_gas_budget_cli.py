"""``acds cold-gas-budget SCENARIO [--runs N] [--seed S] [--percentile P] [--acquisitions K]``: the sizing case from
the distribution of separations.

Seed 002 §3.2, §5.1: the cold-gas system "was sized to perform 3 sun acquisitions assuming worst case spacecraft
inertias (HEAO-B) and initial body rates of 1 degree/second about each axis"; "the required propellant weight is
4.3 pounds"; two 7.6-in tanks hold 4.6 lb. The study gives rates and inertias, not the separation's attitude and
orbit geometry, so "worst case" is a property of the distribution of those: this draws N samples of the scenario's
open conditions (seed S; sample K is the same draw as in ``montecarlo``/``sweep`` of the same seed), runs one
acquisition of each (direct engine, to capture), and takes the draw that used the most GN₂ (the worst of N) and
the draw nearest the P-th percentile of the GN₂ used. Each of the two is then flown K times back to back on one
load (each from its separation again, with the gas the previous ones left: isothermal blowdown, the mass is the
tanks' whole state), and the totals are printed beside the study's 4.3 lb. An acquisition that cannot start (the
tanks below the regulator's set point) or does not reach capture within the scenario's duration ends that chain,
said so. ``--json PATH`` writes the draws, the chains and the totals.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from acds_cli.arguments import UsageError, check_output_file, positive_int
from cold_gas.study import STUDY_LOAD_LB, STUDY_THREE_ACQUISITIONS_LB

_KEYS = ('gas_handover_min', 'acquisition_time_min', 'gas_used_lb', 'gas_left_lb', 'gas_final_tank_psia',
         'gas_valve_cycles', 'gas_vented_lb', 'truth_digest')


def _f(v: float | None, spec: str) -> str:
    return '—' if v is None else format(v, spec)


def _chain(sample: Any, sampler: Any, acquisitions: int) -> tuple[list[dict[str, Any]], str]:
    """``acquisitions`` of one draw back to back on one load: the rows, and why the chain ended ('' if it did not)."""
    from acds_common.scenario import ScenarioError
    from acds_common.units import LB_KG
    from acds_runtime.direct import DirectRun
    from acds_runtime.preflight import preflight

    rows: list[dict[str, Any]] = []
    left_kg = sample.scenario.get('cold_gas', 'load_mass')
    print(f'  {"#":>2s} {"on gas min":>10s} {"capture min":>11s} {"GN₂ used lb":>11s} {"left lb":>8s} '
          f'{"tank psia":>9s} {"valve cycles":>12s}')
    for i in range(1, acquisitions + 1):
        sc = sampler.draw(sample.index).scenario
        sc.values['cold_gas']['load_mass'] = left_kg
        try:
            preflight(sc)
        except ScenarioError as exc:
            return rows, f'acquisition {i} cannot start: {str(exc).split(": ", 1)[-1]}'
        s = DirectRun(sc).run().summary
        row = {'acquisition': i, **{k: s.get(k) for k in _KEYS}}
        rows.append(row)
        print(f'  {i:>2d} {_f(row["gas_handover_min"], ".2f"):>10s} {_f(row["acquisition_time_min"], ".2f"):>11s} '
              f'{row["gas_used_lb"]:>11.3f} {row["gas_left_lb"]:>8.3f} {row["gas_final_tank_psia"]:>9.0f} '
              f'{row["gas_valve_cycles"]:>12d}', flush=True)
        left_kg = row['gas_left_lb'] * LB_KG
        if row['acquisition_time_min'] is None:
            return rows, f'acquisition {i} did not reach capture within {sc.duration_s() / 60:g} min'
    return rows, ''


def cmd_budget(args: argparse.Namespace) -> int:
    """Draw, pick the worst and the percentile draw, chain each (module doc)."""
    import numpy as np
    from acds_cli.verbs.montecarlo import _draw, _sampler
    from acds_common.scenario import load_scenario
    from acds_common.units import LB_KG
    from acds_runtime import dispersion_report as dr
    from acds_runtime.direct import DirectRun
    from acds_runtime.preflight import preflight

    base = load_scenario(args.scenario)
    if 'cold_gas' not in base.get('', 'nodes'):
        raise UsageError(f'{args.scenario}: no cold_gas node in its graph: nothing to budget')
    if not 0.0 < args.percentile <= 100.0:
        raise UsageError(f'--percentile {args.percentile:g}: must be in (0, 100]')
    preflight(base)
    if args.json:
        check_output_file('--json', Path(args.json))
    sampler = _sampler(base, args.seed, [])
    load_lb = base.get('cold_gas', 'load_mass') / LB_KG
    print(f'{base.name}: GN₂ per acquisition over {args.runs} draws of the separation (seed {args.seed}, direct engine)',
          flush=True)
    draws = []
    for k in range(args.runs):
        s = DirectRun(_draw(sampler, k).scenario).run().summary
        draws.append({'index': k, **{key: s.get(key) for key in _KEYS}})
    used = np.array([d['gas_used_lb'] for d in draws], dtype=float)
    worst = max(draws, key=lambda d: (d['gas_used_lb'], -d['index']))
    target = dr.percentile(used, args.percentile)
    near = min(draws, key=lambda d: (abs(d['gas_used_lb'] - target), d['index']))
    print(f'  GN₂ used, lb: median {dr.percentile(used, 50):.3f}, {args.percentile:g}th percentile {target:.3f} '
          f'(nearest: sample {args.seed}:{near["index"]}, {near["gas_used_lb"]:.3f}), worst {worst["gas_used_lb"]:.3f} '
          f'(sample {args.seed}:{worst["index"]}); {args.runs} draws')
    chains = []
    for label, d in ((f'worst of {args.runs} draws', worst), (f'{args.percentile:g}th percentile of {args.runs} draws',
                                                            near)):
        print(f'{args.acquisitions} acquisitions back to back on {load_lb:.2f} lb, sample {args.seed}:{d["index"]} '
              f'({label})', flush=True)
        rows, ended = _chain(_draw(sampler, d['index']), sampler, args.acquisitions)
        total = sum(r['gas_used_lb'] for r in rows)
        left = rows[-1]['gas_left_lb'] if rows else load_lb
        print(f'  total GN₂ used {total:.3f} lb of the {load_lb:.2f} lb load ({total / load_lb:.0%}); left {left:.3f} lb')
        if ended:
            print(f'  chain ended: {ended}')
        chains.append({'label': label, 'sample': d['index'], 'acquisitions': rows, 'total_used_lb': total,
                       'left_lb': left, 'ended': ended or None})
    print(f'study (seed 002 §3.2): {STUDY_THREE_ACQUISITIONS_LB} lb for three worst-case acquisitions, '
          f'{STUDY_LOAD_LB} lb capacity')
    if args.json:
        from acds_runtime.summary import write_summary_json

        write_summary_json(Path(args.json), {'scenario': base.name, 'seed': args.seed, 'runs': args.runs,
                                             'percentile': args.percentile, 'load_lb': load_lb, 'draws': draws,
                                             'chains': chains})
    print(f'[cold-gas-budget] {args.runs} draws, {sum(len(c["acquisitions"]) for c in chains)} chained acquisition(s) '
          'run', file=sys.stderr)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``cold-gas-budget`` verb."""
    p = sub.add_parser('cold-gas-budget', help='worst-case cold-gas acquisitions back to back on one GN₂ load, from '
                                               'the distribution of separations (seed 002 §3.2: three, 4.3 lb)',
                       description=__doc__.split('\n\n', 1)[1])
    p.add_argument('scenario', nargs='?', default='heao_b_cold_gas_three_acquisitions', metavar='SCENARIO',
                   help='a cold-gas acquisition scenario (default heao_b_cold_gas_three_acquisitions)')
    p.add_argument('--runs', type=positive_int, default=100,
                   help='draws of the separation (default 100: ~3 min on one core)')
    p.add_argument('--seed', type=int, default=1, help='study seed (default 1, the trade\'s)')
    p.add_argument('--percentile', type=float, default=90.0, help='the percentile draw chained beside the worst '
                                                                  '(default 90)')
    p.add_argument('--acquisitions', type=positive_int, default=3, help='how many in a row (default 3, the study\'s)')
    p.add_argument('--json', metavar='PATH', help='write the draws, the chains and the totals as JSON')
    p.set_defaults(func=cmd_budget)
