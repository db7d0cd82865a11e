"""The GSFC Mark VI torque-meter stand (seed 001 "Subsystem testing", Figs. 11–14): its core and ``acds torque-meter``."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import pytest
from acds_cli.__main__ import main
from acds_common.units import GAUSS_T, nm_to_dyne_cm
from ascs_mode_manager import torque_meter
from ascs_mode_manager.spin_mechanizations import ATTITUDE_COIL, SPIN_COIL, AscsError
from sss_mission.torque_meter_cli import CSV_HEADER


def _csv_rows(capsys: pytest.CaptureFixture[str], argv: list[str]) -> list[dict]:
    assert main(["torque-meter", *argv]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0] == CSV_HEADER
    return list(csv.DictReader(io.StringIO(out)))


def test_csv_single_field_steady_rotation(capsys: pytest.CaptureFixture[str]) -> None:
    rows = _csv_rows(capsys, ["--csv", "--field", "0.3"])
    assert len(rows) == 1
    row = rows[0]
    assert float(row["field_g"]) == pytest.approx(0.3)
    assert int(row["enabled"]) == 1
    assert float(row["on_fraction"]) == pytest.approx(1.0, abs=1e-3)
    # Derived: dead zone |sin θ| < L/B removes the low part of each lobe:
    # τ_avg = (2/π)·M·B·√(1 − (L/B)²), peak = M·B.
    m, b, ratio = SPIN_COIL.peak_moment_am2(), 0.3 * GAUSS_T, 0.075 / 0.3
    expected_avg = nm_to_dyne_cm(2 / math.pi * m * b * math.sqrt(1 - ratio**2))
    assert float(row["avg_torque_dyne_cm"]) == pytest.approx(expected_avg, rel=0.01)
    assert float(row["peak_torque_dyne_cm"]) == pytest.approx(nm_to_dyne_cm(m * b), rel=0.005)
    assert float(row["ripple_pct"]) > 48.3  # more than the ideal one-channel value (seed: "more torque ripple")


def test_csv_at_0070_stays_off(capsys: pytest.CaptureFixture[str]) -> None:
    rows = _csv_rows(capsys, ["--csv", "--field", "0.070"])
    assert len(rows) == 1
    assert int(rows[0]["enabled"]) == 0
    assert float(rows[0]["on_fraction"]) == 0.0
    assert float(rows[0]["avg_torque_dyne_cm"]) == 0.0


def test_default_perigee_pass_turns_on_once_and_off_once() -> None:
    run = torque_meter.run_torque_meter()
    rows = torque_meter.step_rows(run)
    assert [r["field_g"] for r in rows] == list(torque_meter.DEFAULT_FIELD_STEPS_G)
    assert [e.kind for e in run.events] == ["turn_on", "turn_off"]
    first_on = next(i for i, r in enumerate(rows) if r["enabled"])
    assert rows[first_on - 1]["field_g"] <= 0.075 < rows[first_on]["field_g"]
    assert rows[0]["on_fraction"] == 0.0 and rows[-1]["on_fraction"] == 0.0 and rows[-1]["enabled"] == 0
    peak = max(rows, key=lambda r: r["field_g"])
    assert peak["coil_duty"] > 0.8  # seed: "energized over 80% of the time" at the 0.274 G peak
    avgs = [r["avg_torque_dyne_cm"] for r in rows]
    assert avgs == pytest.approx(avgs[::-1], rel=1e-3, abs=1e-9)  # the stepped pass is symmetric
    assert all(r["avg_torque_dyne_cm"] >= 0.0 for r in rows)


def test_despin_reverses_the_stand_torque() -> None:
    up = torque_meter.step_rows(torque_meter.run_torque_meter((0.2,), dwell_s=30.0))[0]
    down = torque_meter.step_rows(torque_meter.run_torque_meter((0.2,), dwell_s=30.0, direction="despin"))[0]
    assert down["avg_torque_dyne_cm"] == pytest.approx(-up["avg_torque_dyne_cm"], rel=1e-6)
    assert up["avg_torque_dyne_cm"] > 0.0


def test_attitude_variant_tilt_geometry(capsys: pytest.CaptureFixture[str]) -> None:
    rows = _csv_rows(capsys, ["--csv", "--attitude", "--field", "0.274"])
    run = torque_meter.run_torque_meter((0.274,), attitude=True)
    reading_peak = torque_meter.step_rows(run)[0]["peak_reading_dyne_cm"]
    m, b = ATTITUDE_COIL.peak_moment_am2(), 0.274 * GAUSS_T
    assert reading_peak == pytest.approx(nm_to_dyne_cm(m * b * math.sin(math.radians(10.0))), rel=0.005)
    assert float(rows[0]["peak_torque_dyne_cm"]) == pytest.approx(5.61 * reading_peak, rel=1e-3)
    assert float(rows[0]["avg_torque_dyne_cm"]) == pytest.approx(nm_to_dyne_cm(m * b), rel=0.01)
    assert float(rows[0]["on_fraction"]) == pytest.approx(1.0)


def test_png_written(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["torque-meter", "--field", "0.1", "0.3", "--dwell-s", "20", "--png", str(tmp_path)]) == 0
    out = capsys.readouterr()
    assert "Mark VI" in out.out and "turn_on" in out.out
    png = tmp_path / "torque_meter_spin.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bad_arguments() -> None:
    with pytest.raises(AscsError):
        torque_meter.run_torque_meter((math.nan,))
    with pytest.raises(AscsError):
        torque_meter.run_torque_meter((0.3,), dt_s=0.0)
    assert main(["torque-meter", "--field", "-1"]) == 2


@pytest.mark.parametrize("argv", [["--dt-s", "1e-9"], ["--dwell-s", "1e9"]])
def test_a_run_too_long_to_sample_is_one_line_exit_2(capsys: pytest.CaptureFixture[str], argv: list[str]) -> None:
    """A dwell/period that asks for more samples than memory holds was a numpy MemoryError traceback (exit 1)."""
    assert main(["torque-meter", *argv]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and len(captured.err.strip().splitlines()) == 1
    assert "samples, more than the" in captured.err
