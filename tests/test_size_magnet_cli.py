"""``acds size-magnet`` (seed 000 §7–§12): typed moments, a dump report, §12 estimates, clear errors."""

from __future__ import annotations

import json
import math

import pytest
from acds_cli.__main__ import main

#: Fig. 4's POP gimbaled column as moments: M_m = 109 amp-turns × the 20 ft coil area; M_n = M_d chosen so
#: that the gimbaled turns × area is Fig. 4's 0.141 in² (see em_driver/test/test_magnet_sizing.py).
POP_M_M = 109.0 * math.pi * (10 * 0.3048) ** 2
POP_RMS = 0.7593 * POP_M_M


def test_typed_moments_print_and_write_the_fig4_pop_design(tmp_path, capsys) -> None:
    out = tmp_path / 'pop.json'
    code = main(['size-magnet', '--mode', 'day-night', '--core', 'air', '--m-n-am2', str(POP_RMS),
                 '--m-d-am2', str(POP_RMS), '--m-o-am2', str(POP_RMS), '--m-m-am2', str(POP_M_M), '--json', str(out)])
    assert code == 0
    text = capsys.readouterr().out
    assert 'Total weight, lbs' in text and 'three orthogonal' in text and 'Field at coil centre' in text
    rep = json.loads(out.read_text())
    assert rep['moments_source'] == 'typed'
    three = rep['designs']['three_orthogonal']
    assert round(three['Total weight, lbs']) == 134
    assert round(rep['designs']['gimbaled']['Maximum power, W (total)']) == 47
    assert three['Field at coil centre, % of B_0'] == pytest.approx(86, abs=1)


def test_from_report_and_day_constant(tmp_path, capsys) -> None:
    report = tmp_path / 'dump.json'
    report.write_text(json.dumps({'M_n_am2': POP_RMS, 'M_d_am2': POP_RMS, 'M_o_am2': POP_RMS, 'M_m_am2': POP_M_M,
                                  'delta_H_s_ftlbs': 1.0, 'min_energy_M_o_am2': 2000.0, 'per_orbit': []}))
    out = tmp_path / 'design.json'
    assert main(['size-magnet', '--mode', 'day-constant', '--core', 'air', '--from-report', str(report),
                 '--json', str(out)]) == 0
    rep = json.loads(out.read_text())
    assert rep['moments_source'] == f'dump report {report}'
    three = rep['designs']['three_orthogonal']
    assert three['  battery, lbs'] == 0.0
    assert three['Total weight, lbs'] == pytest.approx(153, rel=0.02)  # §10 POP
    assert main(['size-magnet', '--mode', 'day-night', '--core', 'iron', '--from-report', str(report)]) == 0
    assert 'Iron core weight' in capsys.readouterr().out


def test_a_flown_day_constant_profile_is_sized_as_it_flew(tmp_path, capsys) -> None:
    """Issue 21 (§10 flown): a dump report of day-only dumping at constant |M| is sized at that |M| (factor 1, not
    1.3 × its M_m again), and only as day-constant."""
    report = tmp_path / 'day.json'
    report.write_text(json.dumps({'M_n_am2': 0.0, 'M_d_am2': 4000.0, 'M_o_am2': 3130.0, 'M_m_am2': 4000.0,
                                  'profile': 'day_constant', 'day_moment_am2': 4000.0, 'per_orbit': []}))
    flown, typed = tmp_path / 'flown.json', tmp_path / 'typed.json'
    assert main(['size-magnet', '--mode', 'day-constant', '--core', 'air', '--from-report', str(report),
                 '--json', str(flown)]) == 0
    assert main(['size-magnet', '--mode', 'day-constant', '--core', 'air', '--m-n-am2', '0', '--m-d-am2', '0',
                 '--m-m-am2', str(4000 / 1.3), '--json', str(typed)]) == 0
    a, b = (json.loads(p.read_text())['designs']['three_orthogonal'] for p in (flown, typed))
    assert a['Total weight, lbs'] == pytest.approx(b['Total weight, lbs'], rel=1e-9)
    assert 'day-only dumping flown' in json.loads(flown.read_text())['moments_source']
    capsys.readouterr()
    assert main(['size-magnet', '--mode', 'day-night', '--core', 'air', '--from-report', str(report)]) == 2
    assert 'size it with --mode day-constant' in capsys.readouterr().err


def test_section_12_estimate_and_errors(tmp_path, capsys) -> None:
    assert main(['size-magnet', '--mode', 'day-night', '--core', 'air', '--h-b-ftlbs', '255',
                 '--wire-area-in2', '0.008155']) == 0
    text = capsys.readouterr().out
    assert '§12 M_m = 12.5 H_b' in text and 'turns,' in text and 'V max' in text
    assert main(['size-magnet', '--mode', 'day-night', '--core', 'air', '--m-n-am2', '100', '--m-m-am2', '200']) == 2
    assert 'give both --m-n-am2 and --m-d-am2' in capsys.readouterr().err
    report = tmp_path / 'nonight.json'
    report.write_text(json.dumps({'M_n_am2': None, 'M_d_am2': 10.0, 'M_o_am2': 10.0, 'M_m_am2': 20.0}))
    assert main(['size-magnet', '--mode', 'day-night', '--core', 'air', '--from-report', str(report)]) == 2
    assert 'no orbital night' in capsys.readouterr().err
    assert main(['size-magnet', '--mode', 'day-night', '--core', 'air', '--m-n-am2', '300', '--m-d-am2', '1',
                 '--m-m-am2', '200']) == 2
    assert 'exceeds the maximum' in capsys.readouterr().err


def _exit_code(argv: list[str]) -> int:
    """main's return value, or the code of the SystemExit argparse raises on a bad option."""
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code)


@pytest.mark.parametrize(('args', 'message'), [
    (['--h-b-ftlbs', '-5'], 'argument --h-b-ftlbs: must be a finite number > 0, got -5'),
    (['--h-b-ftlbs', '255', '--altitude-nmi', '-100'], 'argument --altitude-nmi: must be a finite number > 0, got -100'),
    (['--h-b-ftlbs', '255', '--wire-area-in2', '0'], 'argument --wire-area-in2: must be a finite number > 0, got 0'),
    (['--h-b-ftlbs', '255', '--iz-minus-ix-slugft2', '1000'],
     'the moments come from one source; got --h-b-ftlbs and --iz-minus-ix-slugft2'),
])
def test_bad_options_are_one_line_in_the_units_typed_before_any_output(capsys, args, message) -> None:
    """A bad value is named by its option in the unit the user typed (not converted to SI), two sources of the
    moments are refused rather than one silently ignored, and nothing is printed first."""
    assert _exit_code(['size-magnet', '--mode', 'day-night', '--core', 'air', *args]) == 2
    captured = capsys.readouterr()
    assert message in captured.err and len(captured.err.strip().splitlines()) == 1, captured.err
    assert captured.out == ''


def test_json_path_is_checked_first_and_its_folder_created(tmp_path, capsys) -> None:
    assert main(['size-magnet', '--mode', 'day-night', '--core', 'air', '--h-b-ftlbs', '255',
                 '--json', '/proc/acds.json']) == 2
    captured = capsys.readouterr()
    assert captured.out == '' and '--json /proc/acds.json: cannot write' in captured.err
    out = tmp_path / 'new' / 'folder' / 'design.json'
    assert main(['size-magnet', '--mode', 'day-night', '--core', 'air', '--h-b-ftlbs', '255', '--json', str(out)]) == 0
    assert json.loads(out.read_text())['mode'] == 'day-night'
