"""The magnetic against cold-gas acquisition trade's propellant budget (seed 002 §2, §3.1, §3.2, §5): a paired
sweep's cold-gas case (``acds sweep acquisition-trade --runs N``), entry point ``acds.study_budgets``
(:data:`acds_common.plugins.STUDY_BUDGETS`; docs/architecture.md "Adding a mission").

The module gives ``applies(scenario)`` (the case runs the cold-gas subsystem), :data:`PAIRED_QUANTITIES` (what the
paired table compares when a case does), :func:`study_budget` (the case's budget over its draws, kept in the sweep's
JSON under the entry-point name) and :func:`study_budget_table` (its lines under the table).
"""

from __future__ import annotations

import math
from typing import Any

from acds_common.units import LB_KG
from cold_gas.study import STUDY_ACQUISITION_MIN, STUDY_THREE_ACQUISITIONS_LB

#: The quantities a paired sweep with a cold-gas case compares: the acquisition time only (no magnetics-only phase).
PAIRED_QUANTITIES = (('acquisition_time_min', 'acquisition time'),)


def applies(scenario: Any) -> bool:
    """A case with the cold-gas subsystem in its graph."""
    return 'cold_gas' in scenario.get('', 'nodes')


def study_budget(rows: list[dict[str, Any]], sc: Any) -> dict[str, Any]:
    """A paired sweep's cold-gas case (``acds sweep --runs N``): its propellant and valve use over its draws, and
    how many acquisitions its load supports.

    Per acquisition (the run ends at capture): the time on gas (start → hand-over to the wheels, min; not reached:
    +∞), GN₂ used (lb) and valve cycles, median, 10–90 % and worst, with the
    draw of the worst; the acquisitions the load supports at the 90th percentile of the GN₂ used, counting the whole
    load and counting only the gas above the regulator's set point (below it the regulator drops out and the thrust
    falls with the tank: blowdown, seed 002 §5.2.1 regulation lost); three acquisitions at the worst draw and at the
    90th percentile beside the study's 4.3 lb (§3.2); the draws captured within the study's ten minutes (§2: "the
    cold gas system selected will permit sun acquisition within ten minutes"), with a Wilson 95 % interval.
    """
    import numpy as np
    from acds_runtime import dispersion_report as dr

    done = [r for r in rows if 'error' not in r and r.get('gas_used_lb') is not None]
    out: dict[str, Any] = {'n': len(done)}
    for key in ('gas_handover_min', 'gas_used_lb', 'gas_valve_cycles'):
        vals = np.array([math.inf if r[key] is None else float(r[key]) for r in done])
        worst = max(done, key=lambda r: math.inf if r[key] is None else r[key]) if done else None
        out[key] = {'median': dr.percentile(vals, 50), 'p10': dr.percentile(vals, 10), 'p90': dr.percentile(vals, 90),
                    'worst': dr.percentile(vals, 100), 'worst_index': None if worst is None else worst['index']}
    c = sc.values['cold_gas']
    load_lb = c['load_mass'] / LB_KG
    residual_lb = load_lb * c['regulator_set_pressure'] / _tank_pressure_pa(c)
    p90 = out['gas_used_lb']['p90']
    out.update(load_lb=load_lb, residual_at_set_point_lb=residual_lb,
               acquisitions_at_p90=None if not p90 else int(load_lb // p90),
               acquisitions_at_p90_regulated=None if not p90 else int((load_lb - residual_lb) // p90))
    within = sum(1 for r in done if r.get('acquisition_time_min') is not None
                 and r['acquisition_time_min'] <= STUDY_ACQUISITION_MIN)
    interval = dr.wilson_interval(within, len(done))
    out['within_study_time'] = {'minutes': STUDY_ACQUISITION_MIN, 'count': within, 'n': len(done),
                                'interval': None if interval is None else list(interval)}
    return out


def _tank_pressure_pa(c: dict[str, Any]) -> float:
    """The loaded tanks' pressure at t0 (the cold_gas core's isothermal ideal gas, :mod:`cold_gas.rcs`)."""
    from cold_gas.configuration import rcs_config

    cfg = rcs_config(c)
    return cfg.tank_pressure_pa(cfg.load_mass_kg)


def study_budget_table(scenario_name: str, g: dict[str, Any]) -> str:
    """The cold-gas case's propellant lines under the paired table (:func:`study_budget`)."""

    def line(key: str, title: str, spec: str) -> str:
        q = g[key]

        def f(v: float | None) -> str:
            return '—' if v is None else format(v, spec)
        return (f'  {title:34s} median {f(q["median"]):>7s}   p10–p90 {f(q["p10"])}–{f(q["p90"])}   worst '
                f'{f(q["worst"])} (sample {q["worst_index"]})')
    at = g['acquisitions_at_p90']
    w, used = g['within_study_time'], g['gas_used_lb']
    lo, hi = w['interval'] or (math.nan, math.nan)
    three = ('—' if used['worst'] is None else
             f'{3 * used["worst"]:.2f} lb at the worst draw (sample {used["worst_index"]}), '
             f'{3 * used["p90"]:.2f} lb at the 90th percentile ({g["n"]} draws); study (§3.2) '
             f'{STUDY_THREE_ACQUISITIONS_LB} lb')
    return '\n'.join([
        f'{scenario_name}: cold gas per acquisition ({g["n"]} draws)',
        line('gas_handover_min', 'on gas: start → hand-over, min', '.2f'),
        line('gas_used_lb', 'GN₂ used, lb', '.3f'), line('gas_valve_cycles', 'valve cycles (all six valves)', '.0f'),
        f'  the {g["load_lb"]:.2f} lb load supports {"—" if at is None else at} acquisitions at the 90th percentile '
        f'({g["acquisitions_at_p90_regulated"]} on the gas above the regulator set point; '
        f'{g["residual_at_set_point_lb"]:.3f} lb is left when the tanks reach it)',
        f'  three acquisitions: {three}',
        f'  captured within the study\'s {w["minutes"]:g} min (§2): {w["count"]} of {w["n"]} '
        f'(Wilson 95 % interval {100 * lo:.1f}–{100 * hi:.1f} %)'])
