"""The verbs that print and draw a core's numbers: ``acds duty-curve`` (spec §6, Fig. 4-10) and ``acds
mechanizations`` (seed 001 Table 1); ``acds torque-meter``: tests/test_torque_meter.py."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import pytest
from acds_cli.__main__ import main
from em_driver.bridge_switch import duty_cycle_closed_form
from em_driver.duty_curve import FIG_4_10_COIL, FIG_4_10_DRIVER
from heao_mission import duty_curve_cli as duty_curve
from sss_mission import mechanizations_cli as mechanizations

KEYS = ("two_channel_sine", "two_channel_constant", "one_channel_sine", "one_channel_constant")


def test_csv_output_is_exactly_a_csv(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(['duty-curve', '--csv']) == 0
    out = capsys.readouterr().out
    rows = list(csv.reader(io.StringIO(out)))
    assert rows[0] == duty_curve.CSV_HEADER.split(',')
    data = [[float(x) for x in row] for row in rows[1:]]
    assert len(data) >= 17 and all(len(r) == 3 for r in data)
    assert data[0][0] == pytest.approx(0.05) and data[-1][0] == pytest.approx(0.85)
    for current, duty_pct, switch_hz in data:
        duty_eq, f_eq = duty_cycle_closed_form(current, FIG_4_10_COIL, FIG_4_10_DRIVER)
        assert duty_pct == pytest.approx(100.0 * duty_eq, abs=1.0)  # within 1 % absolute
        assert switch_hz == pytest.approx(f_eq, rel=0.01)
    duties = [r[1] for r in data]
    assert duties == sorted(duties)  # duty rises with current (Fig. 4-10)
    assert duties[0] == pytest.approx(54.0, abs=1.0)


def test_readable_table(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(['duty-curve']) == 0
    out = capsys.readouterr().out
    assert 'eq4-28' in out and '0.85' in out


def test_png_output(tmp_path: Path) -> None:
    assert main(['duty-curve', '--csv', '--png', str(tmp_path)]) == 0
    for name in ('duty_curve.png', 'coil_current_step.png'):
        path = tmp_path / name
        assert path.is_file() and path.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
        assert path.stat().st_size > 10_000


def test_mechanizations_tool_csv(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["mechanizations", "--csv"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0] == mechanizations.CSV_HEADER
    rows = list(csv.DictReader(io.StringIO(out)))
    assert [r["mechanization"] for r in rows] == list(KEYS)
    by_key = {r["mechanization"]: r for r in rows}
    assert float(by_key["two_channel_sine"]["ripple_pct"]) < 0.5
    assert float(by_key["two_channel_constant"]["sweep_deg"]) == pytest.approx(90.0, abs=0.5)
    assert int(by_key["one_channel_constant"]["coils"]) == 1
    for r in rows:
        assert float(r["avg_torque_dyne_cm"]) == pytest.approx(506.0, rel=0.015)


def test_mechanizations_tool_readable(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["mechanizations"]) == 0
    out = capsys.readouterr().out
    assert "one_channel_constant" in out and "Table 1" in out


@pytest.mark.parametrize('argv', [
    ['duty-curve', '--png'],
    ['torque-meter', '--field', '0.3', '--dwell-s', '1', '--png'],
    ['emff-airtrack', '--duration-s', '1', '--out'],
], ids=['duty-curve', 'torque-meter', 'emff-airtrack'])
@pytest.mark.parametrize('where', ['unwritable', 'a file'])
def test_a_plot_folder_that_cannot_be_written_is_one_line_exit_2_before_any_output(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], where: str) -> None:
    folder = '/proc/acds_plots' if where == 'unwritable' else str(tmp_path / 'file.txt')
    (tmp_path / 'file.txt').write_text('x')
    assert main([*argv, folder]) == 2
    captured = capsys.readouterr()
    assert captured.out == ''
    assert captured.err.startswith(f'acds {argv[0]}: error: --{argv[-1].lstrip("-")} {folder}: ')
    assert len(captured.err.strip().splitlines()) == 1
