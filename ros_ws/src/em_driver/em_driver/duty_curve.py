"""Duty-cycle curve tool: measured bridge-switch duty and switching frequency vs coil current (spec §6).

Reproduces the kind of plot of seed 002 Fig. 4-10 from the simulated waveform
(not from the formula): for each commanded current the coil is run from rest
until settled in the ±ε band, then the duty cycle and the switching frequency
are measured over whole switching cycles (between the first and the last
off→on edge). The corrected eq. 4-28 is shown beside it for comparison.
Constants are those of Fig. 4-10: E = 28 V, V_ces = 0.35 V, R_L = 30 Ω,
ED = 0.6 V, ε = 0.01, with L = 20.3 H (Table 4-3).

Usage: ``duty-curve [--csv] [--png DIR]``.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from em_driver.bridge_switch import BridgeSwitchCoil, CoilParams, DriverParams, duty_cycle_closed_form

__all__ = ['FIG_4_10_COIL', 'FIG_4_10_DRIVER', 'sweep_currents_a', 'measure_duty', 'main']

#: Fig. 4-10 coil: R_L = 30 Ω (the figure's value), L = 20.3 H (Table 4-3).
FIG_4_10_COIL = CoilParams(resistance_ohm=30.0, inductance_h=20.3)
#: Fig. 4-10 driver constants.
FIG_4_10_DRIVER = DriverParams(supply_v=28.0, v_ces_v=0.35, diode_drop_v=0.6, epsilon=0.01)


def sweep_currents_a() -> np.ndarray:
    """The swept command currents, A: 0.05 to 0.85 A in 0.05 A steps (17 points)."""
    return np.round(np.arange(1, 18) * 0.05, 10)


def measure_duty(i_c_a: float, coil: CoilParams = FIG_4_10_COIL, driver: DriverParams = FIG_4_10_DRIVER,
                 settle_s: float | None = None, cycles: int = 20, max_window_s: float = 20.0) -> tuple[float, float]:
    """Measured (duty 0…1, switching frequency Hz) for command i_c_a (A) from the simulated waveform.

    Runs from rest for settle_s (default 8·τ, well past the rise into the band),
    then records in chunks until ``cycles`` whole switching cycles are seen or
    max_window_s (s) elapses. No switching at all means saturation: (1.0, 0.0)
    if the bridge stayed on, (0.0, 0.0) if it stayed off.
    """
    unit = BridgeSwitchCoil(coil, driver)
    unit.run(i_c_a, 8.0 * coil.tau_s if settle_s is None else settle_s)
    chunk_s = 0.25
    rising: list[float] = []
    falling: list[float] = []
    elapsed = 0.0
    was_on = unit.bridge_on
    while len(rising) < cycles + 1 and elapsed < max_window_s:
        wave = unit.run(i_c_a, chunk_s, record=True, record_step_s=chunk_s).waveform
        assert wave is not None
        for t, on in zip(wave.times_s[:-1], wave.bridge_on[:-1], strict=True):
            if on != was_on:
                (rising if on else falling).append(elapsed + float(t))
                was_on = bool(on)
        elapsed += chunk_s
    if len(rising) < 2:
        return (1.0 if unit.bridge_on else 0.0), 0.0
    start, end = rising[0], rising[-1]
    on_time = 0.0
    for t_up in rising[:-1]:
        t_down = next(t for t in falling if t > t_up)
        on_time += t_down - t_up
    span = end - start
    return on_time / span, (len(rising) - 1) / span


def _sweep(coil: CoilParams, driver: DriverParams) -> list[tuple[float, float, float, float, float]]:
    """Rows (current A, measured duty, measured Hz, eq. 4-28 duty, eq. 4-28 Hz)."""
    rows = []
    for i_c in sweep_currents_a():
        duty, freq = measure_duty(float(i_c), coil, driver)
        duty_eq, freq_eq = duty_cycle_closed_form(float(i_c), coil, driver)
        rows.append((float(i_c), duty, freq, duty_eq, freq_eq))
    return rows


def _write_pngs(out_dir: Path, rows: list[tuple[float, float, float, float, float]], coil: CoilParams,
                driver: DriverParams) -> list[Path]:
    """duty_curve.png (measured vs corrected eq. 4-28) and coil_current_step.png (0 → 0.5 A step)."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    grid = np.linspace(0.01, 0.9, 300)
    eq = np.array([duty_cycle_closed_form(float(i), coil, driver) for i in grid])
    fig, ax1 = plt.subplots(figsize=(7, 4.5))
    ax1.plot(grid, 100.0 * eq[:, 0], '-', color='C0', label='duty, corrected eq. 4-28')
    ax1.plot([r[0] for r in rows], [100.0 * r[1] for r in rows], 'o', color='C0', label='duty, measured')
    ax1.set_xlabel('coil current I_c (A)')
    ax1.set_ylabel('duty cycle (%)')
    ax2 = ax1.twinx()
    ax2.plot(grid, eq[:, 1], '--', color='C1', label='switching freq., eq.')
    ax2.plot([r[0] for r in rows], [r[2] for r in rows], 's', color='C1', mfc='none', label='switching freq., measured')
    ax2.set_ylabel('switching frequency (Hz)')
    ax2.set_yscale('log')
    lines = ax1.get_legend_handles_labels()
    lines2 = ax2.get_legend_handles_labels()
    ax1.legend(lines[0] + lines2[0], lines[1] + lines2[1], loc='center right', fontsize=8)
    ax1.set_title('Electromagnet driver duty cycle vs coil current (cf. seed Fig. 4-10)')
    ax1.grid(True, alpha=0.3)
    duty_png = out_dir / 'duty_curve.png'
    fig.tight_layout()
    fig.savefig(duty_png, dpi=120)
    plt.close(fig)

    i_step = 0.5
    unit = BridgeSwitchCoil(coil, driver)
    wave = unit.run(i_step, 4.0, record=True, record_step_s=1e-4).waveform
    assert wave is not None
    tau = coil.tau_s
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6))
    top.plot(wave.times_s, wave.currents_a, lw=0.8, label='coil current')
    free = np.linspace(0.0, 2.5 * tau, 200)
    top.plot(free, unit.on_current_a * (1 - np.exp(-free / tau)), 'C0--', lw=0.6,
             label='on path continued: I_on(1 − e^(−t/τ))')
    top.axvline(tau, color='gray', ls=':', label=f'τ = L/R = {tau:.3f} s')
    top.axhline((1 - math.exp(-1)) * unit.on_current_a, color='C2', ls=':', label='63.2 % of I_on')
    top.axhline(i_step, color='k', lw=0.5, label=f'command {i_step} A')
    top.set_xlabel('time (s)')
    top.set_ylabel('coil current (A)')
    top.set_title(f'Coil current, command step 0 → {i_step} A')
    top.legend(fontsize=8)
    zoom = wave.times_s > 3.9
    bottom.plot(wave.times_s[zoom], wave.currents_a[zoom], lw=0.8)
    for level in (1 - driver.epsilon, 1 + driver.epsilon):
        bottom.axhline(level * i_step, color='C3', ls='--', lw=0.7)
    bottom.set_xlabel('time (s)')
    bottom.set_ylabel('coil current (A)')
    bottom.set_title(f'settled: held in the ±ε = ±{driver.epsilon:.0%} band')
    step_png = out_dir / 'coil_current_step.png'
    fig.tight_layout()
    fig.savefig(step_png, dpi=120)
    plt.close(fig)
    return [duty_png, step_png]


def main(argv: list[str] | None = None) -> int:
    """Entry point: ``[--csv] [--png DIR]``; returns the process exit code."""
    parser = argparse.ArgumentParser(prog='duty-curve', description=__doc__.splitlines()[0])
    parser.add_argument('--csv', action='store_true',
                        help='print only a CSV (current_a,duty_pct,switch_hz) on stdout')
    parser.add_argument('--png', metavar='DIR', type=Path,
                        help='write duty_curve.png and coil_current_step.png into DIR')
    args = parser.parse_args(argv)
    coil, driver = FIG_4_10_COIL, FIG_4_10_DRIVER
    rows = _sweep(coil, driver)
    if args.csv:
        print('current_a,duty_pct,switch_hz')
        for i_c, duty, freq, _, _ in rows:
            print(f'{i_c:.2f},{100.0 * duty:.3f},{freq:.3f}')
    else:
        print('Bridge-switch duty cycle (E=28 V, Vces=0.35 V, R=30 ohm, ED=0.6 V, eps=0.01, L=20.3 H)')
        print(f'{"I_c (A)":>8} {"duty meas (%)":>14} {"duty eq4-28 (%)":>16} {"f meas (Hz)":>12} {"f eq (Hz)":>10}')
        for i_c, duty, freq, duty_eq, freq_eq in rows:
            print(f'{i_c:8.2f} {100 * duty:14.3f} {100 * duty_eq:16.3f} {freq:12.2f} {freq_eq:10.2f}')
    if args.png is not None:
        for path in _write_pngs(args.png, rows, coil, driver):
            print(f'wrote {path}', file=sys.stderr)
    return 0


if __name__ == '__main__':
    sys.exit(main())
