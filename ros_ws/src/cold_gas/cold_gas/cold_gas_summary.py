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

from typing import Any

from acds_common import topics
from acds_common.units import LB_KG, LBF_N, PSI_PA

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
