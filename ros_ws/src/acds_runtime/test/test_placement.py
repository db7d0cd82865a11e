"""The launcher's placement of its node processes on two CPUs (acds_runtime.placement; docs/measurements.md)."""

from __future__ import annotations

import pytest
from acds_common.graph import build_graph
from acds_common.parameters import node_parameters
from acds_common.scenario import load_scenario
from acds_runtime import placement


def _shape(name: str) -> placement.StepShape:
    return placement.shape_of(build_graph(node_parameters(load_scenario(name), 10)))


def test_levels_follow_the_heao_step():
    """Truth → magnetometer and mode manager → controller → the two drivers (spec §2's firing order)."""
    assert placement.levels(_shape('heao_b_acquisition')) == {
        'rigid_body': 0, 'magnetometer_sim': 1, 'ascs_mode_manager': 1, 'acds_controller': 2, 'em_driver': 3,
        'reaction_wheels': 3}


def test_weight_counts_each_input_and_each_reader_of_a_per_step_output():
    weight = _shape('heao_b_acquisition').weight
    # the mode manager reads gyro and sun; its mode goes to four nodes, and to the run monitor
    assert weight['ascs_mode_manager'] == 2 + (1 + 4)
    # the wheels read the wheel volts; momentum and torque go to the rigid body, the controller and the monitor
    assert weight['reaction_wheels'] == 1 + 2 * (1 + 2)


def test_the_chain_keeps_one_cpu_and_the_heavier_node_of_a_level_takes_the_other():
    plan = placement.place(_shape('heao_b_acquisition'), (3, 5))
    assert plan == {'rigid_body': 3, 'ascs_mode_manager': 3, 'acds_controller': 3, 'reaction_wheels': 3,
                    'magnetometer_sim': 5, 'em_driver': 5}


def test_a_wide_level_is_shared_by_weight():
    shape = _shape('emff_three_vehicle_array')
    plan = placement.place(shape, (0, 1))
    assert set(plan) == set(shape.weight) and set(plan.values()) == {0, 1}
    load = [sum(w for n, w in shape.weight.items() if plan[n] == cpu) for cpu in (0, 1)]
    assert abs(load[0] - load[1]) <= max(shape.weight.values())


def test_a_ring_goes_on_one_cpu():
    """Nothing runs beside a chain that relays one message: every hand-off stays on the first CPU."""
    assert set(placement.place(placement.chain_shape(['a', 'b', 'c', 'd']), (0, 1)).values()) == {0}


@pytest.mark.parametrize(('cpus', 'env', 'expected'), [
    ({4, 2}, '', (2, 4)), ({0, 1, 2, 3}, '', None), ({0}, '', None), ({0, 1}, 'off', None)])
def test_placement_only_on_exactly_two_cpus(monkeypatch, cpus, env, expected):
    monkeypatch.setattr(placement.os, 'sched_getaffinity', lambda _pid: cpus)
    monkeypatch.setenv(placement.PLACEMENT_ENV, env)
    assert placement.placement_cpus() == expected


def test_an_external_node_is_never_placed(monkeypatch):
    monkeypatch.setattr(placement, 'placement_cpus', lambda: (0, 1))
    graph = build_graph(node_parameters(load_scenario('heao_b_acquisition'), 10))
    plan = placement.node_placement(graph, ['acds_controller'])
    assert 'acds_controller' not in plan and set(plan) == set(graph.nodes) - {'acds_controller'}
