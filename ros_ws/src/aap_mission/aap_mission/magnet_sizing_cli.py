"""``acds size-magnet``: minimum-weight magnet + power-supply designs for the AAP Workshop CMG dump (seed 000 §7–§12).

The moments come from typed values (``--m-n-am2 --m-d-am2 --m-m-am2 [--m-o-am2]``), from a dump report
(``--from-report``: the largest M_n, M_d, M_o, M_m over the orbits, as the seed's Table 1 takes them), from
M_m alone with §11's approximation M_n ≈ M_d ≈ 0.78 M_m, or from §12's estimate of M_m (``--h-b-ftlbs`` for a
bias in the orbital plane, ``--iz-minus-ix-slugft2`` for 45° OP). Both structures of the chosen core are
printed (one gimbaled magnet, three fixed orthogonal magnets), in the seed's units with SI beside them.

Declared in the entry-point group ``acds.verbs`` (setup.py), beside the sizing core :mod:`em_driver.magnet_sizing`.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any


def _moments(args: argparse.Namespace) -> tuple[Any, str]:
    """(DumpMoments, where they came from) from the options."""
    from acds_common import units
    from em_driver.magnet_sizing import (
        DumpMoments,
        MagnetSizingError,
        approximate_moments,
        estimate_max_moment_45op_am2,
        estimate_max_moment_am2,
    )

    given = [option for option, value in (('--from-report', args.from_report), ('--h-b-ftlbs', args.h_b_ftlbs),
                                          ('--iz-minus-ix-slugft2', args.iz_minus_ix_slugft2),
                                          ('--m-*-am2', args.m_m_am2 if args.m_m_am2 is not None else
                                           args.m_n_am2 if args.m_n_am2 is not None else args.m_d_am2))
             if value is not None]
    if len(given) > 1:
        raise MagnetSizingError(f'the moments come from one source; got {" and ".join(given)}')
    if args.from_report:
        try:
            rep = json.loads(Path(args.from_report).read_text())
        except (OSError, ValueError) as exc:
            raise MagnetSizingError(f'cannot read dump report {args.from_report}: {exc}') from exc
        missing = [k for k in ('M_m_am2', 'M_o_am2') if not isinstance(rep.get(k), (int, float))]
        if missing:
            raise MagnetSizingError(f'dump report {args.from_report} lacks {", ".join(missing)}')
        m_n, m_d = rep.get('M_n_am2'), rep.get('M_d_am2')
        if rep.get('profile') == 'day_constant':
            # §10 flown: the report's |M| is already the constant day moment; it is sized as it flew (factor 1)
            if args.mode != 'day-constant':
                raise MagnetSizingError(f'dump report {args.from_report} flew day-only dumping at constant |M| '
                                        '(§10): size it with --mode day-constant')
            args.day_constant_factor = 1.0
            return (DumpMoments(m_n or 0.0, m_d or 0.0, rep['M_o_am2'], rep['M_m_am2']),
                    f'dump report {args.from_report} (day-only dumping flown at constant |M|, §10)')
        if args.mode == 'day-night' and (m_n is None or m_d is None):
            raise MagnetSizingError(f'dump report {args.from_report} has no orbital '
                                    f'{"night" if m_n is None else "day"} (M_n_am2/M_d_am2 null: eclipse off?); '
                                    'day-and-night sizing needs both')
        return DumpMoments(m_n or 0.0, m_d or 0.0, rep['M_o_am2'], rep['M_m_am2']), f'dump report {args.from_report}'
    if args.h_b_ftlbs is not None:
        m_m = estimate_max_moment_am2(units.ftlbs_to_nms(args.h_b_ftlbs))
        return approximate_moments(m_m), f'§12 M_m = 12.5 H_b (H_b = {args.h_b_ftlbs:g} ft-lb-sec), §11 M_n = M_d = 0.78 M_m'
    if args.iz_minus_ix_slugft2 is not None:
        m_m = estimate_max_moment_45op_am2(units.slugft2_to_kgm2(args.iz_minus_ix_slugft2))
        return approximate_moments(m_m), (f'§12 M_m = 0.0665 (I_z - I_x) (I_z - I_x = {args.iz_minus_ix_slugft2:g} '
                                          'slug-ft²), §11 M_n = M_d = 0.78 M_m')
    if args.m_m_am2 is None:
        raise MagnetSizingError('give --m-m-am2 (with --m-n-am2 --m-d-am2, or alone for the §11 approximation), '
                                '--from-report, --h-b-ftlbs or --iz-minus-ix-slugft2')
    if args.m_n_am2 is None and args.m_d_am2 is None:
        return approximate_moments(args.m_m_am2), '§11 approximation M_n = M_d = M_o = 0.78 M_m (typed M_m)'
    if args.m_n_am2 is None or args.m_d_am2 is None:
        raise MagnetSizingError('give both --m-n-am2 and --m-d-am2 (or neither, for the §11 approximation)')
    if args.m_o_am2 is None:
        return DumpMoments(args.m_n_am2, args.m_d_am2, 0.0, args.m_m_am2), 'typed (M_o not given, shown as 0)'
    return DumpMoments(args.m_n_am2, args.m_d_am2, args.m_o_am2, args.m_m_am2), 'typed'


def _rows(d: Any, b0_t: float, diameter_m: float | None) -> list[tuple[str, float | None, str]]:
    """(label, value in seed units, SI note) for one design."""
    from acds_common import units

    lb, inch, ft = units.LB_KG, units.INCH_M, units.FOOT_M
    rows: list[tuple[str, float | None, str]] = [
        ('Equivalent moment M_e, A·m²·(lb/W)^½', d.equivalent_moment / math.sqrt(lb), ''),
        ('Maximum amp-turns (per coil)', d.ampere_turns_a, ''),
        ('Turns × conductor area, in.² (per coil)', d.turns_area_m2 / inch ** 2, f'{d.turns_area_m2 * 1e6:.4g} mm²'),
        ('Maximum power, W (total)', d.max_power_w, ''),
        ('Conductor weight, lbs (total)', d.conductor_kg / lb, f'{d.conductor_kg:.4g} kg'),
        ('Power supply weight, lbs', d.power_supply_kg / lb, f'{d.power_supply_kg:.4g} kg'),
        ('  battery, lbs', d.battery_kg / lb, ''),
        ('  solar array, lbs', d.solar_array_kg / lb, ''),
        ('  control amplifier, lbs', d.amplifier_kg / lb, ''),
    ]
    if d.core == 'iron':
        rows += [('Iron core length, ft', d.core_length_m / ft, f'{d.core_length_m:.4g} m'),
                 ('Iron core diameter, in.', d.core_diameter_m / inch, f'{d.core_diameter_m * 100:.4g} cm'),
                 ('Iron core weight, lbs (total)', d.core_kg / lb, f'{d.core_kg:.4g} kg')]
    rows += [('Total weight, lbs', d.total_kg / lb, f'{d.total_kg:.4g} kg'),
             ('Current density, A/in.²', d.current_density_a_m2 * inch ** 2, f'{d.current_density_a_m2 * 1e-6:.3g} A/mm²')]
    if d.core == 'air' and diameter_m is not None:
        rows.append(('Field at coil centre, % of B_0', 100.0 * d.centre_field_t() / b0_t,
                     f'{d.centre_field_t() * 1e6:.4g} µT'))
        for k in (2, 3, 4):
            rows.append((f'Field on axis at {k} diameters, % of B_0', 100.0 * d.axis_field_t(k * diameter_m) / b0_t, ''))
    return rows


def _fmt(x: float | None) -> str:
    if x is None:
        return '—'
    return f'{x:,.4g}' if abs(x) < 1e5 else f'{x:,.0f}'


def cmd_size_magnet(args: argparse.Namespace) -> int:
    """Print (and optionally write as JSON) the designs for both structures of the chosen core."""
    from acds_cli.arguments import check_output_file
    from acds_common import units
    from em_driver import magnet_sizing as ms

    if args.json:
        check_output_file('--json', Path(args.json))
    try:
        moments, source = _moments(args)
        ps = ms.with_power_supply_orbit(ms.SEED_POWER_SUPPLY, args.altitude_nmi * units.NMI_M, args.daylight_deg)
        conductor = {'copper': ms.COPPER, 'aluminium': ms.ALUMINIUM}[args.conductor]
        iron = ms.PERMALLOY_45_CHART[args.q]
        if args.b_core_t is not None:
            iron = replace(iron, b_max_t=args.b_core_t)
        diameter = args.diameter_ft * units.FOOT_M
        designs = {s: ms.design(moments, args.mode, args.core, s, coil_diameter_m=diameter, conductor=conductor,
                                iron=iron, ps=ps, day_constant_factor=args.day_constant_factor)
                   for s in ms.STRUCTURES}
    except ms.MagnetSizingError as exc:
        print(f'acds size-magnet: {exc}', file=sys.stderr)
        return 2
    lb = units.LB_KG
    print(f'Magnet sizing (seed 000 §7–§12): {args.mode} dump, {args.core} core, {conductor.name} conductor')
    print(f'  moments from {source}:')
    print(f'    M_n {_fmt(moments.m_n_am2)}  M_d {_fmt(moments.m_d_am2)}  M_o {_fmt(moments.m_o_am2)}  '
          f'M_m {_fmt(moments.m_m_am2)} A·m²')
    if args.mode == 'day-constant':
        print(f'    day dump at constant |M| = {args.day_constant_factor:g} × M_m = '
              f'{_fmt(args.day_constant_factor * moments.m_m_am2)} A·m² (§10; M_n, M_d, M_o not used)')
    print(f'  power supply (Appendix C): T_n {ps.night_s / 60:.1f} min, T_d {ps.day_s / 60:.1f} min '
          f'({args.altitude_nmi:g} nmi, {args.daylight_deg:g}° day)')
    for s in ms.STRUCTURES:
        k_n, k_d, k_a = ms.power_supply_constants(ps, s)
        print(f'    {s:16s} K_n {k_n / lb:.4f}  K_d {k_d / lb:.4f}  K_a {k_a / lb:.2f} lb/W')
    if args.core == 'air':
        print(f'  air coils {args.diameter_ft:g} ft diameter; B_0 = {ms.SEED_B0_T * 1e6:.0f} µT (App. A, 220 nmi)')
    else:
        print(f'  iron core {iron.name}: α {iron.alpha}, D {iron.d_factor}, B {iron.b_max_t:g} Wb/m², '
              f'σ_i {iron.density_kg_m3 * units.INCH_M ** 3 / lb:.3f} lb/in.³')
    rows = {s: _rows(d, ms.SEED_B0_T, diameter if args.core == 'air' else None) for s, d in designs.items()}
    width = max(len(label) for label, _, _ in rows['gimbaled'])
    print(f'\n  {"":{width}s}  {"gimbaled":>12s}  {"three orthogonal":>16s}   SI (three orthogonal)')
    for (label, g, _), (_, t, si) in zip(rows['gimbaled'], rows['three_orthogonal'], strict=True):
        print(f'  {label:{width}s}  {_fmt(g):>12s}  {_fmt(t):>16s}   {si}')
    print('\n  weights exclude insulation and winding forms (§7); totals over the three coils where there are three')
    if args.wire_area_in2 is not None:
        print(f'  winding with {args.wire_area_in2:g} in.² conductor (§8), per coil:')
        for s, d in designs.items():
            try:
                w = ms.wind(d, args.wire_area_in2 * units.INCH_M ** 2, conductor)
            except ms.MagnetSizingError as exc:
                print(f'acds size-magnet: {exc}', file=sys.stderr)
                return 2
            print(f'    {s:16s} {w.turns:.1f} turns, {w.max_current_a:.3g} A max, {w.resistance_ohm:.3g} ohm, '
                  f'{w.max_voltage_v:.3g} V max')
    if args.json:
        from acds_runtime.summary import write_summary_json

        out = {'mode': args.mode, 'core': args.core, 'conductor': conductor.name, 'moments_source': source,
               'M_n_am2': moments.m_n_am2, 'M_d_am2': moments.m_d_am2, 'M_o_am2': moments.m_o_am2,
               'M_m_am2': moments.m_m_am2, 'night_s': ps.night_s, 'day_s': ps.day_s,
               'designs': {s: {label: value for label, value, _ in r} for s, r in rows.items()}}
        write_summary_json(Path(args.json), out)
        print(f'wrote {args.json}', file=sys.stderr)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``size-magnet`` verb."""
    from acds_cli.arguments import positive_number

    p = sub.add_parser('size-magnet', help='minimum-weight magnet + power-supply design for the CMG dump (seed 000)',
                       description=__doc__.split('\n\n')[1])
    p.add_argument('--mode', choices=['day-night', 'day-constant'], required=True,
                   help='continuous dumping (§7, App. D) or day-only at constant |M| (§10, App. E)')
    p.add_argument('--core', choices=['air', 'iron'], required=True, help='air coils or iron-core coils')
    for name, text in (('n', 'rms |M| over orbital night'), ('d', 'rms |M| over orbital day'),
                       ('o', 'rms |M| over the orbit (reported only)'), ('m', 'maximum |M|')):
        p.add_argument(f'--m-{name}-am2', type=positive_number if name == 'm' else float,
                       help=f'M_{name}: {text}, A·m²')
    p.add_argument('--from-report', metavar='DUMP_REPORT.json', help='take M_n, M_d, M_o, M_m from a dump report')
    p.add_argument('--h-b-ftlbs', type=positive_number, help='§12 estimate M_m = 12.5 H_b for a bias H_b in the orbital plane')
    p.add_argument('--iz-minus-ix-slugft2', type=positive_number, help='§12 estimate for 45° OP: M_m = 0.0665 (I_z - I_x)')
    p.add_argument('--diameter-ft', type=positive_number, default=20.0, help='air coil diameter, ft (default 20, §8)')
    p.add_argument('--conductor', choices=['copper', 'aluminium'], default='copper', help='coil conductor')
    p.add_argument('--q', type=int, choices=[20, 30, 40], default=30, help='iron core length/diameter (§7 chart)')
    p.add_argument('--b-core-t', type=positive_number, help='iron core maximum flux density, Wb/m² (default 1, §8)')
    p.add_argument('--day-constant-factor', type=positive_number, default=1.3,
                   help='day-constant |M| as a multiple of the day-and-night M_m (default 1.3, §10)')
    p.add_argument('--altitude-nmi', type=positive_number, default=220.0,
                   help='circular orbit altitude for T_n, T_d (default 220)')
    p.add_argument('--daylight-deg', type=float, default=220.0, help='orbital daylight arc, degrees (default 220)')
    p.add_argument('--wire-area-in2', type=positive_number,
                   help='also wind each coil with this conductor area, in.² (§8: #10 wire is 0.008155)')
    p.add_argument('--json', metavar='PATH', help='write the inputs and both designs as JSON (seed units)')
    p.set_defaults(func=cmd_size_magnet)
