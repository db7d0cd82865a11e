"""Tests of the duty-curve user tool (spec §6, seed 002 Fig. 4-10)."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import pytest
from em_driver.bridge_switch import duty_cycle_closed_form
from em_driver.duty_curve import FIG_4_10_COIL, FIG_4_10_DRIVER, main, measure_duty, sweep_currents_a


def test_sweep_points() -> None:
    currents = sweep_currents_a()
    assert len(currents) >= 17
    assert currents[0] == pytest.approx(0.05) and currents[-1] == pytest.approx(0.85)


def test_csv_output_is_exactly_a_csv(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(['--csv']) == 0
    out = capsys.readouterr().out
    rows = list(csv.reader(io.StringIO(out)))
    assert rows[0] == ['current_a', 'duty_pct', 'switch_hz']
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


def test_measured_duty_is_from_the_waveform_not_the_formula() -> None:
    """Saturation (upper threshold above I_on) measures as 100 % and 0 Hz."""
    i_on = (28.0 - 0.7) / 30.0
    assert measure_duty(0.995 * i_on) == (1.0, 0.0)
    duty, freq = measure_duty(0.3, cycles=5)
    duty_eq, f_eq = duty_cycle_closed_form(0.3, FIG_4_10_COIL, FIG_4_10_DRIVER)
    assert duty == pytest.approx(duty_eq, abs=1e-6) and freq == pytest.approx(f_eq, rel=1e-6)


def test_readable_table(capsys: pytest.CaptureFixture[str]) -> None:
    assert main([]) == 0
    out = capsys.readouterr().out
    assert 'eq4-28' in out and '0.85' in out


def test_png_output(tmp_path: Path) -> None:
    assert main(['--csv', '--png', str(tmp_path)]) == 0
    for name in ('duty_curve.png', 'coil_current_step.png'):
        path = tmp_path / name
        assert path.is_file() and path.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
        assert path.stat().st_size > 10_000
