"""A contract an outsider can fly from: a controller written from the printed contract and the YAML alone.

``tests/fixtures/contract_controller.py`` imports no module of the emulator: it takes its topics, types, QoS,
output frame and the magnetometer volts' transfer to field from the contract file ``acds contract oresat_detumble
--node acds_controller --format yaml`` prints (generated here, as an outsider would), and its gains from the
scenario's YAML. Flown as the external ``acds_controller`` of ``oresat_detumble`` through the raw volts, it must
detumble the CubeSat (|ω| < 0.1°/s) within the run; its time is printed beside the built-in controller's.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from acds_common.scenario import SCENARIO_DIR, load_scenario
from acds_runtime.direct import DirectRun
from acds_runtime.testing import external_node

FIXTURE = Path(__file__).parent / 'fixtures' / 'contract_controller.py'
#: 100 min: the built-in controller detumbles at 91 min; the run stops a little after.
STEPS = 6000


def _contract(tmp_path: Path) -> Path:
    path = tmp_path / 'acds_controller.contract.yaml'
    text = subprocess.run([sys.executable, '-m', 'acds_cli', 'contract', 'oresat_detumble', '--node', 'acds_controller',
                           '--format', 'yaml'], capture_output=True, text=True, check=True).stdout
    path.write_text(text)
    return path


def test_the_outside_controller_imports_nothing_of_the_emulator():
    tree = ast.parse(FIXTURE.read_text())
    imported = {a.name.split('.')[0] for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names} | \
        {n.module.split('.')[0] for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
    src = Path(__file__).resolve().parents[1] / 'ros_ws' / 'src'
    ours = {p.name for p in src.iterdir() if (p / 'setup.py').exists()}
    assert imported and not imported & ours, imported & ours


def test_the_contract_gives_the_volts_transfer_and_the_graphs_other_topics(tmp_path):
    c = yaml.safe_load(_contract(tmp_path).read_text())
    volts = next(i for i in c['inputs'] if i['topic'] == '/acds/magnetometer/volts')
    text = ' '.join(volts['transfer'])
    for wanted in ('V_bias = 2.5 V', 'scale k = 2.5 V/G = 25000 V/T', 'range ±1 G', 'steps of 0.01 V = 0.004 G',
                   '/acds/magnetometer/bias_volts (the bias channel'):
        assert wanted in text, (wanted, text)
    others = {o['topic']: o for o in c['other_topics']}
    assert 'calibrated' in others['/acds/magnetometer/field']['realism']
    assert others['/acds/truth/b_body']['realism'].startswith('truth')
    assert not [p['name'] for p in c['parameters'] if p['name'].startswith('cold_gas_')]


@pytest.mark.slow
def test_an_outside_controller_from_the_contract_alone_detumbles_oresat(launch_graph, tmp_path):
    contract = _contract(tmp_path)
    built_in = DirectRun(load_scenario('oresat_detumble'), steps=STEPS).run().summary
    argv = [sys.executable, str(FIXTURE), str(contract), str(SCENARIO_DIR / 'oresat_detumble.yaml'), 'outside_detumble']
    with launch_graph('oresat_detumble', steps=STEPS, keep=False, external=['acds_controller=outside_detumble']) as graph:
        with external_node(graph, argv):
            ours = graph.wait().summary
    print(f"\nbuilt-in: detumble {built_in['detumble_time_min']:.2f} min, {built_in['detumble_energy_j']:.4f} J; "
          f"outside controller from the contract: {ours['detumble_time_min']} min, {ours['detumble_energy_j']:.4f} J")
    assert ours['detumble_time_min'] is not None and ours['detumble_time_min'] < STEPS / 60, ours
