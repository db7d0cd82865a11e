"""Pre-flight: build every model the graph's nodes will build, in the launcher, before any process starts.

The schema checks types, units and ranges; a model's core knows more (an
inertia tensor must be positive definite and obey the triangle inequality, an
apogee lies above the perigee, a ground-command schedule reads "T_S: command",
the SSS polarity level is above zero, ...). For each node of the scenario this
calls the very builder the node calls on start-up (``<package>.configuration``
or the core module's ``build_*``), with the same sections, and turns the core's
own exception into one :class:`ScenarioError` line naming the file and the
section or key. The models built here are thrown away.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from acds_common.scenario import NODE_SECTIONS, Scenario, ScenarioError


def _checks(sc: Scenario) -> dict[str, list[tuple[str, Callable[[], Any]]]]:
    """Per node: (section label, builder call); an empty label means the builder names the key itself."""
    from acds_controller.configuration import build_dpa
    from ascs_mode_manager.ground_commands import GroundCommandQueue
    from ascs_mode_manager.heao_part import build_core
    from ascs_mode_manager.sss_ascs import build_sss_ascs
    from dynamics.configuration import build_rigid_body, build_wheels
    from em_driver.configuration import build_assembly
    from magnetometer_sim.configuration import build_magnetometer

    v = sc.values
    modes = v['modes']
    return {
        'rigid_body': [('', lambda: build_rigid_body(*(v[s] for s in NODE_SECTIONS['rigid_body'])))],
        'reaction_wheels': [('', lambda: build_wheels(v['wheels']))],
        'magnetometer_sim': [('magnetometer', lambda: build_magnetometer(v['magnetometer'], sc.get('', 'seed')))],
        'em_driver': [('em_driver', lambda: build_assembly(v['em_driver']))],
        'acds_controller': [('controller', lambda: build_dpa(v['spacecraft'], v['controller'], v['magnetometer']))],
        'ascs_mode_manager': [
            ('', lambda: GroundCommandQueue(modes['ground_commands'])),
            ('modes', lambda: build_core(modes)) if modes['system'] == 'heao' else ('sss', lambda: build_sss_ascs(v['sss'])),
        ],
    }


def preflight(scenario: Scenario) -> None:
    """Raise ScenarioError naming the scenario section or key a node's core model rejects."""
    from acds_controller.magnetic_laws import ControllerError
    from ascs_mode_manager.spin_mechanizations import AscsError
    from dynamics.environment import DynamicsError
    from em_driver.bridge_switch import EmDriverError
    from magnetometer_sim.fluxgate import MagnetometerError

    checks = _checks(scenario)
    nodes = scenario.get('', 'nodes')
    for node in (n for n in NODE_SECTIONS if n in nodes):  # fixed order: the rigid body (inertia) first
        for label, build in checks[node]:
            try:
                build()
            except (DynamicsError, MagnetometerError, EmDriverError, ControllerError, AscsError) as exc:
                where = f'{label}: ' if label else ''
                raise ScenarioError(f'{scenario.path}: {where}{exc} (the {node} model refuses it)') from None
