"""``scripts/acds``: one user entry, one verb per job. Every verb has ``--help``."""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from acds_common.scenario import MAX_STEPS, ScenarioError, list_scenarios, load_scenario

from .arguments import (
    OneLineParser,
    UsageError,
    add_foxglove_options,
    check_output_dir,
    check_output_file,
    positive_int,
    positive_minutes,
    real_time_factor,
    step_count,
)
from .verbs.montecarlo import add_sample_options, sample_for_run

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_SCENARIO = 'heao_b_acquisition'


class Progress:
    """One progress line: sim time / total and the real-time factor (in place on a TTY, else every 10 % or 5 s)."""

    def __init__(self, dt_s: float) -> None:
        self.dt_s = dt_s
        self.tty = sys.stderr.isatty()
        self.last_pct = -10
        self.last_print = 0.0

    def __call__(self, k: int, total: int, wall_s: float) -> None:
        pct = 100.0 * k / total
        now = time.monotonic()
        if self.tty and now - self.last_print < 0.2 and k < total:
            return
        if not self.tty and pct < self.last_pct + 10 and now - self.last_print < 5.0 and k < total:
            return
        self.last_print, self.last_pct = now, pct
        sim_min = k * self.dt_s / 60
        rtf = k * self.dt_s / wall_s if wall_s > 0 else 0.0
        line = (f'[progress] sim {sim_min:7.1f} / {total * self.dt_s / 60:.1f} min ({pct:5.1f} %)  '
                f'step {k}/{total}  real-time factor {rtf:,.0f}x')
        print(('\r' + line) if self.tty else line, end='' if self.tty and k < total else '\n',
              file=sys.stderr, flush=True)


def _announce_live(port: int, host: str) -> None:
    print(f'[acds] Foxglove live view on ws://{host}:{port} (Foxglove: Open connection → Foxglove WebSocket; '
          f'layout {ROOT / "foxglove" / "acds_layout.json"})', file=sys.stderr, flush=True)


def cmd_run(args: argparse.Namespace) -> int:
    """Run a scenario through the full process graph (or the direct engine) and print its summary."""
    from acds_runtime.direct import DirectRun
    from acds_runtime.launcher import GraphRun, LaunchError
    from acds_runtime.preflight import preflight
    from acds_runtime.report import format_summary
    from acds_runtime.run_folder import create_run_folder
    from acds_runtime.summary import print_tables, write_summary_json

    scenario, sample_text = sample_for_run(load_scenario(args.scenario or DEFAULT_SCENARIO), args)
    preflight(scenario)
    steps = args.steps
    if args.until_min is not None:
        steps = max(1, round(args.until_min * 60 / scenario.control_period_s))
        if steps > MAX_STEPS:
            raise UsageError(f'--until-min {args.until_min:g}: {steps:,} steps of {scenario.control_period_s} s, '
                             f'more than the {MAX_STEPS:,} a run may have')
    direct = args.engine == 'direct'
    if direct and args.rtf:
        raise UsageError('--rtf paces the process graph\'s clock; the direct engine has none (use --engine graph)')
    check_output_dir('--run-dir' if args.run_dir else 'run folder', Path(args.run_dir or ROOT / 'runs'))
    if args.summary_json:
        check_output_file('--summary-json', Path(args.summary_json))
    # The default folder is created exclusively (a run started in the same second gets its own).
    run_dir = Path(args.run_dir) if args.run_dir else create_run_folder(ROOT / 'runs', scenario.name)
    if sample_text is not None:  # the drawn scenario with how it was drawn (the launcher adds scenario.yaml)
        run_dir.mkdir(parents=True, exist_ok=True)
        (run_dir / 'sample.yaml').write_text(sample_text)
    echo = (lambda line: None) if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    bag = None if args.no_record else Path(args.record) if args.record else run_dir / 'bag'
    if bag is not None:
        from acds_runtime.bag.writer import BagError, check_target
        try:
            check_target(bag, args.storage, args.compression)
        except BagError as exc:
            raise UsageError(str(exc)) from None
    live = None
    if args.foxglove is not None:
        if scenario.formation:
            raise UsageError('--foxglove: the live view serves one spacecraft; a formation is not served yet (record '
                             'it and open the bag in Foxglove)')
        from acds_runtime.foxglove_bridge import live_view
        live = live_view(args.foxglove, args.foxglove_host)
    progress = Progress(scenario.control_period_s)
    options = dict(record=bag, record_storage=args.storage, record_compression=args.compression, live=live)
    if direct:
        run_dir.mkdir(parents=True, exist_ok=True)
        engine = DirectRun(scenario, steps=steps, echo=echo, progress=progress, **options)
    else:
        engine = GraphRun(scenario, run_dir, steps=steps, rtf=args.rtf, echo=echo, progress=progress, **options)
    print(f'[acds] scenario {scenario.name}: {engine.steps} steps of {scenario.control_period_s} s '
          f'({engine.steps * scenario.control_period_s / 60:.1f} min sim), '
          + ('direct engine (one process, no DDS)' if direct else f'nodes {", ".join(scenario.get("", "nodes"))}')
          + f'; run folder {run_dir}', file=sys.stderr, flush=True)
    try:
        if direct:
            if engine.live_sink is not None:
                _announce_live(engine.live_sink.port, args.foxglove_host)
            summary = engine.run().summary
        else:
            with engine:
                print(f'[acds] ROS domain {engine.lease.domain_id}' + (f'; recording into {bag}' if bag else ''),
                      file=sys.stderr, flush=True)
                if engine.live_sink is not None:
                    _announce_live(engine.live_sink.port, args.foxglove_host)
                result = engine.wait()
                for warning in result.warnings:
                    print(f'[acds] WARNING: {warning}', file=sys.stderr)
                summary = result.summary
    except LaunchError as exc:
        print(f'[acds] run failed: {exc}', file=sys.stderr)
        return 1
    except KeyboardInterrupt as exc:
        signum = getattr(exc, 'signum', signal.SIGINT)
        stopped = 'the run stopped' if direct else 'all nodes stopped'
        print(f'\n[acds] stopped by {signal.Signals(signum).name}: {stopped}', file=sys.stderr)
        return 128 + signum
    print('\n' + format_summary(summary))
    print_tables(summary)
    if args.summary_json:
        write_summary_json(Path(args.summary_json), summary)
    if bag is not None:
        from .bag.plots import make_plots
        plots = make_plots(bag, bag.parent / 'plots')
        print(f'[acds] bag {bag} (./scripts/acds info {bag}); {len(plots)} plots in {bag.parent / "plots"}',
              file=sys.stderr)
    return 0


def cmd_scenarios(_args: argparse.Namespace) -> int:
    """List the shipped scenarios."""
    for name, description in list_scenarios():
        print(f'{name:32s} {description}')
    return 0


def cmd_test(args: argparse.Namespace) -> int:
    """Lint, then run the whole test suite."""
    env = dict(os.environ)
    lint = subprocess.run([sys.executable, '-m', 'ruff', 'check', '--output-format', 'concise', str(ROOT)],
                          cwd=ROOT, check=False)
    if lint.returncode != 0:
        print('[acds] lint failed (ruff): fix the findings above', file=sys.stderr)
        return lint.returncode
    cmd = [sys.executable, '-m', 'pytest', '-q', '-n', str(args.jobs), *args.pytest_args]
    return subprocess.run(cmd, cwd=ROOT, env=env, check=False).returncode


def cmd_bench(args: argparse.Namespace) -> int:
    """Benchmark: graph lockstep steps/s, a bare rclpy chain with the same hops, core-only steps/s."""
    from .bench import main as bench_main
    return bench_main(args)


def build_parser() -> argparse.ArgumentParser:
    """The command-line surface (later verbs register here too)."""
    parser = OneLineParser(prog='acds', description='ACDS emulator: HEAO wheels+magnetics, SSS magnetic control.')
    sub = parser.add_subparsers(dest='verb', metavar='VERB', required=True)

    p = sub.add_parser('run', help='run a scenario through the full node graph (default: the main job)',
                       description='Run SCENARIO (a shipped name or a YAML path) through the full process graph '
                                   '(or --engine direct).')
    p.add_argument('scenario', nargs='?', help=f'scenario name or path (default {DEFAULT_SCENARIO})')
    g = p.add_mutually_exclusive_group()
    g.add_argument('--steps', type=step_count, help='number of control steps (default: the scenario duration)')
    g.add_argument('--until-min', type=positive_minutes, help='run until this sim time, minutes (> 0)')
    p.add_argument('--summary-json', metavar='PATH',
                   help='write the summary as one JSON object (non-finite numbers as null)')
    g = p.add_mutually_exclusive_group()
    g.add_argument('--record', metavar='PATH', help='record the run into this rosbag2 bag (default RUN_DIR/bag)')
    g.add_argument('--no-record', action='store_true', help="don't record a bag (nor plot it)")
    from .verbs.bag import add_bag_options
    add_bag_options(p)
    p.add_argument('--rtf', type=real_time_factor, default=0.0,
                   help='pace at this real-time factor (default 0: as fast as possible)')
    p.add_argument('--run-dir', help='run folder (default runs/<scenario>_<time>); checked writable before the run')
    p.add_argument('--quiet', action='store_true', help="don't forward the nodes' output")
    add_sample_options(p, run=True)
    p.add_argument('--engine', choices=('graph', 'direct'), default='graph',
                   help='graph: one process per node over DDS (default); direct: the same steppers in this process, '
                        'no DDS — bit-identical data, faster')
    add_foxglove_options(p, 'the running graph')
    p.set_defaults(func=cmd_run)

    p = sub.add_parser('scenarios', help='list the shipped scenarios', description='List the shipped scenarios.')
    p.set_defaults(func=cmd_scenarios)

    p = sub.add_parser('test', help='run the whole test suite (lint + pytest)',
                       description='Lint (ruff) and run every test (pytest). Extra args go to pytest.')
    p.add_argument('--jobs', '-j', type=positive_int, default=2, help='parallel test workers (default 2)')
    p.add_argument('pytest_args', nargs=argparse.REMAINDER, help='passed to pytest')
    p.set_defaults(func=cmd_test)

    p = sub.add_parser('setup', help='only set up the virtual environment (idempotent)',
                       description='Create or refresh .venv (done by scripts/acds before any verb).')
    p.set_defaults(func=lambda _a: 0)

    p = sub.add_parser('bench', help='benchmark the lockstep graph against a bare rclpy chain',
                       description='Print graph lockstep steps/s, a bare rclpy chain with the same hops, their ratio, '
                                   'direct-engine and core-only dynamics steps/s, and the samples/s of a fixed '
                                   '20-sample case-1 dispersion.')
    p.add_argument('--json', action='store_true', help='last line: one JSON object')
    p.add_argument('--steps', type=step_count, default=2000, help='steps per measurement (default 2000)')
    p.set_defaults(func=cmd_bench)
    for module in _verb_modules():
        module.register(sub)
    return parser


def _verb_modules() -> list:
    """Verb groups in ``acds_cli/verbs/`` (one module each, with ``register(subparsers)``)."""
    import importlib
    import pkgutil

    from . import verbs
    return [importlib.import_module(f'{verbs.__name__}.{m.name}') for m in sorted(pkgutil.iter_modules(verbs.__path__),
                                                                                  key=lambda m: m.name)]


class Stopped(KeyboardInterrupt):
    """SIGTERM or SIGHUP (a closed terminal), raised in the main thread and handled like Ctrl-C."""

    def __init__(self, signum: int) -> None:
        super().__init__(f'signal {signum}')
        self.signum = signum


def _terminate(signum: int, _frame: object) -> None:
    raise Stopped(signum)


def main(argv: list[str] | None = None) -> int:
    """Parse the verb and run it; usage and scenario errors are one line, exit 2.

    SIGTERM and SIGHUP stop like Ctrl-C; a stopped verb exits 128 + the signal number
    (130 SIGINT, 143 SIGTERM, 129 SIGHUP), the shell convention.
    """
    signal.signal(signal.SIGTERM, _terminate)
    signal.signal(signal.SIGHUP, _terminate)
    parser = build_parser()
    args, extra = parser.parse_known_args(argv)
    if getattr(args, 'passthrough', False):
        args.tool_args = [*extra, *args.tool_args]
    elif extra:
        parser.error(f'unrecognized arguments: {" ".join(extra)}')
    try:
        return args.func(args)
    except ScenarioError as exc:
        print(f'acds: scenario error: {exc}', file=sys.stderr)
        return 2
    except UsageError as exc:
        print(f'acds {args.verb}: error: {exc}', file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        signum = getattr(exc, 'signum', signal.SIGINT)
        print(f'\n[acds] stopped by {signal.Signals(signum).name}', file=sys.stderr)
        return 128 + signum


if __name__ == '__main__':
    sys.exit(main())
