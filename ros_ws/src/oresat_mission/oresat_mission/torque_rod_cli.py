"""``acds design-torque-rod``: size a CubeSat torque rod with the seed-003 procedure (em_driver.torque_rod_design).

Prints every design quantity with its unit and whether the core saturates at full current;
``--json PATH`` writes the design as one flat JSON object (units in the keys), the record a
scenario will load as its rods. An infeasible request exits 1 naming the binding constraint.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def _envelope_mm(text: str) -> tuple[float, float, float]:
    try:
        parts = tuple(float(x) for x in text.lower().split('x'))
    except ValueError:
        parts = ()
    if len(parts) != 3 or not all(p > 0.0 for p in parts):
        raise argparse.ArgumentTypeError(f'envelope must be AxBxC in mm (e.g. 35x35x25), got {text!r}')
    return parts  # type: ignore[return-value]


def _gauge(text: str) -> int:
    """``--awg``: a whole wire gauge the diameter formula covers (``em_driver.torque_rod.AWG_GAUGES``)."""
    from em_driver.torque_rod import AWG_GAUGES

    value = int(text) if text.strip().lstrip('-').isdigit() else None
    if value is None or value not in AWG_GAUGES:
        raise argparse.ArgumentTypeError(f'must be a whole wire gauge {AWG_GAUGES[0]}…{AWG_GAUGES[-1]}, got {text}')
    return value


def _report(d: dict) -> list[str]:
    """The design as aligned lines, seed units."""
    rows = [
        ('core material', f"{d['core']} (µ_r {d['core_relative_permeability']:g}, B_sat {d['core_saturation_t']:g} T)"),
        ('core length', f"{d['core_length_mm']:.3f} mm"),
        ('core radius', f"{d['core_radius_mm']:.3f} mm"),
        ('outer diameter (over winding)', f"{d['outer_diameter_mm']:.2f} mm"),
        ('wire', f"AWG {d['awg']}, {d['wire_insulated_diameter_mm']:.4f} mm insulated, {d['wire_ohm_per_m']:.4f} Ω/m"),
        ('windings (redundant, bifilar)', f"{d['windings']}"),
        ('wire length per winding', f"{d['wire_length_per_winding_m']:.2f} m"),
        ('turns per winding', f"{d['turns']:.0f}"),
        ('layers (whole winding)', f"{d['layers']:.1f}"),
        ('resistance per winding', f"{d['resistance_ohm']:.2f} Ω (+ {d['bridge_resistance_ohm']:g} Ω bridge)"),
        ('inductance per winding', f"{d['inductance_h'] * 1e3:.2f} mH"),
        ('time constant τ = L/R', f"{d['tau_s'] * 1e3:.3f} ms"),
        ('voltage', f"{d['voltage_v']:g} V"),
        ('full current', f"{d['current_a'] * 1e3:.2f} mA"),
        ('power at full current', f"{d['power_w']:.4f} W"),
        ('demagnetising factor N_d', f"{d['n_d']:.5f} (seed ref. [4] formula: {d['n_d_seed_formula']:.5f})"),
        ('apparent susceptibility', f"{d['apparent_susceptibility']:.2f}"),
        ('core flux density at full current', f"{d['flux_density_t']:.3f} T"),
        ('core saturates at full current', 'yes' if d['core_saturates'] else
         f"no (saturation at {d['saturation_current_a'] * 1e3:.2f} mA)"),
        ('dipole moment at full current', f"{d['moment_am2']:.4f} A·m² (required {d['moment_required_am2']:g})"),
        ('mass', f"{d['mass_g']:.2f} g (wire {d['wire_mass_g']:.2f} g, core {d['core_mass_g']:.2f} g)"),
        ('search', f"{d['search_rounds']} refinement rounds, {d['evaluations']} evaluations"),
    ]
    width = max(len(k) for k, _ in rows)
    return [f'  {k:<{width}}  {v}' for k, v in rows]


def cmd_design(args: argparse.Namespace) -> int:
    """Design the rod, print it, optionally write the JSON record."""
    from acds_cli.arguments import UsageError, check_output_file
    from em_driver.bridge_switch import EmDriverError
    from em_driver.torque_rod import HEAVY_BUILD_INCREMENT_MIL
    from em_driver.torque_rod_design import DesignRequest, InfeasibleDesignError, design_torque_rod
    if args.insulation_mm is None and args.awg not in HEAVY_BUILD_INCREMENT_MIL:
        raise UsageError(f'--awg {args.awg}: the heavy-build insulation table covers AWG {min(HEAVY_BUILD_INCREMENT_MIL)}'
                         f'–{max(HEAVY_BUILD_INCREMENT_MIL)}; give --insulation-mm (the enamel build on the diameter) '
                         'for another gauge')
    if args.json:
        check_output_file('--json', Path(args.json))
    try:
        req = DesignRequest(mass_max_kg=args.mass_g * 1e-3, power_max_w=args.power_w, voltage_v=args.voltage,
                            moment_min_am2=args.moment_am2, envelope_m=tuple(x * 1e-3 for x in args.envelope_mm),
                            core=args.core, awg=args.awg, windings=args.windings,
                            bridge_resistance_ohm=args.bridge_ohm,
                            insulation_build_m=None if args.insulation_mm is None else args.insulation_mm * 1e-3,
                            allow_saturation=args.allow_saturation, min_core_radius_m=args.min_core_radius_mm * 1e-3)
        design = design_torque_rod(req)
    except InfeasibleDesignError as exc:
        print(f'[design-torque-rod] infeasible: {exc}', file=sys.stderr)
        return 1
    except EmDriverError as exc:
        print(f'[design-torque-rod] bad request: {exc}', file=sys.stderr)
        return 2
    record = design.to_json_dict()
    print(f'torque rod: minimum mass for {args.moment_am2:g} A·m² within {args.mass_g:g} g, {args.power_w:g} W, '
          f'{args.voltage:g} V, envelope {"x".join(f"{x:g}" for x in args.envelope_mm)} mm')
    print('\n'.join(_report(record)))
    if args.json:
        from acds_runtime.summary import write_summary_json

        write_summary_json(Path(args.json), record)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``design-torque-rod`` verb."""
    from acds_cli.arguments import non_negative_number, positive_number

    text = 'size a CubeSat torque rod (seed 003 design procedure as a bounded minimum-mass search)'
    p = sub.add_parser('design-torque-rod', help=text, description=text + '. Defaults: the seed 003 constraints.')
    p.add_argument('--mass-g', type=positive_number, default=100.0, help='mass limit per rod, g (default 100)')
    p.add_argument('--power-w', type=positive_number, default=0.5, help='power per rod at full current, W (default 0.5)')
    p.add_argument('--voltage', type=positive_number, default=7.2, help='bus voltage, V (default 7.2)')
    p.add_argument('--moment-am2', type=positive_number, default=0.1552, help='required dipole, A·m² (default 0.1552)')
    p.add_argument('--envelope-mm', type=_envelope_mm, default=(35.0, 35.0, 25.0),
                   help='envelope AxBxC, mm (default 35x35x25)')
    p.add_argument('--core', choices=('permalloy', 'permendur', 'ck30'), default='permalloy',
                   help='core material (default permalloy)')
    p.add_argument('--awg', type=_gauge, default=36, help='wire gauge, AWG (default 36; the heavy-build enamel is '
                   'tabulated for 30–40, give --insulation-mm for another)')
    p.add_argument('--windings', type=int, choices=(1, 2), default=2, help='redundant windings (default 2)')
    p.add_argument('--bridge-ohm', type=non_negative_number, default=0.36,
                   help='H-bridge resistance in the loop, Ω (default 0.36)')
    p.add_argument('--insulation-mm', type=positive_number, help='enamel build on the diameter, mm (default: heavy build)')
    p.add_argument('--min-core-radius-mm', type=positive_number, default=0.5, help='smallest core radius, mm (default 0.5)')
    p.add_argument('--allow-saturation', action='store_true',
                   help='accept a core that saturates at full current (its saturated moment must meet the requirement)')
    p.add_argument('--json', metavar='PATH', help='write the design as one JSON object')
    p.set_defaults(func=cmd_design)
