"""Node parameters: one declaration per parameter (type, default, range, unit, meaning), no rclpy.

Every node's parameters are the lockstep ones (:data:`LOCKSTEP`, plus :data:`TIME_OWNER_ONLY`
for the time owner) and the fields of the scenario sections its package declares it reads
(:attr:`acds_common.graph.Node.sections`, named ``<section>_<field>_<si unit>``). The ROS
host declares each as a typed, described, range-checked, read-only ROS parameter; the direct
engine passes the same values; both go through :func:`normalize`, so a node core sees the same
Python values in either engine.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import yaml

from acds_common import topics
from acds_common.graph import MONITOR_NAME, declared_node, external_parameter
from acds_common.scenario import MAX_STEPS, REQUIRED, SCHEMA, Scenario


class ConfigError(ValueError):
    """A node's parameters are wrong (missing, unknown, out of range, inconsistent)."""


@dataclass(frozen=True)
class ParamSpec:
    """One node parameter. ``kind``: float | int | bool | str | floats | strs. ``required``: no default."""

    name: str
    kind: str
    default: Any
    description: str
    unit: str = ''
    lo: float | None = None
    hi: float | None = None
    choices: tuple[str, ...] = ()
    length: int | None = None

    @property
    def required(self) -> bool:
        """The launcher always supplies it; a node started without it stops with 'missing parameter'."""
        return self.default is REQUIRED


#: Parameters every lockstep node takes.
LOCKSTEP: tuple[ParamSpec, ...] = (
    ParamSpec('control_period_s', 'float', 0.5, 'lockstep control period Δt (the DPA cycle)', 's', 1e-4, 60.0),
    ParamSpec('graph_nodes', 'strs', REQUIRED, 'names of the nodes present in this graph (inputs from others '
              'are absent)'),
    ParamSpec('input_timeout_s', 'float', 30.0, 'wall seconds a stage may wait for an input before the run '
              'fails', 's', 0.1, 3600.0),
    ParamSpec('seed', 'int', 1, 'scenario random seed (deterministic noise streams)', '', 0, 2**31 - 1),
    ParamSpec('deadline_ms', 'float', 0.0, 'wall-time budget of one step, from its last input to its published '
              'outputs (0: none); steps over it are counted (issue 20 §4)', 'ms', 0.0, 3.6e6),
    ParamSpec('deadline_strict', 'bool', False, 'fail the run at the first step over deadline_ms'),
    ParamSpec('external_nodes', 'strs', [], 'nodes of graph_nodes that the user runs (issue 20): '
              '"instance=ROS identity" entries; their publishers carry that identity, and they send no READY'),
    ParamSpec('vehicle', 'str', '', 'the formation vehicle this node belongs to (its namespace /acds/<vehicle>); '
              "'' in a single-vehicle graph"),
)
#: Fastest pacing a run may ask for (``real_time_factor``; 0 = as fast as possible).
MAX_REAL_TIME_FACTOR = 1e6
#: Parameters of the time owner only.
TIME_OWNER_ONLY: tuple[ParamSpec, ...] = (
    ParamSpec('total_steps', 'int', REQUIRED, 'number of control steps to run', '', 1, MAX_STEPS),
    ParamSpec('real_time_factor', 'float', 0.0, 'pace sim time at this multiple of wall time (0: as fast as '
              'possible)', '', 0.0, MAX_REAL_TIME_FACTOR),
)


#: The parameter naming a formation's vehicles (declared first: it decides the rest).
FORMATION_VEHICLES = ParamSpec('formation_vehicles', 'strs', REQUIRED, 'names of the formation\'s vehicles, in '
                               'order (each one\'s sections are the parameters <vehicle>.<name>)')


def _section_specs(section: str, prefix: str = '') -> list[ParamSpec]:
    out = []
    for name, f in SCHEMA[section].items():
        bounded = f.kind not in ('str', 'bool', 'strs')
        out.append(ParamSpec(
            prefix + f.param_name(section, name), f.kind, f.default, f.doc, f.si,
            f.lo if bounded else None, f.hi if bounded else None,
            f.choices if f.kind in ('str', 'strs') else (), f.length))
    return out


def node_param_specs(node: str, vehicles: list[str] | tuple[str, ...] = (),
                     graph_nodes: list[str] | tuple[str, ...] = ()) -> list[ParamSpec]:
    """Every parameter of ``node`` in a graph of ``graph_nodes``: lockstep ones, then the fields of the scenario
    sections it reads there (:meth:`~acds_common.graph.Node.sections_in`); a formation-wide node
    (:func:`formation_wide`) also has ``formation_vehicles`` and each vehicle's sections."""
    _pkg, decl = declared_node(node)
    specs = list(LOCKSTEP) + (list(TIME_OWNER_ONLY) if decl.time_owner else [])
    for section in decl.sections_in(graph_nodes):
        specs.extend(_section_specs(section))
    if decl.every_vehicle:
        specs.append(FORMATION_VEHICLES)
        for v in vehicles:
            for section in decl.every_vehicle:
                specs.extend(_section_specs(section, f'{v}.'))
    return specs


def formation_wide(node: str) -> bool:
    """Whether ``node`` acts on the whole formation (it takes every vehicle's sections as ``<vehicle>.<parameter>``)."""
    return bool(declared_node(node)[1].every_vehicle)


def _check(spec: ParamSpec, node: str, value: Any) -> Any:
    where = f'{node}: parameter {spec.name}'
    if spec.kind in ('floats', 'strs'):
        if not isinstance(value, (list, tuple)):
            raise ConfigError(f'{where} must be a list, got {value!r}')
        items = list(value)
        if spec.length is not None and len(items) not in (0, spec.length):
            raise ConfigError(f'{where} must have {spec.length} values, got {len(items)}')
        scalar_kind = 'float' if spec.kind == 'floats' else 'str'
        return [_scalar(spec, scalar_kind, where, v) for v in items]
    return _scalar(spec, spec.kind, where, value)


def _scalar(spec: ParamSpec, kind: str, where: str, value: Any) -> Any:
    if kind == 'float':
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f'{where} must be a number, got {value!r}')
        value = float(value)
    elif kind == 'int':
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f'{where} must be an integer, got {value!r}')
    elif kind == 'bool':
        if not isinstance(value, bool):
            raise ConfigError(f'{where} must be true or false, got {value!r}')
        return value
    else:
        if not isinstance(value, str):
            raise ConfigError(f'{where} must be a string, got {value!r}')
        if spec.choices and value not in spec.choices:
            raise ConfigError(f'{where}={value!r} not one of {list(spec.choices)}')
        return value
    if not math.isfinite(value):
        raise ConfigError(f'{where} is not finite: {value}')
    if (spec.lo is not None and value < spec.lo) or (spec.hi is not None and value > spec.hi):
        raise ConfigError(f'{where}={value} outside [{spec.lo}, {spec.hi}]{" " + spec.unit if spec.unit else ""}')
    return value


def normalize(node: str, given: dict[str, Any]) -> dict[str, Any]:
    """The node's parameter values: defaults filled in, types and ranges checked, unknown names refused.

    ``given`` maps parameter names to values (a params file, or the scenario's
    :func:`~acds_common.scenario.Scenario.node_parameters`); a ROS host passes ``None`` for a
    parameter it did not receive.
    """
    specs = node_param_specs(node, given.get('formation_vehicles') or (), given.get('graph_nodes') or ())
    known = {s.name for s in specs}
    unknown = sorted(set(given) - known - {'use_sim_time'})
    if unknown:
        raise ConfigError(f'{node}: unknown parameter(s) {", ".join(unknown)} (declared: {", ".join(sorted(known))})')
    out: dict[str, Any] = {}
    for spec in specs:
        value = given.get(spec.name)
        if value is None:
            if spec.required:
                raise ConfigError(f'{node}: missing parameter {spec.name} ({spec.description}); start the node '
                                  f'with --ros-args --params-file FILE (./scripts/acds params SCENARIO)')
            value = spec.default
        out[spec.name] = _check(spec, node, value)
    return out


def section(params: dict[str, Any], name: str, vehicle: str = '') -> dict[str, Any]:
    """{field: value} of scenario section ``name`` from normalized node parameters (SI); ``vehicle``: that
    formation vehicle's copy, which the formation-wide nodes receive as ``<vehicle>.<parameter>``."""
    prefix = f'{vehicle}.' if vehicle else ''
    return {field: params[prefix + f.param_name(name, field)] for field, f in SCHEMA[name].items()}


def node_parameters(scenario: Scenario, steps: int, rtf: float = 0.0,
                    overrides: dict[str, dict[str, Any]] | None = None,
                    external: dict[str, str] | None = None) -> dict[str, dict[str, Any]]:
    """Every node's parameters for a run of ``steps`` steps: the lockstep ones plus its scenario sections.

    What the launcher writes to ``params.yaml`` and the direct engine passes its steppers, by instance:
    ``<node>`` for the nodes of the whole graph, ``<vehicle>/<node>`` for a formation vehicle's (which get
    parameter ``vehicle``). Empty lists are left out (rcl cannot type an empty list: the node's default).
    ``external``: {instance: ROS identity} of the nodes the user runs (default: the scenario's,
    :meth:`~acds_common.scenario.Scenario.external`); they are part of the graph (parameters included: the
    contract's parameters file), not started by the launcher.
    """
    instances = scenario.instances()
    vehicles = [v['name'] for v in scenario.values.get('vehicles', [])]
    common = {
        'control_period_s': scenario.control_period_s,
        'graph_nodes': [inst for inst, _n, _v in instances] + [MONITOR_NAME],
        'input_timeout_s': scenario.get('', 'input_timeout'),
        'seed': scenario.get('', 'seed'),
        'external_nodes': external_parameter(scenario.external() if external is None else external),
    }
    out: dict[str, dict[str, Any]] = {}
    for inst, node, vehicle in instances:
        params = {**common, **scenario.node_parameters(node, vehicle)}
        if vehicle:
            params['vehicle'] = vehicle
        _pkg, decl = declared_node(node)
        if decl.every_vehicle:
            params['formation_vehicles'] = vehicles
        if decl.time_owner:
            params.update(total_steps=steps, real_time_factor=rtf)
        params.update((overrides or {}).get(inst, {}))
        out[inst] = {k: v for k, v in params.items() if v != []}  # rcl cannot type an empty list: node default
    return out


class NoAliasDumper(yaml.SafeDumper):
    """rcl's params-file parser rejects YAML aliases: write every value out."""

    def ignore_aliases(self, data: Any) -> bool:
        return True


def parameters_yaml(params_by_node: dict[str, dict[str, Any]]) -> str:
    """The ROS 2 parameters file of the given nodes (``/acds/<node>: ros__parameters: {...}``).

    What the launcher writes to a run's ``params.yaml`` and ``acds params`` prints: any node
    started with ``--ros-args --params-file FILE`` takes its own section.
    """
    return yaml.dump({f'{topics.NAMESPACE}/{n}': {'ros__parameters': p} for n, p in params_by_node.items()},
                     Dumper=NoAliasDumper, sort_keys=True)
