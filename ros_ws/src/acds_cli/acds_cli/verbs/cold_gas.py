"""``acds cold-gas-budget SCENARIO [--acquisitions N]``: worst-case acquisitions back to back on one GN₂ load.

Seed 002 §3.2, §5.1: the cold-gas system "was sized to perform 3 sun acquisitions assuming worst case spacecraft
inertias (HEAO-B) and initial body rates of 1 degree/second about each axis"; "the required propellant weight is
4.3 pounds"; two 7.6-in tanks hold 4.6 lb. This runs the scenario's acquisition (direct engine, to capture) N times
in a row, each starting from the scenario's separation (the tip-off again) with the gas the previous ones left in
the tanks (isothermal blowdown: the mass is the tanks' whole state), and prints per acquisition the times, the
GN₂ used and left and the tank pressure, then the total against the load. An acquisition that cannot start (the
tanks below the regulator's set point) or does not reach capture within the scenario's duration ends the chain,
said so. ``--json PATH`` writes the acquisitions' rows and the totals.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ..arguments import UsageError, check_output_file, positive_int

#: The study's figures the budget is printed beside (seed 002 §3.2), lb.
STUDY_THREE_ACQUISITIONS_LB = 4.3
STUDY_LOAD_LB = 4.6
#: Seed 002 §2: "The cold gas system selected will permit sun acquisition within ten minutes", min.
STUDY_ACQUISITION_MIN = 10.0


def cmd_budget(args: argparse.Namespace) -> int:
    """Chain the acquisitions (module doc)."""
    from acds_common.scenario import ScenarioError, load_scenario
    from acds_common.units import LB_KG
    from acds_runtime.direct import DirectRun
    from acds_runtime.preflight import preflight

    base = load_scenario(args.scenario)
    if 'cold_gas' not in base.get('', 'nodes'):
        raise UsageError(f'{args.scenario}: no cold_gas node in its graph: nothing to budget')
    preflight(base)
    if args.json:
        check_output_file('--json', Path(args.json))
    load_lb = base.get('cold_gas', 'load_mass') / LB_KG
    rows: list[dict[str, Any]] = []
    left_kg, ended = base.get('cold_gas', 'load_mass'), ''
    print(f'{base.name}: {args.acquisitions} acquisitions back to back on {load_lb:.2f} lb of GN₂ (direct engine)')
    print(f'  {"#":>2s} {"on gas min":>10s} {"capture min":>11s} {"GN₂ used lb":>11s} {"left lb":>8s} '
          f'{"tank psia":>9s} {"valve cycles":>12s}')
    for i in range(1, args.acquisitions + 1):
        sc = load_scenario(args.scenario)
        sc.values['cold_gas']['load_mass'] = left_kg
        try:
            preflight(sc)
        except ScenarioError as exc:
            ended = f'acquisition {i} cannot start: {str(exc).split(": ", 1)[-1]}'
            break
        s = DirectRun(sc).run().summary
        row = {'acquisition': i, **{k: s.get(k) for k in ('gas_handover_min', 'acquisition_time_min', 'gas_used_lb',
                                                          'gas_left_lb', 'gas_final_tank_psia', 'gas_valve_cycles',
                                                          'gas_vented_lb', 'truth_digest')}}
        rows.append(row)

        def f(v: float | None, spec: str) -> str:
            return '—' if v is None else format(v, spec)
        print(f'  {i:>2d} {f(row["gas_handover_min"], ".2f"):>10s} {f(row["acquisition_time_min"], ".2f"):>11s} '
              f'{row["gas_used_lb"]:>11.3f} {row["gas_left_lb"]:>8.3f} {row["gas_final_tank_psia"]:>9.0f} '
              f'{row["gas_valve_cycles"]:>12d}', flush=True)
        left_kg = row['gas_left_lb'] * LB_KG
        if row['acquisition_time_min'] is None:
            ended = f'acquisition {i} did not reach capture within {sc.duration_s() / 60:g} min'
            break
    used = sum(r['gas_used_lb'] for r in rows)
    print(f'  total GN₂ used {used:.3f} lb of the {load_lb:.2f} lb load ({used / load_lb:.0%}); left '
          f'{left_kg / LB_KG:.3f} lb')
    print(f'  study (seed 002 §3.2): {STUDY_THREE_ACQUISITIONS_LB} lb for three worst-case acquisitions, '
          f'{STUDY_LOAD_LB} lb capacity')
    if ended:
        print(f'  chain ended: {ended}')
    if args.json:
        from acds_runtime.summary import write_summary_json

        write_summary_json(Path(args.json), {'scenario': base.name, 'load_lb': load_lb, 'acquisitions': rows,
                                             'total_used_lb': used, 'left_lb': left_kg / LB_KG, 'ended': ended or None})
    print(f'[cold-gas-budget] {len(rows)} acquisition(s) run', file=sys.stderr)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``cold-gas-budget`` verb."""
    p = sub.add_parser('cold-gas-budget', help='worst-case cold-gas acquisitions back to back on one GN₂ load '
                                               '(seed 002 §3.2: three, 4.3 lb)',
                       description=__doc__.split('\n\n', 1)[1])
    p.add_argument('scenario', nargs='?', default='heao_b_cold_gas_three_acquisitions', metavar='SCENARIO',
                   help='a cold-gas acquisition scenario (default heao_b_cold_gas_three_acquisitions)')
    p.add_argument('--acquisitions', type=positive_int, default=3, help='how many in a row (default 3, the study\'s)')
    p.add_argument('--json', metavar='PATH', help='write the rows and totals as JSON')
    p.set_defaults(func=cmd_budget)
