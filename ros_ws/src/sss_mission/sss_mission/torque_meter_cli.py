"""``acds torque-meter``: the GSFC Mark VI torque-meter test of the SSS ASCS (seed 001 "Subsystem testing").

The stand is :mod:`ascs_mode_manager.torque_meter` (``run_torque_meter``, ``step_rows``); this verb prints
its rows (a table, or ``--csv``: field_g; enabled; on_fraction; avg/peak torque in dyne-cm; ripple %) and
draws the strip chart of seed Figs. 11–14 (``--png DIR``).
"""

from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np
from acds_common.units import GAUSS_T, nm_to_dyne_cm
from ascs_mode_manager.spin_mechanizations import AscsError
from ascs_mode_manager.sss_ascs import SssAscsConfig
from ascs_mode_manager.torque_meter import (
    DEFAULT_FIELD_STEPS_G,
    SEED_TILT_FACTOR,
    STAND_TILT_DEG,
    StandRun,
    run_torque_meter,
    step_rows,
)

CSV_HEADER = "field_g,enabled,on_fraction,avg_torque_dyne_cm,peak_torque_dyne_cm,ripple_pct"


def _format_csv(rows: list[dict]) -> str:
    lines = [CSV_HEADER]
    for r in rows:
        lines.append(f"{r['field_g']:.3f},{r['enabled']},{r['on_fraction']:.4f},{r['avg_torque_dyne_cm']:.2f},"
                     f"{r['peak_torque_dyne_cm']:.2f},{r['ripple_pct']:.2f}")
    return "\n".join(lines) + "\n"


def _format_table(run: StandRun, rows: list[dict]) -> str:
    mode = "attitude (10° tilt)" if run.attitude else "spin"
    lines = [f"GSFC Mark VI torque-meter, SSS ASCS {mode} mode, 4 rpm rotating field (seed 001 Figs. 11-14)"]
    if run.attitude:
        lines.append(f"torques: avg = developed |M x B|; peak = {SEED_TILT_FACTOR} x peak stand reading "
                     f"(geometric 1/sin {STAND_TILT_DEG:.0f} deg = {1 / math.sin(math.radians(STAND_TILT_DEG)):.2f})")
    lines.append(f"{'field G':>8} {'active':>6} {'on frac':>8} {'coil duty':>9} {'avg dyn-cm':>11} "
                 f"{'peak dyn-cm':>12} {'reading pk':>11} {'ripple %':>9}")
    for r in rows:
        lines.append(f"{r['field_g']:8.3f} {r['enabled']:6d} {r['on_fraction']:8.3f} {r['coil_duty']:9.3f} "
                     f"{r['avg_torque_dyne_cm']:11.1f} {r['peak_torque_dyne_cm']:12.1f} "
                     f"{r['peak_reading_dyne_cm']:11.1f} {r['ripple_pct']:9.1f}")
    lines.append("events:")
    lines.extend(f"  t={e.t_s:8.2f} s  {e.kind:8s} {e.detail}" for e in run.events)
    return "\n".join(lines) + "\n"


def write_png(run: StandRun, directory: str) -> str:
    """Strip chart like seed Figs. 11–14: field magnitude and magnetometer signal, torque-meter output over
    the run, and one enlarged revolution at the peak field; returns the PNG path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(directory, exist_ok=True)
    path = os.path.join(directory, f"torque_meter_{'attitude' if run.attitude else 'spin'}.png")
    fig, axes = plt.subplots(3, 1, figsize=(11, 9))
    axes[0].plot(run.t_s, run.signal_g, lw=0.6, label="ASCS magnetometer (body y)")
    axes[0].plot(run.t_s, run.field_g, "k", lw=1.2, label="control field magnitude")
    level_g = SssAscsConfig().polarity_level_t / GAUSS_T
    for sign in (1, -1):
        axes[0].axhline(sign * level_g, color="r", ls=":", lw=0.8)
    axes[0].set_ylabel("field, G")
    axes[0].legend(loc="upper right", fontsize=8)
    torque_dyne = nm_to_dyne_cm(run.stand_torque_nm)
    axes[1].plot(run.t_s, torque_dyne, lw=0.6)
    for e in run.events:
        axes[1].axvline(e.t_s, color="g" if e.kind == "turn_on" else "r", ls="--", lw=0.8)
    axes[1].set_ylabel("torque-meter output, dyne-cm")
    peak_step = int(np.argmax(run.field_steps_g))
    t0 = run.t_s[run.step_index == peak_step][0]
    zoom = (run.t_s >= t0) & (run.t_s < t0 + 60.0 / 4.0)
    axes[2].plot(run.t_s[zoom], torque_dyne[zoom], lw=1.0)
    axes[2].set_title(f"enlarged: {run.field_steps_g[peak_step]:.3f} G, 4-rpm control field", fontsize=9)
    axes[2].set_ylabel("dyne-cm")
    axes[2].set_xlabel("time, s")
    fig.suptitle(f"SSS ASCS {'attitude' if run.attitude else 'spin'} mode on the Mark VI torque-meter")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def cmd_torque_meter(args: argparse.Namespace) -> int:
    """Run the stand and print its table (or CSV); write the strip chart when asked."""
    from pathlib import Path

    from acds_cli.arguments import check_output_dir

    if args.png:
        check_output_dir("--png", Path(args.png))
    try:
        run = run_torque_meter(tuple(args.field) if args.field else DEFAULT_FIELD_STEPS_G,
                               attitude=args.attitude, dwell_s=args.dwell_s, dt_s=args.dt_s,
                               direction="despin" if args.despin else "spin_up")
    except AscsError as exc:
        print(f"acds torque-meter: {exc}", file=sys.stderr)
        return 2
    rows = step_rows(run)
    sys.stdout.write(_format_csv(rows) if args.csv else _format_table(run, rows))
    if args.png:
        path = write_png(run, args.png)
        print(f"wrote {path}", file=sys.stderr)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``torque-meter`` verb."""
    text = "the GSFC Mark VI torque-meter test of the SSS spin/attitude modes"
    p = sub.add_parser("torque-meter", help=text, description=text)
    p.add_argument("--csv", action="store_true", help="print only the CSV table on stdout")
    p.add_argument("--png", metavar="DIR", help="write a torque-vs-time PNG into DIR")
    p.add_argument("--field", metavar="G", type=float, nargs="+", help="field magnitude step(s), gauss")
    p.add_argument("--attitude", action="store_true", help="attitude-mode test with the 10° tilt")
    p.add_argument("--despin", action="store_true", help="command despin instead of spin-up")
    p.add_argument("--dwell-s", type=float, default=60.0, help="duration of each field step, s")
    p.add_argument("--dt-s", type=float, default=0.02, help="sample step, s")
    p.set_defaults(func=cmd_torque_meter)
