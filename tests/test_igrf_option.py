"""The IGRF option of the scenario (``earth.model: igrf``, issue 12 §6) and the untouched dipole default.

The study's tilted dipole stays the default of every study scenario (the merge of the option was checked to
leave the direct engine's truth digests of heao_b_acquisition and sss_a_spin_up unchanged).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from acds_common import units
from acds_common.environment import IgrfField, TiltedDipoleField, field_from_section
from acds_common.scenario import SCENARIO_DIR, ScenarioError, load_scenario
from acds_runtime.direct import DirectRun


def test_every_shipped_scenario_keeps_the_study_dipole() -> None:
    for path in sorted(SCENARIO_DIR.glob('*.yaml')):
        earth = load_scenario(str(path)).values['earth']
        assert earth['model'] == 'dipole', path.name
        assert isinstance(field_from_section(earth), TiltedDipoleField), path.name


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
