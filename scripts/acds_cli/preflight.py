"""Pre-flight: check a scenario against the models' own physical validity before any process starts.

The schema checks types, units and ranges; a model's core knows more (an
inertia tensor must be positive definite and obey the triangle inequality).
Running those checks here turns a node's start-up failure into one clear
scenario error naming the key.
"""

from __future__ import annotations

from acds_common.scenario import Scenario, ScenarioError


def preflight(scenario: Scenario) -> None:
    """Raise ScenarioError naming the scenario key a core model rejects."""
    from dynamics.rigid_body_model import inertia_tensor

    try:
        inertia_tensor(*scenario.get('spacecraft', 'inertia'))
    except ValueError as exc:
        raise ScenarioError(f'{scenario.path}: spacecraft.inertia: {exc}') from None
