"""The cold-gas acquisition's part of the ascs_mode_manager stepper (``modes.system: heao_cold_gas``; seed 002 §3.1).

The HEAO part (:mod:`ascs_mode_manager.heao_part`: ground commands, ``mode``, ``events``) around the core
:class:`~ascs_mode_manager.cold_gas_modes.ColdGasModeManager`: gas rate damping → gas sun acquisition → hand-over
to Mode 1B, then the HEAO capture and cruise.
"""

from __future__ import annotations

from typing import Any

from ascs_mode_manager.cold_gas_modes import ColdGasModeManager, GasHandover
from ascs_mode_manager.heao_part import HeaoPart, heao_config


def build_gas_core(m: dict[str, Any]) -> ColdGasModeManager:
    """The HEAO mode logic with the gas acquisition in front, from the scenario's ``modes`` section (SI values)."""
    return ColdGasModeManager(heao_config(m), GasHandover(m['gas_damped_rate'], m['gas_handover_cone'],
                                                          m['gas_handover_rate']), m['initial_mode'])


class ColdGasPart(HeaoPart):
    """The HEAO mode logic with the cold-gas acquisition (module docstring)."""

    build_core = staticmethod(build_gas_core)
