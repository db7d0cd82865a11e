"""``acds dump-report``: the AAP Workshop CMG dump report (seed 000 §5) of a bag or of a scenario's run, and the k and
M_m studies (``--k-sweep``, ``--mm-sweep``). Declared in the entry-point group ``acds.verbs`` (setup.py), beside the
Workshop computer's dump law and report (:mod:`acds_controller.cmg_dump`, :mod:`acds_controller.aap_summary`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

DUMP_REPORT_DOC = """The dump report (seed 000 §5, Tables 1 and 2) of an AAP Workshop run: per orbit M_n, M_d, M_o (rms |M|
over orbital night, day, the whole orbit), M_m (max |M|), H_s as sampled, |ΔH_s|, the bias the CMGs took,
the sampled loop's gains (eigenvalues of k·W) and the minimum-energy M_o on the orbit's own field; then the
largest of each over the orbits, and one warning line when some orbit's loop gain leaves (0, 2) (the loop
cannot converge). From a bag it reads the bag (read-only); from a scenario it first runs it with the direct
engine, recording a bag into --out. Plots: |M|(t) and H_s per orbit (PNG, in --out). --k-sweep (§5's k
study) and --mm-sweep (§12's M_m estimation) run a scenario many times instead (no bag)."""


def cmd_dump_report(args: argparse.Namespace) -> int:
    """Print the dump report of a bag or of a scenario's direct-engine run; write its JSON and plots."""
    from acds_cli.arguments import check_output_file
    from acds_common.scenario import ScenarioError
    from acds_controller.aap_summary import print_tables
    from acds_runtime.bag.writer import BagError, check_out_dir, check_target
    from acds_runtime.launcher import LaunchError
    from acds_runtime.summary import write_summary_json

    from aap_mission.dump_report import check_workshop, plot_dump, report_from_bag

    source = Path(args.source)
    is_bag = source.is_dir() or source.suffix in ('.mcap', '.db3')
    if args.k_sweep or args.mm_sweep:
        if is_bag:
            print('acds dump-report: --k-sweep and --mm-sweep run a scenario, not a recorded bag', file=sys.stderr)
            return 2
        from aap_mission.dump_study_cli import cmd_study
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
            from acds_cli.verbs.run import Progress
            from acds_cli.workspace import new_run_dir, workspace
            from acds_runtime.direct import DirectRun
            from acds_runtime.preflight import preflight

            from aap_mission.dump_study import scenario_with_sets

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
    """Add the ``dump-report`` verb."""
    from acds_cli.arguments import step_count

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
