"""``acds params SCENARIO [--node NODE]``: the ROS 2 parameters file the launcher gives the nodes.

The same dump :class:`~acds_runtime.launcher.GraphRun` writes to a run's ``params.yaml``
(:func:`acds_common.parameters.parameters_yaml` of
:func:`~acds_common.parameters.node_parameters`), so any node can be started by hand::

    ./scripts/acds params SCENARIO --node reaction_wheels > rw.yaml
    .venv/bin/reaction_wheels --ros-args --params-file rw.yaml

With ``--node`` the file starts with comments saying what that node then waits for.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..arguments import UsageError, real_time_factor, step_count
from .run import DEFAULT_SCENARIO


def waits_for(node: str, params: dict[str, Any]) -> list[str]:
    """What ``node`` (with these parameters) waits for before its first step, one line each."""
    from acds_common import topics
    from acds_common.graph import MONITOR_NAME, node_spec, time_owner_among

    spec = node_spec(node.rpartition('/')[2], params)  # a formation vehicle's node: VEHICLE/NODE
    owner = time_owner_among(params['graph_nodes'])
    present = set(params['graph_nodes'])
    lines = [f'a publisher on {spec.topic(i.topic)} (from {i.source})'
             for st in spec.stages for i in st.inputs if i.source in present]
    lines = list(dict.fromkeys(lines))
    if spec.time_owner:
        others = sorted(present - {spec.instance})
        if others:
            lines.append(f'a {topics.resolve(topics.READY)} message from each of {", ".join(others)}')
        if MONITOR_NAME in present:
            lines.append(f'then, every step, {topics.resolve(topics.MONITOR_ACK)} from {MONITOR_NAME} '
                         f'(the recorder; remove it from graph_nodes to run without one)')
    else:
        if any(not any(i.lag == 0 and i.source in present for i in st.inputs) for st in spec.stages):
            lines.append(f'then {topics.CLOCK} from {owner}, step by step')
        if owner:
            lines.append(f'(no step after the one {owner} names on {topics.RUN_END} as the run ends: it then waits '
                         'for nothing and stays until stopped)')
    return lines


def _params(args: argparse.Namespace) -> int:
    from acds_common import topics
    from acds_common.parameters import node_parameters, parameters_yaml
    from acds_common.scenario import load_scenario

    scenario = load_scenario(args.scenario or DEFAULT_SCENARIO)
    steps = args.steps if args.steps is not None else scenario.total_steps()
    params = node_parameters(scenario, steps, args.rtf)
    if args.node is not None:
        if args.node not in params:
            raise UsageError(f'--node {args.node}: scenario {scenario.name} runs no such node '
                             f'(its nodes: {", ".join(params)})')
        params = {args.node: params[args.node]}
        timeout = max(params[args.node]['input_timeout_s'], 20.0)
        vehicle, _, exe = args.node.rpartition('/')  # a formation vehicle's node runs in the vehicle's namespace
        remap = f'-r __ns:={topics.NAMESPACE}/{vehicle} ' if vehicle else ''
        head = [f'ROS 2 parameters of /acds/{args.node}, scenario {scenario.name} ({steps} steps).',
                f'Start it by hand: .venv/bin/{exe} --ros-args {remap}--params-file THIS_FILE',
                f'It then waits (at most {timeout:g} s, else it exits 3 naming what is missing) for:',
                *(f'  {line}' for line in waits_for(args.node, params[args.node]))]
        sys.stdout.write(''.join(f'# {line}\n' for line in head))
    sys.stdout.write(parameters_yaml(params))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``params`` verb."""
    p = sub.add_parser('params', help='print the ROS 2 parameters file the launcher gives the nodes',
                       description='Print the ROS 2 parameters YAML (params.yaml of a run) of SCENARIO: every '
                                   'node, or --node NODE with what that node waits for once started by hand '
                                   '(.venv/bin/NODE --ros-args --params-file FILE).')
    p.add_argument('scenario', nargs='?', help=f'scenario name or path (default {DEFAULT_SCENARIO})')
    p.add_argument('--node', help='only this node (e.g. rigid_body, reaction_wheels)')
    p.add_argument('--steps', type=step_count, help='total_steps of rigid_body (default: the scenario duration)')
    p.add_argument('--rtf', type=real_time_factor, default=0.0,
                   help='real_time_factor of the time owner (default 0: as fast as possible)')
    p.set_defaults(func=_params)
