"""``acds size-magnet`` and ``acds dump-report``: the AAP Workshop CMG dump (seed 000).

``size-magnet``: minimum-weight magnet + power-supply designs (seed 000 §7–§12).

The moments come from typed values (``--m-n-am2 --m-d-am2 --m-m-am2 [--m-o-am2]``), from a dump report
(``--from-report``: the largest M_n, M_d, M_o, M_m over the orbits, as the seed's Table 1 takes them), from
M_m alone with §11's approximation M_n ≈ M_d ≈ 0.78 M_m, or from §12's estimate of M_m (``--h-b-ftlbs`` for a
bias in the orbital plane, ``--iz-minus-ix-slugft2`` for 45° OP). Both structures of the chosen core are
printed (one gimbaled magnet, three fixed orthogonal magnets), in the seed's units with SI beside them.
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
    from acds_common import units
    from em_driver import magnet_sizing as ms

    from ..arguments import check_output_file

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


DUMP_REPORT_DOC = """The dump report (seed 000 §5, Tables 1 and 2) of an AAP Workshop run: per orbit M_n, M_d, M_o (rms |M|
over orbital night, day, the whole orbit), M_m (max |M|), H_s as sampled, |ΔH_s|, the bias the CMGs took,
the sampled loop's gains (eigenvalues of k·W) and the minimum-energy M_o on the orbit's own field; then the
largest of each over the orbits, and one warning line when some orbit's loop gain leaves (0, 2) (the loop
cannot converge). From a bag it reads the bag (read-only); from a scenario it first runs it with the direct
engine, recording a bag into --out. Plots: |M|(t) and H_s per orbit (PNG, in --out). --k-sweep (§5's k
study) and --mm-sweep (§12's M_m estimation) run a scenario many times instead (no bag)."""


def cmd_dump_report(args: argparse.Namespace) -> int:
    """Print the dump report of a bag or of a scenario's direct-engine run; write its JSON and plots."""
    from acds_common.scenario import ScenarioError
    from acds_controller.aap_summary import print_tables
    from acds_runtime.bag.writer import BagError, check_out_dir, check_target
    from acds_runtime.launcher import LaunchError
    from acds_runtime.summary import write_summary_json

    from ..arguments import check_output_file
    from ..bag.dump_report import check_workshop, plot_dump, report_from_bag

    source = Path(args.source)
    is_bag = source.is_dir() or source.suffix in ('.mcap', '.db3')
    if args.k_sweep or args.mm_sweep:
        if is_bag:
            print('acds dump-report: --k-sweep and --mm-sweep run a scenario, not a recorded bag', file=sys.stderr)
            return 2
        from ..dump_study import cmd_study
        return cmd_study(args)
    try:
        if args.json:
            check_output_file('--json', Path(args.json))
        if is_bag:
            if args.set or args.steps:
                raise ScenarioError('--set and --steps apply to a scenario run, not to a recorded bag')
            bag_path = source
            out = Path(args.out) if args.out else (source if source.is_dir() else source.parent).parent / 'plots'
            check_out_dir(out)
        else:
            from acds_runtime.direct import DirectRun
            from acds_runtime.dump_study import scenario_with_sets
            from acds_runtime.preflight import preflight

            from ..workspace import new_run_dir, workspace
            from .run import Progress

            scenario = scenario_with_sets(args.source, args.set or [])
            check_workshop(scenario)
            preflight(scenario)
            if args.out:
                out = Path(args.out)
                check_out_dir(out)
            else:
                check_out_dir(workspace() / 'runs')
                out = new_run_dir(f'{scenario.name}_dump')
            bag_path = out / 'bag'
            check_target(bag_path)
            run = DirectRun(scenario, steps=args.steps, record=bag_path, progress=Progress(scenario.control_period_s))
            print(f'[acds] {scenario.name}: {run.steps} steps of {scenario.control_period_s} s with the direct engine, '
                  f'recording {bag_path}', file=sys.stderr, flush=True)
            result = run.run()
            print(f'[acds] run done in {result.wall_seconds:.1f} s wall', file=sys.stderr)
        summary, series, scenario = report_from_bag(bag_path)
        plots = plot_dump(summary['dump_report'], series, scenario, out)
    except (ScenarioError, BagError, LaunchError) as exc:
        print(f'acds dump-report: {exc}', file=sys.stderr)
        return 2
    print(f'AAP Workshop dump report: {scenario.name} (bag {bag_path})')
    print_tables(summary)
    if args.json:
        write_summary_json(Path(args.json), {'scenario': scenario.name, 'bag': str(bag_path), **summary['dump_report']})
        print(f'wrote {args.json}', file=sys.stderr)
    for p in plots:
        print(f'[acds] plot {p}', file=sys.stderr)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``size-magnet`` and ``dump-report`` verbs."""
    from ..arguments import positive_number, step_count

    p = sub.add_parser('dump-report', help='AAP Workshop CMG dump report of a bag or a scenario (seed 000 §5)',
                       description=DUMP_REPORT_DOC)
    p.add_argument('source', metavar='BAG|SCENARIO', help='a recorded bag (folder or .mcap/.db3) or a scenario')
    p.add_argument('--json', metavar='PATH', help='write the report (JSON keys M_n_am2, M_d_am2, M_o_am2, M_m_am2, '
                   'delta_H_s_ftlbs, min_energy_M_o_am2: the largest over the orbits; loop_gain_min, loop_gain_max, '
                   'loop_converges; per_orbit)')
    p.add_argument('--out', metavar='DIR', help='folder for the plots (and, from a scenario, the bag); default '
                   'runs/<scenario>_dump_<time> (a bag: plots/ beside it)')
    p.add_argument('--steps', type=step_count, help='scenario only: number of control steps (default: its duration)')
    p.add_argument('--set', action='append', metavar='SECTION.KEY=VALUE',
                   help='scenario only: override a scenario key, e.g. controller.dump_h_s_init=measured (H_s from '
                        'zero) or controller.dump_gain_am2_per_ftlbs_t=3e6; repeatable')
    p.add_argument('--k-sweep', metavar='A:B:N', help='scenario only: the k study (§5): N values of k (seed units) from '
                   'A to B, each flown from the §5 initialisation and from H_s = 0; table, k_sweep.png, --json rows')
    p.add_argument('--mm-sweep', metavar='KIND:A:B:N', help='scenario only: the M_m estimation sweep (§12): KIND hb '
                   '(|H_b|, ft-lb-sec, POP), iy_minus_iz (I_y − I_z, slug-ft², IOP, Fig. 7) or iz_minus_ix (45° OP); '
                   'table with the fitted slope, mm_sweep_KIND.png, --json rows')
    p.set_defaults(func=cmd_dump_report)

    p = sub.add_parser('size-magnet', help='minimum-weight magnet + power-supply design for the CMG dump (seed 000)',
                       description=__doc__.split('\n\n')[2])
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
