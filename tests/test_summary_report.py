"""The printed run summary (issue 12 §5): aligned rows in the study's units, no raw dicts, no ``None``;
drift rows only for torque-free runs; the SSS pass report's one-revolution torque and ripple at the
pass's peak spin-plane field (seed 001's quantity)."""

from __future__ import annotations

import contextlib
import io
import math

import pytest
from acds_common.scenario import load_scenario
from acds_common.units import GAUSS_T, nm_to_dyne_cm, rpm_to_rad_s
from acds_runtime.direct import DirectRun
from acds_runtime.report import format_summary, summary_rows
from ascs_mode_manager.spin_mechanizations import MECHANIZATIONS, closed_form_average_torque_nm, closed_form_ripple_pct
from ascs_mode_manager.sss_summary import one_revolution, print_tables

SUMMARY = {
    'scenario': 'x', 'steps': 10, 'sim_minutes': 5.0, 'wall_seconds': 1.0,
    'torque_free': False, 'momentum_drift_rel': 0.01, 'energy_drift_rel': 0.02,
    'final_rates_deg_s': [0.1, -0.25, 1e-5], 'final_momentum_ftlbs': 12.3456,
    'b_min_gauss': None, 'peak_wheel_momentum_ftlbs': {'x': 1.0, 'y': 2.0, 'z': 3.0, 'rss': 3.74},
    'acquisition_time_min': 23.456, 'mode_transitions': [{'t_min': 1.0, 'from': 'a', 'to': 'b', 'cause': ''}],
    'final_mode': 'mode_1b', 'truth_messages': 70,
}


def test_rows_are_aligned_in_study_units_without_raw_values():
    text = format_summary(SUMMARY)
    lines = text.splitlines()[1:]
    assert 'None' not in text and '{' not in text and "'" not in text
    assert 'drift' not in text, 'drift of a run with torques is physics, not integration error: not printed'
    rows = {label: (value, unit) for label, value, unit in summary_rows(SUMMARY)}
    assert rows['peak wheel momentum (x / y / z / rss)'] == ('1.000 / 2.000 / 3.000 / 3.740', 'ft-lb-sec')
    assert rows['final body rates (x / y / z)'] == ('0.1 / -0.25 / 1e-05', 'deg/s')
    assert rows['|B| min seen'] == ('—', 'G') and rows['acquisition time'] == ('23.46', 'min')
    assert not any(label.startswith('mode transitions') for label in rows)  # a table, printed by its module
    value_ends = {line.index(value) + len(value) for line in lines for value, _ in [rows[_label(line, rows)]]}
    assert len(value_ends) == 1, text  # every value right-aligned in one column
    free = format_summary({**SUMMARY, 'torque_free': True})
    assert 'momentum drift  ' in free and '1.000e-02  (relative)' in free


def _label(line: str, rows: dict) -> str:
    return next(label for label in sorted(rows, key=len, reverse=True) if line.strip().startswith(label))


def test_one_revolution_matches_the_closed_forms_without_a_dead_zone():
    mech = MECHANIZATIONS['one_channel_constant']
    field = 0.3 * GAUSS_T
    avg, ripple = one_revolution(mech, field, rpm_to_rad_s(4.0), 0.0, 1)
    assert avg == pytest.approx(closed_form_average_torque_nm(mech, field), rel=5e-3)
    assert ripple == pytest.approx(closed_form_ripple_pct(mech), rel=1e-2)
    gated, gated_ripple = one_revolution(mech, field, rpm_to_rad_s(4.0), 0.075 * GAUSS_T, 1)
    assert 0.0 < gated < avg and gated_ripple > ripple  # the polarity-sensing level cuts the torque pulses
    below, below_ripple = one_revolution(mech, 0.05 * GAUSS_T, rpm_to_rad_s(4.0), 0.075 * GAUSS_T, 1)
    assert below == 0.0 and math.isnan(below_ripple)
    assert one_revolution(mech, field, rpm_to_rad_s(4.0), 0.0, -1)[0] == pytest.approx(-avg)


def test_sss_pass_report_adds_the_one_revolution_quantities_at_its_peak_field():
    summary = DirectRun(load_scenario('sss_a_pass_test'), steps=600).run().summary
    (p,) = summary['perigee_passes']
    assert p['mode'] == 'spin' and not p['complete']
    assert 0.075 < p['peak_spin_plane_field_gauss'] <= summary['b_max_gauss']
    avg_nm, ripple = one_revolution(MECHANIZATIONS['one_channel_constant'], p['peak_spin_plane_field_gauss'] * GAUSS_T,
                                    rpm_to_rad_s(4.0), 0.075 * GAUSS_T, 1)
    assert p['one_rev_avg_torque_dyne_cm'] == pytest.approx(nm_to_dyne_cm(avg_nm), rel=1e-3)  # spin ≈ 4 rpm
    assert p['one_rev_ripple_pct'] == pytest.approx(ripple, rel=1e-2)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        print_tables(summary)
    text = out.getvalue()
    assert "including the field's rise and fall" in text and '1-rev avg torque' in text
    assert f'{p["one_rev_avg_torque_dyne_cm"]:.1f}' in text and 'None' not in text
