"""The HEAO mode logic's limits on the common figures (``acds plot``) and the live view (Foxglove): entry point
``acds.limits`` (:func:`acds_common.plugins.limits`; docs/architecture.md "Adding a mission").

A run whose mode manager ran the HEAO logic (``modes.system: heao``) compares |ω_i| with the Mode 1A → 1B
body-rate thresholds and captures when body z is within the capture cone of the sun line (seed 002 §4); both
are the values the node ran with (its parameters, as a bag stores them).
"""

from __future__ import annotations

from typing import Any

from acds_common.scenario import SCHEMA


def _modes(params: dict[str, dict[str, Any]], key: str) -> Any:
    """``modes.<key>`` as the mode manager received it (None: no mode manager in the graph)."""
    return params.get('ascs_mode_manager', {}).get(SCHEMA['modes'][key].param_name('modes', key))


def limits(params: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """``rate_thresholds`` (rad/s per body axis) and ``capture_cone`` (rad) of a HEAO mode manager's run, else {}."""
    if _modes(params, 'system') != 'heao':
        return {}
    return {'rate_thresholds': _modes(params, 'rate_thresholds'), 'capture_cone': _modes(params, 'capture_cone')}
