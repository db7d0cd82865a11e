"""AAP Workshop keys of the scenario schema and the graph ports they select (seed 000)."""

from __future__ import annotations

import pytest
from acds_common import topics
from acds_common.graph import build_graph
from acds_common.parameters import node_parameters
from acds_common.scenario import ScenarioError, load_scenario
from acds_common.units import FT_LB_S_NMS


def test_workshop_scenarios_convert_the_seed_units() -> None:
    sc = load_scenario('aap_workshop_iop')
    # the memo's k = 4e6 in the amp-turn-ft² reading: M in A·ft² (0.3048² A·m²) per ft-lb-sec per Wb/m²
    assert sc.get('controller', 'dump_gain') == pytest.approx(4e6 * 0.3048 ** 2 / FT_LB_S_NMS, rel=1e-15)
    assert sc.get('controller', 'dump_bias_momentum') == pytest.approx([575 * FT_LB_S_NMS, 160 * FT_LB_S_NMS,
                                                                        -160 * FT_LB_S_NMS])
    assert sc.get('wheels', 'cmg_capacity') == pytest.approx(12000 * FT_LB_S_NMS)
    assert sc.get('disturbance', 'bias_momentum_per_orbit')[1] == pytest.approx(160 * FT_LB_S_NMS)
    assert (sc.get('modes', 'system'), sc.get('wheels', 'kind')) == ('aap', 'cmg')
    assert sc.total_steps() == round(16 * sc.orbit_period_s() / 10.0)


def test_cmg_ports_replace_the_wheel_volts() -> None:
    graph = build_graph(node_parameters(load_scenario('aap_workshop_pop_test'), 10))
    (gimbal,) = graph.nodes['reaction_wheels'].stages
    assert gimbal.name == 'gimbal' and [(i.topic, i.source) for i in gimbal.inputs] == [
        (topics.CMG_TORQUE, 'acds_controller')]
    keys = [o.key for o in graph.nodes['acds_controller'].outputs]
    assert keys == ['moment', 'cmg_torque', 'sampled_momentum', 'diagnostics']
    assert graph.publisher_of(topics.WHEEL_VOLTS) == []
    (logic,) = graph.nodes['ascs_mode_manager'].stages  # the AAP variant: ground commands only, no inputs
    assert graph.nodes['ascs_mode_manager'].stepper.endswith(':AapModeManagerStep') and logic.inputs == ()
    heao = build_graph(node_parameters(load_scenario('heao_b_acquisition'), 10))
    assert heao.nodes['reaction_wheels'].stages[0].name == 'drive'
    assert [o.key for o in heao.nodes['acds_controller'].outputs] == ['moment', 'volts', 'diagnostics']


@pytest.mark.parametrize(('text', 'fragment'), [
    ('extends: aap_workshop_pop\nwheels:\n  kind: wheels\n', "wheels.kind: 'wheels' with modes.system 'aap'"),
    ('extends: heao_b_acquisition\nwheels:\n  kind: cmg\n', "wheels.kind: 'cmg' with modes.system 'heao'"),
    ('extends: aap_workshop_pop\nmodes:\n  initial_mode: mode_1a\n', "modes.initial_mode: 'mode_1a' with modes.system"),
    ('extends: heao_b_acquisition\nmodes:\n  initial_mode: cmg_dump\n', "modes.initial_mode: 'cmg_dump' with"),
])
def test_the_workshop_mode_logic_goes_with_the_cmgs(tmp_path, text, fragment) -> None:
    path = tmp_path / 'bad.yaml'
    path.write_text('name: bad\n' + text)
    with pytest.raises(ScenarioError, match=fragment.replace('(', r'\(')):
        load_scenario(str(path))
