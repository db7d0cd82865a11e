"""cold_gas stepper: the HEAO cold-gas reaction control subsystem as a node (seed 002 §5; core :mod:`cold_gas.rcs`).

Stage ``fire`` of step k takes the controller's signed on-time request per body axis (``controller/gas_on_time``,
step k) and the ``mode`` of step k (ground commands the mode manager forwards as ``command/cold_gas``:
``isolation <1|2> <open|close>``, ``bank <on|off>``, ``transducer <on|off>``, Table 5-2; applied before the
frame), runs one frame [t_k, t_k+1] and returns:

* ``wrench`` (every step): the thrusters' frame-average force (N) and torque (N·m), body axes: the rigid
  body integrates the torque (the force is stated, not flown: :mod:`acds_common.thrusters`);
* ``state`` (every step): status ``cold_gas`` with the frame's thrust level and per-thruster thrust and
  command times, the most valves open at once, the requests deferred to the next frame, the gas left, tank and
  feed pressures, the totals (gas used, vented, impulse), valve positions, pressure switch and bank power: full
  float precision, for the plots and the propellant bookkeeping;
* ``diagnostics``: Table 5-2 telemetry every ``cold_gas.telemetry_every`` steps and at once on an event
  (a fault, the pressure switch, a ground command applied or refused), WARN while a fault or the switch is on.

No controller in the graph (or before its first step): no requests.
"""

from __future__ import annotations

from typing import Any

from acds_common.cdr import Status
from acds_common.commands import CommandError, GasCommand
from acds_common.messages import OK, WARN, diagnostic, xyz
from acds_common.mode_report import mode_status
from acds_common.stepper import StepError, Stepper

from cold_gas.configuration import build_rcs
from cold_gas.rcs import ColdGasError

_NODE = 'cold_gas'


class ColdGasStep(Stepper):
    """Six thruster/valves, two tanks, two regulators, pressure switch and isolation valves."""

    node = _NODE

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        c = self.section('cold_gas')
        self.telemetry_period = c['telemetry_every']
        self.rcs = build_rcs(c)

    def fire(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Stage ``fire``: commands, then one frame of the subsystem."""
        rcs = self.rcs
        notes: list[str] = []
        _mode, commands = mode_status(inp['mode'], self.node)
        for text in commands:
            try:
                accepted, what = rcs.apply(GasCommand.parse(text.split()))  # forwarded without the verb 'gas'
            except CommandError as exc:
                accepted, what = False, str(exc)
            notes.append(f'command {text!r} at t={t_s:.1f} s: {what}' if accepted
                         else f'command {text!r} refused at t={t_s:.1f} s: {what}')
        try:
            frame = rcs.frame(t_s, self.control_period_s, xyz(inp['pulse']))
        except ColdGasError as exc:
            raise StepError(f'step {k}: {exc}') from None
        notes.extend(frame.events)
        for note in notes:
            self.log('warn' if 'refused' in note or 'fault' in note or 'actuated' in note else 'info', note)
        values = [('thrust_n', repr(frame.thrust_n)),
                  *((f'thrust_time_T{j + 1}_s', repr(t)) for j, t in enumerate(frame.thrust_time_s)),
                  *((f'command_T{j + 1}_s', repr(t)) for j, t in enumerate(frame.command_s)),
                  ('open_valves_max', str(frame.max_open)),
                  ('deferred', ' '.join(f'T{j + 1}' for j in frame.deferred)), ('propellant_kg', repr(rcs.propellant_kg)),
                  ('tank_pressure_pa', repr(rcs.tank_pa)), ('feed_pressure_pa', repr(rcs.feed_pa)),
                  ('used_kg', repr(rcs.used_kg)), ('vented_kg', repr(rcs.vented_kg)),
                  ('impulse_ns', repr(rcs.impulse_ns)), ('valve_cycles', str(sum(rcs.valve_cycles))),
                  ('isolation_valve_1', 'open' if rcs.isolation_open[0] else 'closed'),
                  ('isolation_valve_2', 'open' if rcs.isolation_open[1] else 'closed'),
                  ('pressure_switch', 'actuated' if rcs.switch_actuated else 'open'),
                  ('bank_power', 'on' if rcs.bank_power else 'off')]
        out: dict[str, Any] = {'wrench': (frame.force_n, frame.torque_nm),
                               'state': (Status(OK, _NODE, '; '.join(notes) or 'ok', _NODE, tuple(values)),)}
        if notes or k % self.telemetry_period == 0:
            alarm = rcs.fault_active or rcs.switch_actuated
            out['diagnostics'] = diagnostic(self.instance, rcs.telemetry(), '; '.join(notes) or
                                            ('fault or pressure switch active' if alarm else 'ok'), WARN if alarm else OK)
        return out
