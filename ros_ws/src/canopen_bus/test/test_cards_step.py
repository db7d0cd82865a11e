"""The canopen_cards stepper's edge: sample and hold, the step of each frame, the heartbeat watch (spec §13)."""

import copy
import dataclasses
import math
import struct

import can
import pytest
from acds_common.cdr import OdometryValue
from acds_common.scenario import load_scenario
from acds_common.stepper import StepError
from acds_runtime.direct import DirectRun
from canopen_bus.canlog import CanLog, read_replay

INPUTS = {'odometry': OdometryValue((6.78e6, 0.0, 0.0), (0.0, 7.67e3, 0.0), (0.0, 0.0, 0.0, 1.0), (0.0873, -0.05, 0.01)),
          'b_true': ((2.0e-5, -1.0e-5, 3.0e-5), None), 'dipole': None, 'duty': None}


def _cards(**bus):
    sc = load_scenario('oresat_c3_detumble')
    values = copy.copy(sc.values)
    values['can_bus'] = {**sc.values['can_bus'], **bus}
    return DirectRun(dataclasses.replace(sc, values=values), steps=1).steppers['canopen_cards']


def _download(sub: int, microamps: int) -> can.Message:
    return can.Message(timestamp=1.0, arbitration_id=0x638, is_extended_id=False,
                       data=bytes([0x23, 0x07, 0x40, sub]) + struct.pack('<i', microamps))


def test_a_setpoint_is_held_until_the_step_that_samples_it_and_logged_with_that_step(tmp_path):
    st = _cards()
    st.canlog = CanLog(tmp_path / 'can.asc', 10.0)
    outs = [st.exchange(k, k * 0.1, INPUTS) for k in range(3)]
    st._on_message(_download(4, 5000))  # arrives between step 2 and step 3
    outs += [st.exchange(k, k * 0.1, INPUTS) for k in range(3, 5)]
    st.close()
    assert [o['setpoint'][0] for o in outs] == [0.0, 0.0, 0.0, 0.005, 0.005]
    assert outs[3]['command'][0] == pytest.approx(2.2349 * 0.005)
    assert read_replay(tmp_path / 'can.asc') == {3: [(1.0, 0x638, bytes([0x23, 7, 0x40, 4]) + struct.pack('<i', 5000))]}
    # what the cards sent at step 0: the gyro in mrad/s counts, each magnetometer in mG (noise 1 count rms)
    gyro = outs[0]['body_rate']
    assert gyro == pytest.approx((0.087, -0.05, 0.01))
    assert all(abs(a - b) < 3e-7 for a, b in zip(outs[0]['magnetic_field'], INPUTS['b_true'][0], strict=True))
    assert math.isnan(outs[0]['timing'][0])  # off the bus: no schedule


def test_a_setpoint_beyond_the_driver_is_clamped_and_named_once():
    st = _cards()
    lines = []
    st._log = lambda level, text: lines.append(text)
    st._on_message(_download(6, -90_000))
    out = [st.exchange(k, k * 0.1, INPUTS) for k in range(2)]
    assert out[0]['setpoint'][2] == pytest.approx(-0.04125) and st.clamp_count == 2
    assert sum('clamped at the limit' in line for line in lines) == 1


def test_the_heartbeat_watch_names_the_step_and_fails_when_the_scenario_says_so():
    for policy in ('fly_on', 'fail'):
        st = _cards(on_heartbeat_loss=policy, heartbeat_timeout=0.25)  # R = 1: 3 steps of 0.1 s
        lines = []
        st._log = lambda level, text, lines=lines: lines.append(text)
        st.replay = {0: [(0.0, 0x701, b'\x05')], 1: [(0.1, 0x701, b'\x05')]}
        if policy == 'fail':
            with pytest.raises(StepError, match='heartbeat lost at step 5 .*last at step 1.*on_heartbeat_loss: fail'):
                for k in range(8):
                    st.exchange(k, k * 0.1, INPUTS)
        else:
            for k in range(8):
                st.exchange(k, k * 0.1, INPUTS)
            assert any('heartbeat lost at step 5' in line and 'flying on' in line for line in lines), lines


def test_the_graphs_magnetometer_fault_reaches_the_bus(tmp_path):
    """A card object mapped to magnetometer_sim's field carries that node's faults (here a dead unit at t = 0.5 s)."""
    (tmp_path / 'm.yaml').write_text(
        'devices:\n  adcs:\n    dictionary: oresat1/adcs\n    objects:\n'
        '      - {index: 0x4003, subs: [1, 2, 3], quantity: sensed_magnetic_field, si_per_count: 1.0e-7, unit: T}\n'
        '      - {index: 0x4004, subs: [1, 2, 3], quantity: magnetic_field, si_per_count: 1.0e-7, unit: T}\n')
    sc = load_scenario('oresat_c3_detumble')
    values = copy.deepcopy(sc.values)
    values['']['nodes'] = ['rigid_body', 'magnetometer_sim', 'canopen_cards', 'em_driver']
    values['can_bus']['mapping'] = str(tmp_path / 'm.yaml')
    values['magnetometer'].update(fault='dead_unit', fault_unit='A', fault_time=0.5)
    run = DirectRun(dataclasses.replace(sc, values=values), steps=3)
    run.run()
    adcs = run.steppers['canopen_cards'].devices['adcs']
    early = [adcs.get_raw(0x4003, s) for s in (1, 2, 3)]
    run = DirectRun(dataclasses.replace(sc, values=values), steps=10)
    run.run()
    adcs = run.steppers['canopen_cards'].devices['adcs']
    late = [adcs.get_raw(0x4003, s) for s in (1, 2, 3)]
    truth = [adcs.get_raw(0x4004, s) for s in (1, 2, 3)]
    # a dead unit's 0 V reads as the fluxgate's −1 G full scale on every axis: −1,000 counts of 1 mG
    assert any(early) and late == [-1000, -1000, -1000] and all(truth)
