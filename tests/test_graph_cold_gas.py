"""The cold-gas acquisition through the full seven-process graph (seed 002 §3.1, §5; issue 22).

A shortened cold-gas acquisition (``heao_b_acquisition_cold_gas_short``) goes gas rate damping → gas sun
acquisition → hand-over to the wheels (Mode 1B) → capture, through the per-process graph and on the direct
engine, with the same summary (truth digest, gas totals, every time) and the same cold-gas bytes; the gas
used is the impulse over Isp·g0 and no more than two valves were ever open.
"""

from __future__ import annotations

import pytest
from acds_common import topics
from acds_common.scenario import load_scenario
from acds_common.units import LB_KG, LBF_N, STANDARD_GRAVITY_M_S2
from acds_runtime.direct import DirectRun

NODES = {'rigid_body', 'reaction_wheels', 'magnetometer_sim', 'em_driver', 'acds_controller', 'ascs_mode_manager',
         'cold_gas'}


@pytest.mark.slow  # ~30 s on a loaded 2-core machine: 258 steps of seven processes, then the direct engine
def test_short_cold_gas_acquisition_reaches_capture_on_both_engines_with_identical_data(launch_graph, tmp_path):
    sc = load_scenario('heao_b_acquisition_cold_gas_short')
    direct = DirectRun(sc, record=tmp_path / 'direct_bag').run()
    with launch_graph(sc) as graph:
        result = graph.wait()
        kept = graph.monitor.snapshot()
    assert set(result.exit_codes) == NODES and set(result.exit_codes.values()) == {0}
    s = result.summary
    assert [(t['from'], t['to']) for t in s['mode_transitions']] == [
        ('gas_rate_damping', 'gas_sun_acquisition'), ('gas_sun_acquisition', 'mode_1b'), ('mode_1b', 'capture')]
    assert 0.0 < s['gas_rate_damping_min'] < s['gas_handover_min'] < s['acquisition_time_min']
    assert result.steps < sc.total_steps(), 'the run ends at capture'
    assert s['gas_max_open_valves'] == 2 and s['gas_vented_lb'] == 0.0 and not s['gas_pressure_switch_acted']
    isp_g0 = sc.get('cold_gas', 'isp') * STANDARD_GRAVITY_M_S2
    assert abs(s['gas_used_lb'] - s['gas_impulse_lbf_s'] * LBF_N / isp_g0 / LB_KG) < 1e-12
    assert {k: v for k, v in direct.summary.items() if k != 'wall_seconds'} == \
        {k: v for k, v in s.items() if k != 'wall_seconds'}
    from acds_cli.bag.reader import open_bag

    recorded: dict[str, list[bytes]] = {}
    for topic, _t, data in open_bag(tmp_path / 'direct_bag').messages():
        recorded.setdefault(topic, []).append(data)
    for topic in (topics.GAS_ON_TIME, topics.COLD_GAS_WRENCH, topics.COLD_GAS_STATE, topics.TRUTH_ODOMETRY):
        name = topics.resolve(topic)
        assert recorded[name] == kept[name], f'{name}: the direct bag differs from the graph'
