"""em_driver stepper: three redundant electromagnet drives, one control period per step (spec §6).

Stage ``drive`` of step k takes the moment command of step k (``controller/moment_command``)
from the node named by ``em_driver.command_source`` (acds_controller for HEAO,
ascs_mode_manager for SSS) — or, when that node is not in the graph, the fixed
``em_driver.bench_command`` — and the ``mode`` of step k whose ``command/em_driver`` entries
(``eea_select x B`` …) are applied first. The scenario failure (``em_driver.failure``) is
injected at the first step with t_k ≥ failure_time. The coils are driven over [t_k, t_k+1];
returned: the step-average achieved dipole (what rigid_body applies), the dipole and coil
current at t_k+1, e_ft, and diagnostics (duty, switch count, power, per-axis alarm, active
units, events) every ``telemetry_every`` steps and at every event, alarm change or rejected
command. A NaN/inf command component is rejected with a WARN diagnostic and that axis holds
its last valid command; the excess-coil-current / mismatch alarm is reported at level ERROR.

``em_driver.driver_kind`` picks the hardware (``configuration.build_assembly``): the HEAO/SSS
electromagnets or the seed-003 CubeSat torque rods, behind the same assembly interface. The
torque-rod kind also returns, every step, the net bus power (W) and |PWM duty| of each axis over
[t_k, t_k+1] (``power``, ``duty``), which the CubeSat detumble summary integrates.
"""

from __future__ import annotations

import math
from typing import Any

from acds_common import kernels
from acds_common.fused import FusedStage, Output
from acds_common.messages import ERROR, OK, WARN, diagnostic, vector3
from acds_common.mode_report import ModeStatusReader
from acds_common.stepper import Stepper
from acds_common.validation import scenario_key

from em_driver.bridge_switch import EmDriverError
from em_driver.configuration import apply_command, build_assembly, parse_command
from em_driver.drive_assembly import AssemblyResult, DriveAssembly, drive_step


@kernels.helper
def drive_fused(p: tuple, s: tuple, _k: int, t_s: float, command: Any) -> tuple:
    """Stage ``drive`` as a kernel (:mod:`acds_common.fused`) for the electromagnets' assembly: quiet unless the
    scenario failure is due, a command is non-finite, or an alarm changes or switches a unit (the Python stage then
    reports it). ``p``: (:func:`~em_driver.drive_assembly.drive_step`'s parameter rows, Δt, the time of the pending
    failure: infinite for none); ``s``: (unit table, monitor table, and a scratch copy of each: the step runs on
    the scratch tables, which become the state when it is quiet)."""
    params, dt, failure_time = p
    units, monitor, units1, monitor1 = s
    units1[:, :] = units
    monitor1[:, :] = monitor
    changed, figures = drive_step(units1, params, monitor1, command, dt)
    quiet = not changed and math.isfinite(command[0] + command[1] + command[2]) and t_s < failure_time
    return (quiet, ((units1, monitor1, units, monitor) if quiet else s), figures[0], figures[1], figures[2],
            figures[4])


class EmDriverStep(Stepper):
    """Electromagnets with bridge-switch (HEAO) or constant-level (SSS) drives, or CubeSat torque rods; active/standby."""

    node = 'em_driver'

    def __init__(self, params: dict[str, Any], log: Any = None) -> None:
        super().__init__(params, log)
        self.cfg = self.section('em_driver')
        with scenario_key('em_driver', EmDriverError):
            self.assembly = build_assembly(self.cfg)
        self.source = self.cfg['command_source']
        self._electrical = self.cfg['driver_kind'] == 'torque_rod'
        self._failure_pending = self.cfg['failure'] != 'none'
        self._failure_time_s = self.cfg['failure_time']
        self._telemetry_every = self.cfg['telemetry_every']
        self._bench_command = vector3(self.cfg['bench_command'])
        self._commanded = self.present(self.source)
        self._alarms = (False, False, False)
        self._mode_status = ModeStatusReader(self.node)

    def fused(self, stage: str, held: dict[str, Any]) -> FusedStage | None:
        """Stage ``drive`` as :func:`drive_fused` (:mod:`acds_common.fused`): the electromagnets commanded by a node
        of the graph; None for the torque rods, with telemetry wanted, or commands forwarded in the block's ``mode``."""
        if (stage != 'drive' or self._electrical or not self._commanded or self.telemetry_wanted
                or not isinstance(self.assembly, DriveAssembly) or self._mode_status(held.get('mode'))[1]):
            return None
        units, params, monitor = self.assembly.kernel_parts()
        failure_time = float(self._failure_time_s) if self._failure_pending else math.inf
        return FusedStage(drive_fused, (params, float(self.control_period_s), failure_time),
                          (units.copy(), monitor.copy(), units.copy(), monitor.copy()), ('command',),
                          (Output('dipole_avg', 3), Output('dipole_end', 3), Output('coil_current', 3),
                           Output('e_ft', 3)), self._restore)

    def _restore(self, s: tuple) -> None:
        self.assembly.set_kernel_state(s[0], s[1])

    def drive(self, k: int, t_s: float, inp: dict[str, Any]) -> dict[str, Any]:
        """Apply commands and failures due at step k, drive the coils for one control period."""
        commands = self._mode_status(inp['mode'])[1]
        events: list[str] = []
        rejected: list[str] = []
        if commands or (self._failure_pending and t_s >= self._failure_time_s):
            self._apply(commands, t_s, events, rejected)
        if not self._commanded:
            command = self._bench_command
        else:
            command = (0.0, 0.0, 0.0) if inp['command'] is None else inp['command']
        # A float triple (Vector3Stamped value) and the scenario's checked control period: the unchecked path.
        result = self.assembly.step_xyz(command, self.control_period_s)
        avg_dipole, end_dipole, coil_current, _, e_ft, duty, power, _ = result.figures
        out: dict[str, Any] = {'dipole_avg': avg_dipole, 'dipole_end': end_dipole, 'coil_current': coil_current,
                               'e_ft': e_ft}
        if self._electrical:
            out['power'] = power
            out['duty'] = duty
        alarms = result.alarm_flags
        if (events or rejected or result.events or result.diagnostics or alarms != self._alarms
                or (self.telemetry_wanted and k % self._telemetry_every == 0)):
            events.extend(result.events)
            rejected.extend(result.diagnostics)
            out['diagnostics'] = self.telemetry(result, command, events, rejected)
            for line in rejected:
                self.log('warn', f't={t_s:g} s: {line}')
            for line in events:
                self.log('info', f't={t_s:g} s: {line}')
        self._alarms = alarms
        return out

    def _apply(self, commands: list[str], t_s: float, events: list[str], rejected: list[str]) -> None:
        """The ``command/em_driver`` entries of the step's mode report, then the scenario failure once its time
        has come; appends what happened to ``events`` and the refused commands to ``rejected``."""
        for text in commands:
            try:
                events.append(apply_command(parse_command(text), self.assembly))
            except EmDriverError as exc:
                rejected.append(f'rejected command {text!r}: {exc}')
        if self._failure_pending and t_s >= self._failure_time_s:
            self._failure_pending = False
            axis, unit, kind = self.cfg['failure_axis'], self.cfg['failure_unit'], self.cfg['failure']
            self.assembly.inject_failure(axis, unit, kind)
            events.append(f'scenario failure at t={t_s:g} s: axis {"xyz"[axis]} unit {unit} {kind}')

    def telemetry(self, r: AssemblyResult, command: tuple[float, ...], events: list[str], rejected: list[str]) -> Any:
        """Table 4-11 driver telemetry: coil current, current command, alarms, active units; plus duty/power."""
        level, message = OK, 'ok'
        if rejected:
            level, message = WARN, rejected[0]
        cmd_a, coil_a, eft, duty, switches, power, alarms = (r.per_axis(name) for name in (
            'commanded_current_a', 'coil_current_a', 'e_ft_v', 'duty', 'switch_count', 'power_w', 'alarms'))
        if any(alarms):
            axes = ', '.join(a for a, on in zip('xyz', alarms, strict=True) if on)
            level, message = ERROR, f'excess coil current / mismatch alarm on axis {axes}'
        values: dict[str, object] = {}
        for i, a in enumerate('xyz'):
            values.update({
                f'command_am2_{a}': f'{command[i]:.6g}',
                f'commanded_current_a_{a}': f'{cmd_a[i]:.6g}',
                f'coil_current_a_{a}': f'{coil_a[i]:.6g}',
                f'e_ft_v_{a}': f'{eft[i]:.6g}',
                f'duty_{a}': f'{duty[i]:.4f}',
                f'switch_count_{a}': int(switches[i]),
                f'power_w_{a}': f'{power[i]:.4g}',
                f'alarm_{a}': 'true' if alarms[i] else 'false',
                f'active_unit_{a}': r.active_units[i],
            })
        values.update({f'event_{i}': e for i, e in enumerate(events)})
        values.update({f'rejected_{i}': e for i, e in enumerate(rejected)})
        return diagnostic(self.instance, values, message, level)
