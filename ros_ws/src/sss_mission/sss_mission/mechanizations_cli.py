"""``acds mechanizations [--csv]``: seed 001 Table 1 recomputed from simulated torque histories.

Each of the four spin-mode mechanizations runs in a constant 0.3 G field rotating at 4 rpm in the plane
of motor action (:func:`ascs_mode_manager.spin_mechanizations.table_rows`).  The readable table adds the
derived closed forms and the seed's Table 1 values beside them.
"""

from __future__ import annotations

import argparse
import sys

from acds_common.units import nm_to_dyne_cm
from ascs_mode_manager.spin_mechanizations import (
    DESIGN_FIELD_T,
    MECHANIZATIONS,
    closed_form_average_torque_nm,
    closed_form_ripple_pct,
    table_rows,
)

CSV_HEADER = "mechanization,coils,magnetometers,power_w,peak_moment_am2,avg_torque_dyne_cm,ripple_pct,sweep_deg"


def cmd_mechanizations(args: argparse.Namespace) -> int:
    """Print the mechanization comparison (CSV with ``--csv``, else a readable table)."""
    rows = table_rows()
    if args.csv:
        lines = [CSV_HEADER]
        lines += [f"{r['mechanization']},{r['coils']},{r['magnetometers']},{r['power_w']:.3f},"
                  f"{r['peak_moment_am2']:.3f},{r['avg_torque_dyne_cm']:.1f},{r['ripple_pct']:.2f},"
                  f"{r['sweep_deg']:.1f}" for r in rows]
        sys.stdout.write("\n".join(lines) + "\n")
        return 0
    print("Spin-mode mechanizations in a 0.3 G field rotating at 4 rpm (seed 001 Table 1, simulated)")
    print(f"{'mechanization':22s} {'coils':>5} {'mags':>4} {'power W':>8} {'(seed)':>6} {'peak Am2':>9} "
          f"{'(seed)':>6} {'avg dyn-cm':>10} {'(closed)':>8} {'ripple %':>8} {'(closed)':>8} {'sweep deg':>9}")
    for r in rows:
        mech = MECHANIZATIONS[r["mechanization"]]
        closed = nm_to_dyne_cm(closed_form_average_torque_nm(mech, DESIGN_FIELD_T))
        print(f"{r['mechanization']:22s} {r['coils']:5d} {r['magnetometers']:4d} {r['power_w']:8.3f} "
              f"{mech.seed_power_w:6.2f} {r['peak_moment_am2']:9.3f} {mech.seed_peak_moment_am2:6.2f} "
              f"{r['avg_torque_dyne_cm']:10.1f} {closed:8.1f} {r['ripple_pct']:8.2f} "
              f"{closed_form_ripple_pct(mech):8.2f} {r['sweep_deg']:9.1f}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``mechanizations`` verb."""
    text = 'the four SSS spin-mode mechanizations in a rotating 0.3 G field (seed 001 Table 1)'
    p = sub.add_parser("mechanizations", help=text, description=text)
    p.add_argument("--csv", action="store_true", help="print only the CSV table on stdout")
    p.set_defaults(func=cmd_mechanizations)
