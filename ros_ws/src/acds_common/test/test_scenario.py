"""Scenario loader: schema, units → SI, extends, and errors that name the key."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from acds_common import units as u
from acds_common.scenario import SCHEMA, ScenarioError, load_scenario

BASE = """
name: t
description: test
duration_s: 10
spacecraft:
  inertia_slug_ft2: [1520, 7970, 7920, 47, 359, 4]
"""


def write(tmp_path: Path, text: str, name: str = 't.yaml') -> str:
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def test_units_convert_to_si_and_defaults_fill_in(tmp_path):
    sc = load_scenario(write(tmp_path, BASE + 'orbit:\n  altitude_nmi: 180\n  inclination_deg: 22.75\n'))
    assert sc.get('orbit', 'altitude') == pytest.approx(180 * 1852.0)
    assert sc.get('orbit', 'inclination') == pytest.approx(math.radians(22.75))
    assert sc.get('spacecraft', 'inertia')[0] == pytest.approx(1520 * u.SLUG_FT2_KG_M2)
    assert sc.get('earth', 'dipole_tilt') == pytest.approx(math.radians(11))
    assert sc.total_steps() == 20
    params = sc.node_parameters('rigid_body')
    assert params['orbit_altitude_m'] == pytest.approx(333360.0)
    assert set(params) == {f.param_name(s, n) for s in ('spacecraft', 'orbit', 'earth', 'sun', 'dynamics', 'em_driver',
                                                      'wheels', 'disturbance')
                           for n, f in SCHEMA[s].items()}


def test_duration_in_orbits_uses_the_orbit_period(tmp_path):
    sc = load_scenario(write(tmp_path, BASE.replace('duration_s: 10', 'duration_orbits: 2')))
    a = u.EARTH_RADIUS_M + 225 * u.NMI_M
    assert sc.duration_s() == pytest.approx(2 * 2 * math.pi * math.sqrt(a**3 / u.EARTH_MU_M3_S2))


def test_elliptical_period_is_sss_a(tmp_path):
    sc = load_scenario(write(tmp_path, BASE + 'orbit:\n  kind: elliptical\n'))
    assert sc.orbit_period_s() / 3600 == pytest.approx(7.75, abs=0.05)


def test_extends_overrides_and_replaces_a_key_given_in_another_unit(tmp_path):
    write(tmp_path, BASE + 'orbit:\n  altitude_nmi: 225\n  inclination_deg: 22.5\n', 'base.yaml')
    child = write(tmp_path, f'extends: {tmp_path / "base.yaml"}\nname: c\norbit:\n  altitude_km: 400\n', 'c.yaml')
    sc = load_scenario(child)
    assert sc.name == 'c'
    assert sc.get('orbit', 'altitude') == pytest.approx(400e3)
    assert sc.get('orbit', 'inclination') == pytest.approx(math.radians(22.5))


@pytest.mark.parametrize(('extra', 'message'), [
    ('colour: red\n', 'unknown key "colour"'),
    ('orbit:\n  altitud_nmi: 3\n', 'unknown key "orbit.altitud_nmi"'),
    ('widgets:\n  a: 1\n', 'unknown section "widgets"'),
    ('orbit:\n  altitude_nmi: 225\n  altitude_km: 400\n', '"orbit.altitude" is given twice'),
    ('orbit:\n  kind: parabolic\n', "'parabolic' is not one of circular, elliptical"),
    ('orbit:\n  altitude_nmi: 5\n', 'orbit.altitude_nmi: 5 is out of range'),
    ('dynamics:\n  substeps: 2.5\n', 'dynamics.substeps: expected an integer'),
    ('spacecraft:\n  inertia_slug_ft2: [1, 2]\n', 'expected 6 values, got 2'),
    ('sun:\n  eclipse: maybe\n', 'expected true or false'),
])
def test_errors_name_the_key(tmp_path, extra, message):
    text = BASE + extra if not extra.startswith('spacecraft') else BASE.split('spacecraft')[0] + extra
    with pytest.raises(ScenarioError, match='.*'.join(map(_esc, message.split('.*')))):
        load_scenario(write(tmp_path, text))


def _esc(s: str) -> str:
    import re
    return re.escape(s)


def test_missing_file_lists_shipped_scenarios():
    with pytest.raises(ScenarioError, match='not found.*free_tumble_heao_b'):
        load_scenario('no_such_scenario')


def test_every_shipped_scenario_loads():
    from acds_common.scenario import SCENARIO_DIR
    names = [p.stem for p in SCENARIO_DIR.glob('*.yaml')]
    assert 'free_tumble_heao_b' in names
    for name in names:
        assert load_scenario(name).name == name


@pytest.mark.parametrize(('child', 'message'), [
    ('orbit:\n  altitude_nmi: 225\n  altitude_km: 400\n', '"orbit.altitude" is given twice'),
    ('orbit:\n  altitude_km: 400\n  altitude_nmi: 225\n', '"orbit.altitude" is given twice'),
    ('duration_min: 2\nduration_orbits: 1\n', '"duration" is given twice'),
])
def test_an_extending_file_giving_one_key_in_two_units_is_refused(tmp_path, child, message):
    """``extends`` lets a key in another unit replace the base's, but the extending file's own two units of one key
    are the same key given twice (as in a file without ``extends``), not the last one silently winning."""
    write(tmp_path, BASE + 'orbit:\n  altitude_nmi: 225\n', 'base.yaml')
    with pytest.raises(ScenarioError, match=message):
        load_scenario(write(tmp_path, f'extends: {tmp_path / "base.yaml"}\nname: c\n{child}', 'c.yaml'))


def test_extends_replaces_a_top_level_duration_given_in_another_unit(tmp_path):
    write(tmp_path, BASE.replace('duration_s: 10', 'duration_orbits: 3'), 'base.yaml')
    sc = load_scenario(write(tmp_path, f'extends: {tmp_path / "base.yaml"}\nname: c\nduration_min: 2\n', 'c.yaml'))
    assert sc.duration_s() == pytest.approx(120.0)


def test_every_number_in_the_schema_has_a_physical_range():
    """A number without bounds lets 1e300 through to the models (issue 9 §6: NaN in the summary)."""
    unbounded = [f'{s}.{n}' for s, fields in SCHEMA.items() for n, f in fields.items()
                 if f.kind in ('float', 'int', 'floats') and not (f.lo is not None and f.hi is not None
                                                                 and math.isfinite(f.lo) and math.isfinite(f.hi))]
    assert unbounded == []


def test_a_file_name_key_is_relative_to_the_file_that_gives_it(tmp_path):
    base_dir, child_dir = tmp_path / 'base', tmp_path / 'elsewhere'
    base_dir.mkdir()
    child_dir.mkdir()
    write(base_dir, BASE + 'em_driver:\n  driver_kind: torque_rod\n  torque_rod_design: rods/rod.json\n', 'base.yaml')
    inherited = load_scenario(write(child_dir, f'extends: {base_dir / "base.yaml"}\nname: c\n', 'c.yaml'))
    assert inherited.get('em_driver', 'torque_rod_design') == str((base_dir / 'rods' / 'rod.json').resolve())
    own = load_scenario(write(child_dir, f'extends: {base_dir / "base.yaml"}\nname: d\n'
                                         'em_driver:\n  torque_rod_design: rod.json\n', 'd.yaml'))
    assert own.get('em_driver', 'torque_rod_design') == str((child_dir / 'rod.json').resolve())
    absolute = load_scenario(write(child_dir, BASE + f'em_driver:\n  torque_rod_design: {tmp_path / "r.json"}\n'))
    assert absolute.get('em_driver', 'torque_rod_design') == str(tmp_path / 'r.json')
    assert load_scenario(write(tmp_path, BASE)).get('em_driver', 'torque_rod_design') == ''
