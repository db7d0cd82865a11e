"""Graph test of the SSS ASCS (spec §8; seed 001): one SSS-A perigee pass under the full node graph.

Scenario ``sss_a_pass_test``: rigid_body, magnetometer_sim, em_driver (constant-level coils) and
ascs_mode_manager (SSS part), spin mode enabled for spin-up by scheduled ground commands at t = 0, the
run spanning one perigee pass at a 0.5 s control period (justified in the scenario file). During the
pass a live ground command asking for attitude mode must be refused with a reason (spin and attitude
mode never both on one pass).
"""

from __future__ import annotations

from acds_common import topics
from acds_runtime.testing import ground_command, wait_for_messages


def _turn_events(monitor, kind: str) -> list[str]:
    return [m.data for m in monitor.messages(topics.EVENTS) if m.data.split(' ')[1:2] == [kind]]


def test_one_perigee_pass_spins_up_with_one_turn_on_and_one_turn_off(launch_graph):
    with launch_graph('sss_a_pass_test') as graph:
        monitor = graph.monitor
        if not monitor.wait_for(lambda: bool(_turn_events(monitor, 'turn_on')), timeout_s=120.0):
            wait_for_messages(graph, topics.EVENTS, 1, timeout_s=1.0)  # fails naming what arrived
            raise AssertionError(f'no turn_on event; events: {[m.data for m in monitor.messages(topics.EVENTS)]}')
        # A live attitude-mode request during the spin-mode pass: refused, with the reason.
        refused = ground_command(graph, 'sss mode attitude')
        result = graph.wait()

    assert 'refused' in refused and 'spin-mode pass' in refused, refused
    on, off = _turn_events(result.monitor, 'turn_on'), _turn_events(result.monitor, 'turn_off')
    assert len(on) == 1 and len(off) == 1, (on, off)
    t_on, t_off = (float(e.split(' ')[0].removeprefix('t=')) for e in (on[0], off[0]))
    assert 'sss_spin_idle->sss_spin_torquing' in on[0]
    assert 'hold released' in off[0]
    assert 30 * 60 < t_off - t_on < 60 * 60, 'a perigee pass of SSS-A lasts tens of minutes'

    passes = result.summary['perigee_passes']
    assert len(passes) == 1
    p = passes[0]
    assert p['mode'] == 'spin' and p['complete']
    assert p['spin_rate_change_rpm'] > 0.0, 'spin-up must raise the spin rate'
    assert p['avg_torque_dyne_cm'] > 0.0
    assert p['energy_j'] > 0.0
    # The spin coil was commutated by the magnetometer: the mode stream shows both coil polarities.
    coils = {kv.value for m in result.monitor.messages(topics.MODE) for kv in m.status[0].values
             if kv.key == 'spin_coil'}
    assert {'1', '-1', '0'} <= coils
