"""Cold-gas acquisition summary (seed 002 §3.1, §5): the gas phases' times and the propellant they took.

Contributed when the graph flies the cold-gas subsystem (node ``cold_gas``). From the ``mode`` stream
(one message per step): ``gas_rate_damping_min`` (start → gas sun acquisition) and ``gas_handover_min``
(start → the first hand-over to the wheels, Mode 1B); the acquisition time itself (to capture) is the HEAO
summary's. From ``cold_gas/state`` (every step, the totals after step k's frame): gas used through the
thrusters, vented through the relief valve and left (lb), total impulse (lbf·s), valve cycles (commanded
pulses, all six valves), the most valves open at one instant, the final tank pressure (psia) and whether the
pressure switch acted.
"""

from __future__ import annotations

import math
from typing import Any

from acds_common import topics
from acds_common.units import LB_KG, LBF_N, PSI_PA

from .study import STUDY_ACQUISITION_MIN, STUDY_THREE_ACQUISITIONS_LB

_MODE, _STATE = (topics.resolve(t) for t in (topics.MODE, topics.COLD_GAS_STATE))


#: The summary keys this module contributes (:data:`acds_common.plugins.KEYS_ATTRIBUTE`).
SUMMARY_KEYS = ('gas_rate_damping_min', 'gas_handover_min', 'gas_used_lb', 'gas_vented_lb', 'gas_left_lb',
                'gas_impulse_lbf_s', 'gas_valve_cycles', 'gas_max_open_valves', 'gas_final_tank_psia',
                'gas_pressure_switch_acted')


def applies(scenario: Any) -> bool:
    """Runs with the cold-gas subsystem in the graph."""
    return 'cold_gas' in scenario.get('', 'nodes')


def null_keys(_summary: dict[str, Any]) -> None:
    """No keys of this module appear outside cold-gas runs."""


class Accumulator:
    """The first gas-phase transitions and the subsystem's last totals."""

    topics = (_MODE, _STATE)

    def __init__(self, scenario: Any) -> None:
        self.dt_s = scenario.control_period_s
        self.sun_acquisition_s: float | None = None
        self.handover_s: float | None = None
        self.state: dict[str, str] = {}
        self.max_open = 0
        self.switch_acted = False

    def step(self, k: int, values: dict[str, Any]) -> None:
        """One step: the mode's first gas transitions, the subsystem's state."""
        t = k * self.dt_s
        for st in values.get(_MODE) or ():
            if st.name == 'ascs_mode_manager':
                mode = dict(st.values).get('mode', st.message)
                if mode == 'gas_sun_acquisition' and self.sun_acquisition_s is None:
                    self.sun_acquisition_s = t
                if mode == 'mode_1b' and self.handover_s is None:
                    self.handover_s = t
        for st in values.get(_STATE) or ():
            if st.name == 'cold_gas':
                self.state = dict(st.values)
                self.max_open = max(self.max_open, int(self.state['open_valves_max']))
                self.switch_acted = self.switch_acted or self.state['pressure_switch'] == 'actuated'

    def contribute(self, summary: dict[str, Any]) -> None:
        """Add the cold-gas keys."""
        s = self.state

        def lb(key: str) -> float | None:
            return float(s[key]) / LB_KG if key in s else None
        summary.update({
            'gas_rate_damping_min': None if self.sun_acquisition_s is None else self.sun_acquisition_s / 60,
            'gas_handover_min': None if self.handover_s is None else self.handover_s / 60,
            'gas_used_lb': lb('used_kg'), 'gas_vented_lb': lb('vented_kg'), 'gas_left_lb': lb('propellant_kg'),
            'gas_impulse_lbf_s': float(s['impulse_ns']) / LBF_N if s else None,
            'gas_valve_cycles': int(s['valve_cycles']) if s else None,
            'gas_max_open_valves': self.max_open,
            'gas_final_tank_psia': float(s['tank_pressure_pa']) / PSI_PA if s else None,
            'gas_pressure_switch_acted': self.switch_acted,
        })


def print_tables(summary: dict[str, Any]) -> None:
    """The gas phases and the propellant."""
    if 'gas_used_lb' not in summary:
        return

    def f(x: float | None, spec: str = '.2f') -> str:
        return '—' if x is None else format(x, spec)
    print('\nCold-gas acquisition (seed 002 §3.1, §5)')
    print(f'  rate damping done {f(summary["gas_rate_damping_min"])} min, hand-over to the wheels '
          f'{f(summary["gas_handover_min"])} min, acquisition capture {f(summary.get("acquisition_time_min"))} min')
    print(f'  GN₂ used {f(summary["gas_used_lb"], ".3f")} lb, vented {f(summary["gas_vented_lb"], ".3f")} lb, left '
          f'{f(summary["gas_left_lb"], ".3f")} lb (tank {f(summary["gas_final_tank_psia"], ".0f")} psia); impulse '
          f'{f(summary["gas_impulse_lbf_s"], ".1f")} lbf·s; {summary["gas_valve_cycles"]} valve cycles, at most '
          f'{summary["gas_max_open_valves"]} open at once; pressure switch '
          f'{"acted" if summary["gas_pressure_switch_acted"] else "did not act"}')


# ------------------------------------------------------------------ a paired sweep's cold-gas case (acds sweep --runs)

#: The quantities a paired sweep with a cold-gas case compares: the acquisition time only (no magnetics-only phase).
PAIRED_QUANTITIES = (('acquisition_time_min', 'acquisition time'),)


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
