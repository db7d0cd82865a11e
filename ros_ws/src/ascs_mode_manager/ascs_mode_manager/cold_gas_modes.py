"""HEAO mode sequencing with the cold-gas acquisition: the study's recommended design (seed 002 §2, §3.1, §5.1).

``modes.system: heao_cold_gas``. The acquisition runs on gas, the cruise on wheels + magnetics:

* ``gas_rate_damping`` (from separation): the thrusters null the tip-off rates on the gyros; →
* ``gas_sun_acquisition`` when every |ω_i| ≤ ``gas_damped_rate``: the thrusters turn body z to the sun line
  (sun sensor + gyros); →
* ``mode_1b`` (hand-over to the wheels, magnetics unloading, as in the all-magnetic design) when the sun is
  present, z is within ``gas_handover_cone`` of it and every |ω_i| ≤ ``gas_handover_rate``; then acquisition
  capture in Mode 1B and the cruise mode exactly as :class:`~ascs_mode_manager.heao_modes.HeaoModeManager`.

Sun reacquisition (§3.1: "Sun reacquisitions … would be effected with the cold gas system") is the ground
command ``mode reacquire``: from any mode that is not already a gas mode, back to ``gas_rate_damping``. Cold-gas
hardware commands (Table 5-2) are ``gas isolation <1|2> <open|close>``, ``gas bank <on|off>`` and ``gas
transducer <on|off>``, routed to the ``cold_gas`` node (which applies them, or refuses with the reason on
``/diagnostics``). Every other command is the HEAO grammar.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from acds_common.commands import Command, GasCommand, ModeCommand
from acds_common.modes import GAS_MODES
from acds_common.units import deg

from ascs_mode_manager.ground_commands import CommandResult, refuse
from ascs_mode_manager.heao_modes import HeaoModeConfig, HeaoModeManager, Transition
from ascs_mode_manager.spin_mechanizations import AscsError


@dataclass(frozen=True)
class GasHandover:
    """The gas phases' transition conditions (rad/s, rad): rates damped; hand-over cone and rate."""

    damped_rate_rad_s: float
    handover_cone_rad: float
    handover_rate_rad_s: float

    def __post_init__(self) -> None:
        for name in ('damped_rate_rad_s', 'handover_cone_rad', 'handover_rate_rad_s'):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0.0):
                raise AscsError(f'{name} = {getattr(self, name)!r} must be > 0')


class ColdGasModeManager(HeaoModeManager):
    """HEAO mode logic with the gas acquisition phases in front (module docstring)."""

    def __init__(self, config: HeaoModeConfig, gas: GasHandover, initial_mode: str = 'gas_rate_damping') -> None:
        super().__init__(config)
        if initial_mode not in GAS_MODES:
            raise AscsError(f'initial_mode {initial_mode!r}: a heao_cold_gas acquisition starts in a gas mode '
                            f'({", ".join(GAS_MODES)})')
        self.gas = gas
        self.mode = initial_mode
        #: Sim time of the latest hand-over from gas to the wheels (s), None until it happens.
        self.handover_t_s: float | None = None

    def advance(self, t: float, omega: tuple[float, float, float], sun: tuple[float, float, float],
                sun_present: bool) -> list[Transition]:
        """The HEAO step (queued commands, Mode 1A/1B logic), then the gas phases' transfers (the cause's rates
        formatted at a transfer)."""
        out = super().advance(t, omega, sun, sun_present)
        w = [abs(x) for x in omega]
        if self.mode == 'gas_rate_damping' and max(w) <= self.gas.damped_rate_rad_s:
            out.append(self._enter(t, 'gas_sun_acquisition', f'rates damped on gas ({_rates(w)} ≤ '
                                   f'{deg(self.gas.damped_rate_rad_s):.4f} deg/s)'))
        elif self.mode == 'gas_sun_acquisition':
            norm = math.sqrt(sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2])
            if sun_present and norm > 0.0:
                angle = math.acos(max(-1.0, min(1.0, sun[2] / norm)))
                if angle <= self.gas.handover_cone_rad and max(w) <= self.gas.handover_rate_rad_s:
                    self.handover_t_s = t
                    out.append(self._enter(t, 'mode_1b', f'hand-over to the wheels: z {deg(angle):.2f}° from the sun '
                                           f'line, {_rates(w)} ≤ {deg(self.gas.handover_rate_rad_s):.4f} deg/s'))
        return out

    #: The HEAO commands and the cold-gas hardware's.
    grammar = (*HeaoModeManager.grammar, GasCommand)

    def apply(self, cmd: Command, t_s: float) -> CommandResult:
        """``mode reacquire`` here (a gas mode by name is refused); every other command as in the HEAO logic
        (``gas …`` is routed to cold_gas)."""
        if isinstance(cmd, ModeCommand) and cmd.target == 'reacquire':
            current = self._effective_mode()
            if current in GAS_MODES:
                return refuse(f'wrong mode: already acquiring on gas ({current})')
            self._pending.append(('gas_rate_damping', float(t_s), 'mode reacquire'))
            return CommandResult(True, f'{current} → gas_rate_damping (sun reacquisition on gas) at the next step',
                                 None, 'mode reacquire')
        if isinstance(cmd, ModeCommand) and cmd.target in GAS_MODES:
            return refuse('wrong mode: the gas modes are entered by the acquisition sequence or by "mode reacquire"')
        return super().apply(cmd, t_s)

    def status_state(self) -> tuple[object, ...]:
        """The HEAO status values and the hand-over time."""
        return *super().status_state(), self.handover_t_s

    def status(self) -> dict[str, str]:
        """The HEAO status and the hand-over time (s, '' before it)."""
        return {**super().status(), 'handover_t_s': '' if self.handover_t_s is None else f'{self.handover_t_s:.3f}'}


def _rates(w: list[float]) -> str:
    """|ω_i| (rad/s) as a transfer cause gives them, deg/s."""
    return ', '.join(f'|ω{a}|={deg(x):.4f}' for a, x in zip('xyz', w, strict=True))
