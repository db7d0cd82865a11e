"""``acds dump-report`` (seed 000 §5): a bag gives exactly the report its run printed, read-only; a scenario is run
with the direct engine first; the JSON feeds ``size-magnet``; bad inputs are one line, exit 2."""

from __future__ import annotations

import json

import pytest
from aap_mission.dump_report import report_from_bag
from acds_cli.__main__ import main
from acds_common.scenario import load_scenario
from acds_runtime.direct import DirectRun

STEPS = 330  # 20 s steps: the first orbit (5563 s) and a part of the second


def test_a_bag_gives_the_report_of_its_run_without_changing_it(tmp_path, capsys, folder_state) -> None:
    bag = tmp_path / 'run' / 'bag'
    run = DirectRun(load_scenario('aap_workshop_pop_test'), steps=STEPS, record=bag).run()
    summary, series, scenario = report_from_bag(bag)
    assert summary['dump_report'] == run.summary['dump_report']
    assert scenario.name == 'aap_workshop_pop_test' and len(series.m_am2) == STEPS + 1
    before = folder_state(bag)
    out = tmp_path / 'report.json'
    assert main(['dump-report', str(bag), '--json', str(out), '--out', str(tmp_path / 'plots')]) == 0
    assert folder_state(bag) == before
    report = json.loads(out.read_text())
    for key in ('M_n_am2', 'M_d_am2', 'M_o_am2', 'M_m_am2', 'delta_H_s_ftlbs', 'min_energy_M_o_am2'):
        assert report[key] == max(row[key] for row in report['per_orbit'])
    assert report['orbits'] == 1 and report['per_orbit'][0]['orbit'] == 0
    assert sorted(p.name for p in (tmp_path / 'plots').iterdir()) == ['dump_h_s.png', 'dump_moment.png']
    text = capsys.readouterr().out
    assert 'largest over the orbits (Table 1)' in text and 'minimum-energy solution' in text
    assert main(['size-magnet', '--mode', 'day-night', '--core', 'air', '--from-report', str(out)]) == 0


def test_a_scenario_runs_with_the_direct_engine_and_takes_overrides(tmp_path, capsys) -> None:
    out = tmp_path / 'zero.json'
    code = main(['dump-report', 'aap_workshop_pop_test', '--steps', str(STEPS), '--out', str(tmp_path / 'run'),
                 '--set', 'controller.dump_h_s_init=measured', '--json', str(out)])
    assert code == 0
    first = json.loads(out.read_text())['per_orbit'][0]
    assert first['H_s_ftlbs'] == [0.0, 0.0, 0.0] and first['M_m_am2'] == 0.0  # H_s from zero: no dump on orbit 0
    assert (tmp_path / 'run' / 'bag').is_dir() and (tmp_path / 'run' / 'dump_moment.png').is_file()


def test_the_seed_k_read_in_amp_turn_m2_prints_one_warning_and_in_amp_turn_ft2_converges(tmp_path, capsys) -> None:
    """The memo's k = 4e6 read as its text says (M in amp-turn-m²) gives loop gains that leave (0, 2): one warning
    line, ``loop_converges: false``. Read in amp-turn-ft² (the reading its stated range 3–5e6 fits; the literal
    case the scenarios ship) it is 3.716e5 in amp-turn-m² units and converges, as does the shipped loop-gain rule."""
    literal, ft2, shipped = tmp_path / 'literal.json', tmp_path / 'ft2.json', tmp_path / 'shipped.json'
    assert main(['dump-report', 'aap_workshop_pop_test', '--steps', str(STEPS), '--out', str(tmp_path / 'a'),
                 '--set', 'controller.dump_gain_rule=stated', '--set', 'controller.dump_gain_am2_per_ftlbs_t=4e6',
                 '--json', str(literal)]) == 0
    text = capsys.readouterr().out
    assert sum('WARNING' in line and 'cannot converge' in line for line in text.splitlines()) == 1, text
    report = json.loads(literal.read_text())
    assert report['loop_converges'] is False and report['loop_gain_max'] > 2.0 and report['k_seed'] == 4e6
    gain_m2 = report['loop_gain_max']
    assert main(['dump-report', 'aap_workshop_pop_test', '--steps', str(STEPS), '--out', str(tmp_path / 'c'),
                 '--set', 'controller.dump_gain_rule=stated', '--json', str(ft2)]) == 0
    assert 'WARNING' not in capsys.readouterr().out
    report = json.loads(ft2.read_text())
    assert abs(report['k_seed'] - 4e6 * 0.3048 ** 2) < 1e-6 and report['loop_converges'] is True
    assert abs(report['loop_gain_max'] - gain_m2 * 0.3048 ** 2) < 1e-9  # the gains scale with k
    assert main(['dump-report', 'aap_workshop_pop_test', '--steps', str(STEPS), '--out', str(tmp_path / 'b'),
                 '--json', str(shipped)]) == 0
    assert 'WARNING' not in capsys.readouterr().out
    report = json.loads(shipped.read_text())
    assert report['loop_converges'] is True and 0.0 < report['loop_gain_min'] < report['loop_gain_max'] < 2.0


def test_day_only_dumping_prints_no_loop_gains(tmp_path, capsys) -> None:
    """§10's day-only law flies a constant |M| in daylight, not the linear k·H_s × B loop: the report's k·W gains
    column is empty ('—') and says why, instead of the day-and-night loop's gains."""
    out = tmp_path / 'day.json'
    assert main(['dump-report', 'aap_workshop_pop_test', '--steps', str(STEPS), '--out', str(tmp_path / 'run'),
                 '--set', 'controller.dump_day_only=true', '--json', str(out)]) == 0
    text = capsys.readouterr().out
    report = json.loads(out.read_text())
    assert report['profile'] == 'day_constant' and 'loop_gains' not in report['per_orbit'][0]
    assert 'no k·W gains: that law is not the linear k·H_s × B loop' in text
    assert report['loop_converges'] is None and 'WARNING' not in text


@pytest.mark.slow
def test_k_sweep_and_mm_sweep_tables(tmp_path, capsys) -> None:
    """The §5 k study and a §12 sweep on one orbit each (6 short direct runs): a row per value, the table, the plot
    and the JSON."""
    out = tmp_path / 'k.json'
    assert main(['dump-report', 'aap_workshop_pop_test', '--steps', '290', '--out', str(tmp_path / 'k'),
                 '--k-sweep', '2e5:4e6:2', '--json', str(out)]) == 0
    rows = json.loads(out.read_text())['rows']
    assert [r['k_seed'] for r in rows] == [2e5, 4e6]
    assert rows[0]['loop_converges'] is True and rows[1]['loop_converges'] is False
    assert rows[1]['orbits_to_converge_from_zero'] is None and rows[1]['loop_gain_min'] > 2.0
    assert (tmp_path / 'k' / 'k_sweep.png').is_file() and 'k study' in capsys.readouterr().out
    out = tmp_path / 'mm.json'
    assert main(['dump-report', 'aap_workshop_pop_test', '--steps', '290', '--out', str(tmp_path / 'mm'),
                 '--mm-sweep', 'hb:100:300:2', '--json', str(out)]) == 0
    result = json.loads(out.read_text())
    assert [r['H_b_ftlbs'] for r in result['rows']] == pytest.approx([100.0, 300.0])
    assert result['rows'][1]['M_m_am2'] > 2.0 * result['rows'][0]['M_m_am2'] and result['slopes']['hb_ols'] > 0
    assert (tmp_path / 'mm' / 'mm_sweep_hb.png').is_file()


@pytest.mark.parametrize(('args', 'fragment'), [
    (['no_such_scenario'], 'no_such_scenario'),
    (['aap_workshop_pop_test', '--set', 'dump_law'], 'expected SECTION.KEY=VALUE'),
    (['heao_b_acquisition', '--steps', '2'], 'not an AAP Workshop run'),
    (['aap_workshop_pop_test', '--k-sweep', '1e5:2e5'], 'expected A:B:N'),
    (['aap_workshop_pop_test', '--mm-sweep', 'mass:1:2:2'], 'KIND one of'),
])
def test_bad_inputs_are_one_line(tmp_path, capsys, args, fragment) -> None:
    assert main(['dump-report', *args, '--out', str(tmp_path / 'out')]) == 2
    err = capsys.readouterr().err.strip()
    assert fragment in err and len(err.splitlines()) == 1, err


def test_a_bad_set_key_is_named_against_the_scenario_not_a_temporary_file(tmp_path, capsys) -> None:
    """--set goes through a temporary file that extends the scenario; its schema error named that file
    (/tmp/tmpXXXX/dump_study_scenario.yaml, gone when the user reads it)."""
    assert main(['dump-report', 'aap_workshop_pop_test', '--set', 'controller.foo=1', '--out', str(tmp_path / 'o')]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and 'dump_study_scenario' not in err, err
    assert err.startswith('acds dump-report: aap_workshop_pop_test with --set: unknown key "controller.foo"'), err
