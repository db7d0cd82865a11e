"""``acds contract SCENARIO --node NODE [--format md|yaml]``: what a node of a scenario's graph reads and publishes.

The contract a replacement for the node implements (issue 20 §2): every input topic (its source node, lag,
message type, QoS, the step/stamp rule), every output (type, frame, unit, per step or not, QoS), the fields
that carry data, the rate, and the node's ROS parameters (type, unit, range, value) as a parameters file.
Everything comes from the declarations the graph is built from (:func:`acds_common.graph.build_graph` of
:func:`acds_common.parameters.node_parameters`, the packages' :class:`~acds_common.graph.Topic` s, the
lockstep host's QoS profiles), so the contract cannot disagree with the graph that runs.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

import yaml

from ..arguments import UsageError
from .run import DEFAULT_SCENARIO

#: Entry-point group of contract plug-ins: the side of a node's contract a package adds beyond its topics (a bus, a
#: device). Each entry names a module with
#:   ``resolve(scenario, name)``: None, or (graph node, detail) when ``--node name`` is its node or a part of it (a
#:   device the node serves: detail names it, '' for the whole node);
#:   ``extend(scenario, contract, detail)``: adds its keys to the contract (YAML shows them as they are);
#:   ``markdown(contract)``: its Markdown lines, after the contract's own;
#:   ``FORMATS`` {name: help} and ``write(fmt, scenario, detail)``: the text of a format of its own (ValueError: one
#:   line, a usage error).
CONTRACT_PLUGINS = 'acds.contract'


def contract_plugins() -> list:
    """The modules the entry-point group :data:`CONTRACT_PLUGINS` names, in name order."""
    from importlib.metadata import entry_points

    return [ep.load() for ep in sorted(entry_points(group=CONTRACT_PLUGINS), key=lambda e: e.name)]


def _qos(profile: Any) -> dict[str, Any]:
    return {'reliability': profile.reliability.name.lower(), 'durability': profile.durability.name.lower(),
            'history': profile.history.name.lower(), 'depth': profile.depth}


#: What reading a truth topic means for an external flight computer (no spacecraft measures its own truth).
TRUTH_REALISM = ('truth: the simulated world itself, which no sensor on board gives; a flight computer that reads '
                 'it is better informed than flight hardware allows (fine for a test harness, not for a claim about '
                 'flight performance)')


def _declaration(name: str) -> Any:
    from acds_common import topics
    from acds_common.graph import declared_topics

    decl = declared_topics().get(topics.relative(name))
    if decl is None:  # a formation vehicle's topic: the single-vehicle declaration under its namespace
        decl = declared_topics().get(topics.relative(name).partition('/')[2])
    return decl


def _topic_info(name: str) -> dict[str, Any]:
    """Type, unit, meaning and data fields of a topic, as its package (or the mechanism) declares it."""
    from acds_common import topics
    from acds_common.cdr import DATA_FIELDS

    msg_type = topics.type_of(name)
    decl = _declaration(name)
    return {'type': msg_type, 'unit': decl.unit if decl else '', 'meaning': decl.doc if decl else '',
            'data_fields': DATA_FIELDS[msg_type]}


def _realism(name: str) -> str:
    decl = _declaration(name)
    if decl is not None and decl.realism:
        return decl.realism
    return TRUTH_REALISM if '/truth/' in name else ''


def _transfer(name: str, source: str, graph: Any, params: dict[str, dict[str, Any]]) -> list[str]:
    """The declared transfer of a raw-unit topic to engineering units, from its producing node's parameters."""
    from acds_common.parameters import normalize

    decl = _declaration(name)
    if decl is None or decl.transfer is None or not graph.present(source):
        return []
    return decl.transfer(normalize(graph.nodes[source].name, params[source]))


def scenario_contracts(scenario: Any) -> dict[str, dict[str, Any]]:
    """The contract of every node of ``scenario``'s graph, by instance (its parameters and graph built once)."""
    from acds_common.graph import build_graph
    from acds_common.parameters import node_parameters

    params = node_parameters(scenario, scenario.total_steps())
    graph = build_graph(params)
    return {node: _node_contract(scenario, node, params, graph) for node in params}


def node_contract(scenario: Any, node: str, steps: int | None = None) -> dict[str, Any]:
    """The contract of instance ``node`` in ``scenario``'s graph (UsageError when the graph has no such node)."""
    from acds_common.graph import build_graph
    from acds_common.parameters import node_parameters

    params = node_parameters(scenario, steps if steps is not None else scenario.total_steps())
    if node not in params:
        raise UsageError(f'--node {node}: scenario {scenario.name} runs no such node (its nodes: {", ".join(params)})')
    return _node_contract(scenario, node, params, build_graph(params))


def _node_contract(scenario: Any, node: str, params: dict[str, dict[str, Any]], graph: Any) -> dict[str, Any]:
    from acds_common import topics
    from acds_common.lockstep import COMMAND_QOS, LOCKSTEP_QOS
    from acds_common.parameters import node_param_specs, parameters_yaml

    spec = graph.nodes[node]
    dt = scenario.control_period_s
    lockstep_qos, command_qos = _qos(LOCKSTEP_QOS), _qos(COMMAND_QOS)
    inputs = []
    for stage in spec.stages:
        for inp in stage.inputs:
            present = graph.present(inp.source)
            rule = (f"step k reads the source's step k−{inp.lag} message (stamp (k−{inp.lag})·Δt; none for k < {inp.lag})"
                    if inp.lag else "step k reads the source's step k message (stamp k·Δt)")
            name = spec.topic(inp.topic)
            inputs.append({'topic': name, **_topic_info(name), 'source': inp.source,
                           'present': present, 'stage': stage.name, 'lag': inp.lag, 'qos': lockstep_qos,
                           'rule': rule if present else 'source not in this graph: the input is absent (not subscribed)',
                           'transfer': _transfer(name, inp.source, graph, params), 'realism': _realism(name)})
    clock = (not spec.time_owner and
             any(not any(i.lag == 0 and graph.present(i.source) for i in st.inputs) for st in spec.stages))
    read = {i['topic'] for i in inputs}
    others = [{'topic': other.topic(o.topic), **_topic_info(other.topic(o.topic)), 'source': inst,
               'frame_id': o.frame_id, 'realism': _realism(other.topic(o.topic)),
               'transfer': _transfer(other.topic(o.topic), inst, graph, params)}
              for inst, other in graph.nodes.items() if inst != node
              for o in other.outputs if o.every_step and o.lockstep and other.topic(o.topic) not in read]
    outputs = []
    for out in spec.outputs:
        name = spec.topic(out.topic)
        when = 'one message per step' if out.every_step else 'only when the node has something to say'
        if out.many:
            when += ' (several messages of one step possible)'
        outputs.append({'topic': name, **_topic_info(name), 'frame_id': out.frame_id,
                        'child_frame_id': out.child_frame_id, 'every_step': out.every_step,
                        'stamp_offset': out.stamp_offset, 'qos': lockstep_qos if out.lockstep else command_qos,
                        'rule': f'{when}, the output of step k stamped (k+{out.stamp_offset})·Δt'
                        if out.stamp_offset else f'{when}, the output of step k stamped k·Δt',
                        'transfer': _transfer(name, node, graph, params)})
    if spec.time_owner:
        outputs.append({'topic': topics.CLOCK, **_topic_info(topics.CLOCK), 'frame_id': '', 'child_frame_id': '',
                        'every_step': True, 'stamp_offset': 0, 'qos': lockstep_qos,
                        'rule': 'announces step k (clock k·Δt) once the outputs of step k are published', 'transfer': []})
    rules = ['an output for step k is stamped k·Δt plus its declared stamp_offset (integer nanoseconds, exactly)',
             "a lag-L input of step k is the source's step k−L message; an input whose source is not in the graph "
             'is absent',
             "the node fires its stages in order, once per step, each when it holds all of that step's inputs"]
    if clock:
        rules.append(f'a stage without a lag-0 input from a present node follows {topics.CLOCK} '
                     f'({topics.TYPES[topics.CLOCK]}, {lockstep_qos["reliability"]}): step k exists once /clock says k·Δt')
    if not spec.time_owner:
        rules.append(f'this project\'s node publishes its name once on {topics.READY} when every present input has '
                     'a publisher; a node run as external (acds run --external NODE[=ROS_NODE_NAME]) needs no '
                     'handshake: the graph starts step 0 once it publishes every per-step output and subscribes to '
                     'one present input at least (the readiness timeout names what is missing)')
        rules.append('external node: publish exactly one message per per-step output for each step k, stamped with the '
                     'step time of the inputs it answers (k·Δt), after holding all of step k\'s inputs; a second '
                     'message for a step, a skipped step or another stamp fails the run naming the topic and the step; '
                     'any other publisher on its topics fails the run as an intruder')
        rules.append(f'the run ends at the step the time owner publishes on {topics.RUN_END} '
                     f'({topics.TYPES[topics.RUN_END]}, transient local): no step after it comes, so a node waits '
                     'for none (it stays until it is stopped)')
    else:
        rules.append('the time owner cannot be external (it publishes /clock and paces the graph)')
        rules.append(f'as it finishes, it publishes its last step on {topics.RUN_END} '
                     f'({topics.TYPES[topics.RUN_END]}) before it delivers its last messages and leaves')
    specs = {s.name: s for s in node_param_specs(spec.name, params[node].get('formation_vehicles') or (),
                                                 params[node]['graph_nodes'])}
    parameters = [{'name': name, 'type': specs[name].kind, 'unit': specs[name].unit,
                   'range': [specs[name].lo, specs[name].hi] if specs[name].lo is not None or specs[name].hi is not None
                   else None, 'choices': list(specs[name].choices) or None, 'value': value}
                  for name, value in sorted(params[node].items())]
    return {'node': node, 'package': spec.package, 'scenario': scenario.name, 'stepper': spec.stepper,
            'namespace': spec.namespace, 'control_period_s': dt, 'rate_hz': 1.0 / dt, 'time_owner': spec.time_owner,
            'follows_clock': clock, 'ground_commands': spec.ground_commands, 'rules': rules,
            'inputs': inputs, 'outputs': outputs, 'other_topics': others, 'parameters': parameters,
            'parameters_file': parameters_yaml({node: params[node]})}


def _cell(value: Any) -> str:
    return str(value).replace('|', '\\|') if value not in (None, '') else '—'


def markdown(c: dict[str, Any]) -> str:
    """The contract as Markdown (tables of inputs, outputs and parameters; the parameters file)."""
    lines = [f'# Contract of `{c["node"]}` in `{c["scenario"]}`', '',
             f'Package `{c["package"]}`, stepper `{c["stepper"]}`, namespace `{c["namespace"]}`. '
             f'Rate: Δt = {c["control_period_s"]:g} s ({c["rate_hz"]:g} Hz)'
             + ('; time owner' if c['time_owner'] else '') + ('; follows /clock' if c['follows_clock'] else '')
             + ('; takes ground commands (ground/command, command QoS)' if c['ground_commands'] else '') + '.', '',
             '## Step and stamp rules', '', *(f'- {r}' for r in c['rules']), '',
             '## Inputs', '',
             '| topic | type | unit | source | lag | stage | QoS | data fields | rule |',
             '| --- | --- | --- | --- | --- | --- | --- | --- | --- |']
    for i in c['inputs']:
        qos = f'{i["qos"]["reliability"]}, {i["qos"]["durability"]}, {i["qos"]["history"]} {i["qos"]["depth"]}'
        lines.append(f'| `{i["topic"]}` | {i["type"]} | {_cell(i["unit"])} | {i["source"]}'
                     f'{"" if i["present"] else " (absent)"} | {i["lag"]} | {i["stage"]} | {qos} | '
                     f'{_cell(i["data_fields"])} | {i["rule"]} |')
    lines += ['', '## Outputs', '',
              '| topic | type | unit | frame | every step | stamp | QoS | data fields |',
              '| --- | --- | --- | --- | --- | --- | --- | --- |']
    for o in c['outputs']:
        qos = f'{o["qos"]["reliability"]}, {o["qos"]["durability"]}, {o["qos"]["history"]} {o["qos"]["depth"]}'
        frame = o['frame_id'] + (f' → {o["child_frame_id"]}' if o['child_frame_id'] else '')
        lines.append(f'| `{o["topic"]}` | {o["type"]} | {_cell(o["unit"])} | {_cell(frame)} | '
                     f'{"yes" if o["every_step"] else "no"} | (k+{o["stamp_offset"]})·Δt | {qos} | '
                     f'{_cell(o["data_fields"])} |')
    raw = [(i['topic'], i['source'], i['transfer']) for i in c['inputs'] if i['transfer']] + \
        [(o['topic'], c['node'], o['transfer']) for o in c['outputs'] if o['transfer']]
    if raw:
        lines += ['', '## Raw units: transfer to engineering units', '',
                  'Generated from the producing node\'s parameters in this scenario.']
        for topic, source, transfer in raw:
            lines += ['', f'`{topic}` (from {source}):', '', *(f'- {t}' for t in transfer)]
    real = [i for i in c['inputs'] if i['realism'] and i['present']]
    if real:
        lines += ['', '## Realism of the inputs', '', *(f'- `{i["topic"]}`: {i["realism"]}' for i in real)]
    if c['other_topics']:
        lines += ['', '## Other per-step topics of this graph', '',
                  'Every other per-step topic of the graph, one message per step with the same QoS and stamp rule as '
                  'the inputs above (a node run as external may subscribe to any of them; the graph does not wait '
                  'for its reading). What reading it means for realism is in the last column.', '',
                  '| topic | type | unit | source | frame | meaning | realism |',
                  '| --- | --- | --- | --- | --- | --- | --- |']
        for o in c['other_topics']:
            lines.append(f'| `{o["topic"]}` | {o["type"]} | {_cell(o["unit"])} | {o["source"]} | '
                         f'{_cell(o["frame_id"])} | {_cell(o["meaning"])} | {_cell(o["realism"])} |')
    lines += ['', '## Parameters', '', '| name | type | unit | range | value |', '| --- | --- | --- | --- | --- |']
    for p in c['parameters']:
        rng = p['range'] and f'[{_cell(p["range"][0])}, {_cell(p["range"][1])}]'
        lines.append(f'| {p["name"]} | {p["type"]} | {_cell(p["unit"])} | {_cell(rng or p["choices"])} | '
                     f'{_cell(p["value"])} |')
    lines += ['', 'Parameters file (`--ros-args --params-file FILE`):', '', '```yaml', c['parameters_file'].rstrip(),
              '```', '']
    return '\n'.join(lines)


def _contract(args: argparse.Namespace) -> int:
    from acds_common.scenario import load_scenario

    scenario = load_scenario(args.scenario or DEFAULT_SCENARIO)
    node, detail, owner = args.node, '', None
    for plugin in contract_plugins():
        resolved = plugin.resolve(scenario, args.node)
        if resolved is not None:
            (node, detail), owner = resolved, plugin
            break
    if args.format not in ('md', 'yaml'):
        if owner is None or args.format not in owner.FORMATS:
            raise UsageError(f'--format {args.format}: not a format of node {args.node} in {scenario.name}')
        try:
            sys.stdout.write(owner.write(args.format, scenario, detail))
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        return 0
    c = node_contract(scenario, node)
    if owner is not None:
        owner.extend(scenario, c, detail)
    if args.format == 'yaml':
        sys.stdout.write(yaml.safe_dump(c, sort_keys=False, allow_unicode=True))
    else:
        sys.stdout.write(markdown(c) + ''.join(f'{line}\n' for plugin in contract_plugins() for line in plugin.markdown(c)))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``contract`` verb."""
    p = sub.add_parser('contract', help="print a node's contract: its topics, QoS, stamp rules, parameters",
                       description='Print what NODE reads and publishes in SCENARIO\'s graph: every input (source, '
                                   'lag, type, QoS, stamp rule), every output (type, frame, unit, per step or not, '
                                   'QoS), the data fields, the rate and its ROS parameters, from the declarations '
                                   'the graph is built from.')
    p.add_argument('scenario', nargs='?', help=f'scenario name or path (default {DEFAULT_SCENARIO})')
    p.add_argument('--node', required=True, help='the node (e.g. acds_controller; <vehicle>/<node> in a formation)')
    extra = {name: text for plugin in contract_plugins() for name, text in plugin.FORMATS.items()}
    p.add_argument('--format', choices=('md', 'yaml', *extra), default='md',
                   help='Markdown (default) or YAML' + ''.join(f'; {name}: {text}' for name, text in extra.items()))
    p.set_defaults(func=_contract)
