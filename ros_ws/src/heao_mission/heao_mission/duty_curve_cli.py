"""``acds duty-curve``: bridge-switch duty cycle and switching frequency vs commanded current (spec §6, Fig. 4-10).

The numbers come from :mod:`em_driver.duty_curve` (measured on the simulated waveform, with the corrected
eq. 4-28 beside them); this verb prints them (a table, or ``--csv``) and draws them (``--png DIR``).
Constants are those of Fig. 4-10: E = 28 V, V_ces = 0.35 V, R_L = 30 Ω, ED = 0.6 V, ε = 0.01, L = 20.3 H.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
from em_driver.bridge_switch import BridgeSwitchCoil, duty_cycle_closed_form
from em_driver.duty_curve import FIG_4_10_COIL, FIG_4_10_DRIVER, duty_table, step_response

CSV_HEADER = 'current_a,duty_pct,switch_hz'


def _write_pngs(out_dir: Path, rows: list[tuple[float, float, float, float, float]], coil: Any, driver: Any) -> list[Path]:
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
    wave = step_response(i_step, 4.0, coil, driver)
    i_on = BridgeSwitchCoil(coil, driver).on_current_a
    tau = coil.tau_s
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6))
    top.plot(wave.times_s, wave.currents_a, lw=0.8, label='coil current')
    free = np.linspace(0.0, 2.5 * tau, 200)
    top.plot(free, i_on * (1 - np.exp(-free / tau)), 'C0--', lw=0.6,
             label='on path continued: I_on(1 − e^(−t/τ))')
    top.axvline(tau, color='gray', ls=':', label=f'τ = L/R = {tau:.3f} s')
    top.axhline((1 - math.exp(-1)) * i_on, color='C2', ls=':', label='63.2 % of I_on')
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



def cmd_duty_curve(args: argparse.Namespace) -> int:
    """Print the table (or CSV) and write the PNGs when asked."""
    from acds_cli.arguments import check_output_dir

    if args.png is not None:
        check_output_dir('--png', args.png)
    coil, driver = FIG_4_10_COIL, FIG_4_10_DRIVER
    rows = duty_table(coil, driver)
    if args.csv:
        print(CSV_HEADER)
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


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``duty-curve`` verb."""
    text = 'bridge-switch duty cycle and switching frequency vs commanded current (Fig. 4-10)'
    p = sub.add_parser('duty-curve', help=text, description=text)
    p.add_argument('--csv', action='store_true', help='print only a CSV (current_a,duty_pct,switch_hz) on stdout')
    p.add_argument('--png', metavar='DIR', type=Path, help='write duty_curve.png and coil_current_step.png into DIR')
    p.set_defaults(func=cmd_duty_curve)
