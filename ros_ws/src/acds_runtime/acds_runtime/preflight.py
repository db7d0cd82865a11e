"""Pre-flight: build every node's stepper in the launcher, exactly as the node builds it, before any process starts.

The schema checks types, units and ranges; a model's core knows more (an inertia tensor
must be positive definite and obey the triangle inequality, an apogee lies above the
perigee, a ground-command schedule reads "T_S: command", a comparator level is above
zero, ...). The pre-flight writes the parameters the nodes will get, builds the graph
declaration from them (one publisher per per-step topic, no lag-0 cycle) and constructs
each node's stepper from its parameters — the very code a node process runs on start-up —
turning the core's own exception (its builders name the scenario section or key) into one
:class:`ScenarioError` line. The steppers built here are thrown away.
"""

from __future__ import annotations

from acds_common.graph import build_graph
from acds_common.parameters import node_parameters, normalize
from acds_common.scenario import Scenario, ScenarioError
from acds_common.stepper import load_stepper


def preflight(scenario: Scenario) -> None:
    """Raise ScenarioError naming the scenario section or key a node's stepper (its core model) rejects."""
    params = node_parameters(scenario, scenario.total_steps())
    try:
        graph = build_graph(params)
    except ValueError as exc:
        raise ScenarioError(f'{scenario.path}: nodes: {exc}') from None
    for name, spec in graph.nodes.items():  # the scenario's order: the rigid body (inertia) first
        try:
            load_stepper(spec.stepper)(normalize(spec.name, params[name]), log=lambda _level, _text: None)
        except ValueError as exc:  # every package's exception is a ValueError with a message naming the key
            raise ScenarioError(f'{scenario.path}: {exc} (the {name} model refuses it)') from None
