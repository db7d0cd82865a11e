"""The IGRF option of the scenario (``earth.model: igrf``, issue 12 §6) and the untouched dipole default.

The study's tilted dipole stays the default of every study scenario: the direct engine's truth digests of
two study scenarios are the ones computed on ``main`` before the option existed (commit 639c440). A change
of the physics, or of its floating-point order, changes them: update them then, saying why.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from acds_common import units
from acds_common.environment import IgrfField, TiltedDipoleField
from acds_common.scenario import SCENARIO_DIR, ScenarioError, load_scenario
from acds_runtime.direct import DirectRun
from dynamics.configuration import build_field

#: Direct-engine truth digests (400 steps) on main at 639c440, before the IGRF option.
DIGESTS_BEFORE = {
    'heao_b_acquisition': '158c582ed271051942aec0a38eb0e5fbefc7fe9bedb8cb8186964c2bd4db9d4c',
    'sss_a_spin_up': '708acad97911ee0b113fdf3f421980efe64e933f0f96fab573062dff0b6329f6',
}


def test_every_shipped_scenario_keeps_the_study_dipole() -> None:
    for path in sorted(SCENARIO_DIR.glob('*.yaml')):
        earth = load_scenario(str(path)).values['earth']
        assert earth['model'] == 'dipole', path.name
        assert isinstance(build_field(earth), TiltedDipoleField), path.name


@pytest.mark.parametrize('name', sorted(DIGESTS_BEFORE))
def test_dipole_default_physics_unchanged(name: str) -> None:
    assert DirectRun(load_scenario(name), steps=400).run().summary['truth_digest'] == DIGESTS_BEFORE[name]


def _igrf_scenario(tmp_path: Path, epoch: float = 2025.5, extra: str = '') -> Path:
    path = tmp_path / 'igrf.yaml'
    path.write_text(f'extends: heao_b_acquisition\nname: igrf_main\n{extra}earth:\n  model: igrf\n'
                    f'  epoch_year: {epoch}\n')
    return path


def test_igrf_scenario_runs_with_the_igrf_field(tmp_path: Path) -> None:
    scenario = load_scenario(str(_igrf_scenario(tmp_path)))
    run = DirectRun(scenario, steps=200)
    model = run.steppers['rigid_body'].model
    assert isinstance(model.field, IgrfField)
    summary = run.run().summary
    dipole = DirectRun(load_scenario('heao_b_acquisition'), steps=200).run().summary
    assert summary['truth_digest'] != dipole['truth_digest']
    # The same orbit in a real field: 0.2-0.6 G at 417 km, a few per cent off the study's dipole.
    assert 0.1 < summary['b_min_gauss'] < summary['b_max_gauss'] < 0.6
    assert abs(summary['b_max_gauss'] / dipole['b_max_gauss'] - 1.0) < 0.3
    r = np.array(model.orbit.position_velocity_eci(model.t_s)[0])
    assert 0.1 * units.GAUSS_T < np.linalg.norm(model.field.b_eci(r, model.t_s)) < 0.6 * units.GAUSS_T


def test_igrf_dates_are_checked_at_load(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match=r'earth.epoch_year: 1899 is out of range \[1900, 2030\]'):
        load_scenario(str(_igrf_scenario(tmp_path, 1899)))
    with pytest.raises(ScenarioError, match='after the IGRF-14 coefficients end'):
        load_scenario(str(_igrf_scenario(tmp_path, 2029.999, 'duration_min: 1440\n')))
