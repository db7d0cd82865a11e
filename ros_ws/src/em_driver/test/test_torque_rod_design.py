"""Tests of the torque-rod design routine (spec §9; seed 003 "Design")."""

from __future__ import annotations

import json

import numpy as np
import pytest
from em_driver.bridge_switch import EmDriverError
from em_driver.torque_rod import TorqueRod, rod_properties
from em_driver.torque_rod_design import DesignRequest, InfeasibleDesignError, design_torque_rod, load_rod
from hypothesis import given, settings
from hypothesis import strategies as st

JSON_KEYS = {'mass_g', 'power_w', 'moment_am2', 'core_length_mm', 'core_radius_mm', 'turns', 'resistance_ohm',
             'inductance_h', 'tau_s', 'core_saturates'}


def _check_constraints(req: DesignRequest, rod: TorqueRod) -> None:
    """Every constraint, re-evaluated from the rod itself (not from the search's own bookkeeping)."""
    p = rod.props
    r_loop = p.resistance_ohm + req.bridge_resistance_ohm
    i_full = req.voltage_v / r_loop
    assert req.voltage_v ** 2 / r_loop <= req.power_max_w * (1 + 1e-12)
    assert p.mass_kg <= req.mass_max_kg
    assert float(rod.moment_am2(i_full)) >= req.moment_min_am2
    box = sorted([rod.core_length_m, 2 * p.outer_radius_m, 2 * p.outer_radius_m])
    assert all(b <= e for b, e in zip(box, sorted(req.envelope_m), strict=True))
    assert req.allow_saturation or rod.core_flux_density_t(i_full) <= rod.material.saturation_t
    assert rod.core_radius_m >= req.min_core_radius_m


@settings(max_examples=30)
@given(moment=st.floats(0.02, 0.3), mass_g=st.floats(15.0, 150.0), power=st.floats(0.2, 1.0),
       core=st.sampled_from(['permalloy', 'permendur', 'ck30']), awg=st.integers(32, 38),
       windings=st.sampled_from([1, 2]), allow_saturation=st.booleans(),
       envelope=st.tuples(st.floats(0.02, 0.07), st.floats(0.01, 0.04), st.floats(0.01, 0.04)))
def test_every_returned_design_meets_every_constraint(moment: float, mass_g: float, power: float, core: str, awg: int,
                                                     windings: int, allow_saturation: bool,
                                                     envelope: tuple[float, float, float]) -> None:
    req = DesignRequest(mass_max_kg=mass_g * 1e-3, power_max_w=power, moment_min_am2=moment, envelope_m=envelope,
                        core=core, awg=awg, windings=windings, allow_saturation=allow_saturation)
    try:
        design = design_torque_rod(req)
    except InfeasibleDesignError as exc:
        assert exc.binding and str(exc).startswith('no torque rod meets the request; binding: ')
        return
    _check_constraints(req, design.rod)
    assert design.core_saturates == (design.flux_density_t > design.rod.material.saturation_t)


def test_design_converges_to_the_minimum_mass() -> None:
    """No point of a dense independent grid over the same bounds is feasible and lighter."""
    req = DesignRequest(awg=35)
    design = design_torque_rod(req)
    length, radius = np.meshgrid(np.linspace(2e-3, 0.035, 301), np.linspace(0.5e-3, 0.0175, 301), indexing='ij')
    wire = req.wire
    p = rod_properties(length, radius, design.rod.material, wire, req.coil_resistance_ohm / wire.ohm_per_m, 2)
    i_full = req.full_current_a
    moment = p.air_moment_per_a * i_full + np.minimum(p.core_moment_per_a * i_full, p.core_max_moment_am2)
    feasible = ((moment >= req.moment_min_am2) & (p.mass_kg <= req.mass_max_kg) & (2 * p.outer_radius_m <= 0.025)
                & (p.flux_per_a_t * i_full <= design.rod.material.saturation_t))
    assert feasible.any()
    assert design.mass_kg <= float(p.mass_kg[feasible].min()) + 1e-9
    assert design.moment_am2 == pytest.approx(req.moment_min_am2, rel=1e-4)  # the moment constraint is active
    assert design.search_rounds < 20


def test_seed_constraints_with_awg_35_and_json_round_trip(tmp_path) -> None:  # noqa: ANN001
    design = design_torque_rod(DesignRequest(awg=35))
    record = design.to_json_dict()
    assert JSON_KEYS <= set(record)
    assert record['power_w'] == pytest.approx(0.5) and record['windings'] == 2 and record['core_saturates'] is False
    assert record['tau_s'] == pytest.approx(record['inductance_h'] / (record['resistance_ohm']
                                                                     + record['bridge_resistance_ohm']))
    path = tmp_path / 'rod.json'
    path.write_text(json.dumps(record))
    rod = load_rod(path)
    assert rod.props.turns == pytest.approx(record['turns'], rel=1e-12)
    assert float(rod.moment_am2(record['current_a'])) == pytest.approx(record['moment_am2'], rel=1e-12)
    with pytest.raises(EmDriverError, match="lacks key 'awg'"):
        load_rod({k: v for k, v in record.items() if k != 'awg'})


def test_five_am2_in_ten_grams_is_refused_naming_mass_and_moment() -> None:
    with pytest.raises(InfeasibleDesignError) as info:
        design_torque_rod(DesignRequest(moment_min_am2=5.0, mass_max_kg=0.010))
    assert set(info.value.binding) == {'mass', 'moment'}
    assert 'the wire alone is 18.1 g' in str(info.value) and '< 5 A·m² required' in str(info.value)


def test_power_below_the_bridge_resistance_is_refused() -> None:
    with pytest.raises(InfeasibleDesignError, match='binding: power') as info:
        design_torque_rod(DesignRequest(power_max_w=500.0))
    assert info.value.binding == ('power',)
    with pytest.raises(EmDriverError, match='unknown core'):
        DesignRequest(core='unobtainium')
