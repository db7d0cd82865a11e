"""``acds contract`` (issue 20 §2): a node's contract is the graph's own declaration, in Markdown or YAML."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from acds_cli.verbs.contract import markdown, node_contract
from acds_common.graph import build_graph
from acds_common.parameters import node_parameters
from acds_common.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[1]


def _acds(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, '-m', 'acds_cli', *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=120, check=False)


@pytest.mark.parametrize('name', ['heao_b_acquisition', 'oresat_detumble'])
def test_the_contract_lists_exactly_the_ports_of_the_built_graph(name):
    sc = load_scenario(name)
    spec = build_graph(node_parameters(sc, sc.total_steps())).nodes['acds_controller']
    c = node_contract(sc, 'acds_controller')
    assert [(i['topic'], i['source'], i['lag']) for i in c['inputs']] == \
        [(spec.topic(i.topic), i.source, i.lag) for st in spec.stages for i in st.inputs]
    assert [(o['topic'], o['type'], o['every_step'], o['stamp_offset']) for o in c['outputs']] == \
        [(spec.topic(o.topic), o.msg_type, o.every_step, o.stamp_offset) for o in spec.outputs]
    assert c['control_period_s'] == sc.control_period_s
    assert all(i['qos']['reliability'] == 'reliable' and i['qos']['depth'] > 0 for i in c['inputs'])
    assert {p['name'] for p in c['parameters']} == set(yaml.safe_load(c['parameters_file'])[
        '/acds/acds_controller']['ros__parameters'])
    assert '| `/acds/controller/moment_command` |' in markdown(c)


def test_the_yaml_contract_parses_and_the_markdown_is_the_default():
    out = _acds('contract', 'oresat_detumble', '--node', 'acds_controller', '--format', 'yaml')
    assert out.returncode == 0, out.stderr
    c = yaml.safe_load(out.stdout)
    assert c['node'] == 'acds_controller' and c['scenario'] == 'oresat_detumble'
    coil = next(i for i in c['inputs'] if i['topic'] == '/acds/em_driver/coil_current')
    assert coil['lag'] == 1 and coil['source'] == 'em_driver' and coil['unit'] == 'A'
    mode = next(i for i in c['inputs'] if i['topic'] == '/acds/mode')
    assert not mode['present']  # no mode manager in the OreSat graph
    params = yaml.safe_load(c['parameters_file'])['/acds/acds_controller']['ros__parameters']
    assert params['controller_acquisition_law'] == 'b_cross_omega'
    md = _acds('contract', 'oresat_detumble', '--node', 'acds_controller')
    assert md.returncode == 0 and md.stdout.startswith('# Contract of `acds_controller` in `oresat_detumble`')


@pytest.mark.parametrize('args', [('oresat_detumble', '--node', 'reaction_wheels'),
                                  ('no_such_scenario', '--node', 'acds_controller')])
def test_an_unknown_node_or_scenario_is_one_line_exit_2(args):
    out = _acds('contract', *args)
    assert out.returncode == 2
    assert len(out.stderr.strip().splitlines()) == 1 and out.stdout == ''
