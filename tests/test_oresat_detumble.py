"""OreSat detumble (seed 003) through the node steppers, direct engine: the scenario ``oresat_detumble``.

The designed torque rods and the B̂×ω law take the OreSat-like CubeSat from 5°/s per axis toward
rest; the rod design record loads into a scenario (relative to it); the rigid body bounds the rods'
dipole from the same record; the detumble summary's bookkeeping. The per-process graph runs the same
scenario in ``test_graph_oresat.py`` and ``test_engines.py``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from acds_common import topics
from acds_common.cdr import Codec, OdometryValue
from acds_common.inertia import inertia_tensor
from acds_common.scenario import SCENARIO_DIR, load_scenario
from acds_common.torque_rod_record import dipole_bound_am2, read_torque_rod_record
from acds_runtime.direct import DirectRun
from acds_runtime.preflight import preflight
from em_driver import oresat_summary as oresat
from em_driver.torque_rod_design import DesignRequest, design_torque_rod

SHIPPED_ROD = SCENARIO_DIR / 'oresat_torque_rod_awg35.json'


def test_shortened_detumble_removes_rate_and_kinetic_energy(tmp_path: Path) -> None:
    """Ten minutes at the 1 s period: |ω| well down from 8.66°/s, ½ωᵀJω falling every 100 s."""
    sc = load_scenario('oresat_detumble')
    run = DirectRun(sc, steps=600, record=tmp_path / 'bag').run()
    from acds_runtime.bag.reader import open_bag

    codec = Codec(topics.type_of(topics.TRUTH_ODOMETRY))
    omega = np.array([codec.decode(data)[1].angular for topic, _t, data in open_bag(tmp_path / 'bag').messages()
                      if topic == topics.resolve(topics.TRUTH_ODOMETRY)])
    inertia = inertia_tensor(*sc.get('spacecraft', 'inertia'))
    energy = 0.5 * np.einsum('ni,ij,nj->n', omega, inertia, omega)
    s = run.summary
    assert len(omega) == 601 and s['initial_rate_deg_s'] == pytest.approx(5.0 * math.sqrt(3.0), rel=1e-12)
    assert s['final_rate_deg_s'] < 0.7 * s['initial_rate_deg_s']
    assert np.all(np.diff(energy[::100]) < 0.0)
    full_current_a = 7.2 / (read_torque_rod_record(SHIPPED_ROD)['resistance_ohm'] + 0.36)
    assert 0.0 < s['peak_current_ma'] <= 1e3 * full_current_a * (1.0 + 1e-9)
    assert 0.0 < s['energy_j'] <= 3 * 0.5 * 600 * (1.0 + 1e-9)  # three rods at no more than 0.5 W each
    assert s['detumble_time_min'] is None and s['detumble_energy_j'] is None  # not at rest after 10 min


def test_the_shipped_rod_is_the_design_routine_output() -> None:
    """scenarios/oresat_torque_rod_awg35.json is `acds design-torque-rod --awg 35 --json` of today's routine."""
    fresh = design_torque_rod(DesignRequest(awg=35)).to_json_dict()
    shipped = json.loads(SHIPPED_ROD.read_text())
    assert shipped.keys() == fresh.keys()
    for key, value in fresh.items():
        assert shipped[key] == (pytest.approx(value, rel=1e-12) if isinstance(value, float) else value), key


def test_a_rod_design_file_loads_into_a_scenario_relative_to_it(tmp_path: Path) -> None:
    """A scenario extending oresat_detumble names its own rod (beside it): the em_driver flies that rod, the
    rigid body bounds the dipole with it, and the base's own rod is relative to the base."""
    design = design_torque_rod(DesignRequest(awg=34, core='permendur'))
    (tmp_path / 'rods').mkdir()
    (tmp_path / 'rods' / 'rod34.json').write_text(json.dumps(design.to_json_dict()))
    (tmp_path / 'mine.yaml').write_text('extends: oresat_detumble\nname: mine\n'
                                        'em_driver:\n  torque_rod_design: rods/rod34.json\n')
    sc = load_scenario(str(tmp_path / 'mine.yaml'))
    assert sc.get('em_driver', 'torque_rod_design') == str((tmp_path / 'rods' / 'rod34.json').resolve())
    preflight(sc)
    steppers = DirectRun(sc, steps=1).steppers
    rods = steppers['em_driver'].assembly
    np.testing.assert_allclose(rods.max_moment_am2(), design.moment_am2, rtol=1e-12)
    record = read_torque_rod_record(tmp_path / 'rods' / 'rod34.json')
    np.testing.assert_allclose(steppers['rigid_body'].limits.dipole_am2, dipole_bound_am2(record, 7.2))
    base = load_scenario('oresat_detumble')
    assert base.get('em_driver', 'torque_rod_design') == str(SHIPPED_ROD.resolve())
    (tmp_path / 'gone.yaml').write_text('extends: oresat_detumble\nname: gone\n'
                                        'em_driver:\n  torque_rod_design: nowhere.json\n')
    with pytest.raises(ValueError, match=r'em_driver\.torque_rod_design: .*nowhere\.json: cannot be read'):
        preflight(load_scenario(str(tmp_path / 'gone.yaml')))


def test_rigid_body_refuses_a_dipole_beyond_the_rods() -> None:
    """The rods' bound (both windings at bus/R) is what the time owner accepts: 0.31 A·m², not HEAO's kA·m²."""
    steppers = DirectRun(load_scenario('oresat_detumble'), steps=2).steppers
    body = steppers['rigid_body']
    limit = body.limits.dipole_am2
    assert np.all(limit >= 2 * steppers['em_driver'].assembly.max_moment_am2()) and np.all(limit < 0.4)
    from acds_common.stepper import StepError
    with pytest.raises(StepError, match='beyond what the hardware can produce'):
        body.integrate(0, 0.0, {'dipole': (float(limit[0]) * 1.01, 0.0, 0.0), 'wheel_h': None, 'wheel_hdot': None,
                                'mode': None})


def _odometry(rate_rad_s: float) -> OdometryValue:
    return OdometryValue((7e6, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), (0.0, 7.6e3, 0.0), (rate_rad_s, 0.0, 0.0))


def test_summary_detumble_time_is_when_the_rate_stays_below_the_threshold() -> None:
    """Steps of 2 s: above, below, above again, then below to the end → detumbled at the second crossing;
    energy counts the power of every step before it; the drive of the last step (never integrated) is
    not counted until a next step's truth arrives."""
    sc = load_scenario('oresat_detumble')
    acc = oresat.Accumulator(type('S', (), {'control_period_s': 2.0, 'get': lambda _s, *key: sc.get(*key)})())
    thr = sc.get('dynamics', 'detumbled_rate')
    rates = [3 * thr, 0.5 * thr, 1.5 * thr, 0.9 * thr, 0.2 * thr]
    for k, rate in enumerate(rates):
        acc.step(k, {oresat.ODOMETRY: _odometry(rate), oresat.POWER: (0.1, 0.2, 0.0),
                     oresat.DUTY: (1.0 if k == 0 else 0.5, 0.25, 0.0), oresat.CURRENT: (-0.01 * k, 0.0, 0.0)})
    out: dict = {}
    acc.contribute(out)
    assert out['detumble_time_min'] == pytest.approx(3 * 2.0 / 60)
    assert out['first_below_threshold_min'] == pytest.approx(1 * 2.0 / 60)
    assert out['detumble_energy_j'] == pytest.approx(3 * 0.3 * 2.0)
    assert out['energy_j'] == pytest.approx(4 * 0.3 * 2.0)
    assert out['peak_current_ma'] == pytest.approx(30.0)
    assert out['mean_duty'] == pytest.approx([0.625, 0.25, 0.0])
    assert out['mean_duty_to_detumble'] == pytest.approx([2.0 / 3.0, 0.25, 0.0])
    assert out['full_duty_fraction'] == pytest.approx(0.25)
    assert oresat.applies(sc) and not oresat.applies(load_scenario('heao_b_acquisition'))
    acc.step(5, {oresat.ODOMETRY: _odometry(2 * thr), oresat.POWER: (0.0,) * 3, oresat.DUTY: (0.0,) * 3,
                 oresat.CURRENT: (0.0,) * 3})
    acc.contribute(out)
    assert out['energy_j'] == pytest.approx(5 * 0.3 * 2.0) and out['peak_current_ma'] == pytest.approx(40.0)
    assert out['detumble_time_min'] is None and out['detumble_energy_j'] is None  # ends above: not detumbled
