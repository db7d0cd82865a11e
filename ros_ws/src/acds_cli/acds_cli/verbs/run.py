"""``acds run``: a scenario through the full process graph (or the direct engine), its summary, its bag and plots."""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import time
from pathlib import Path

from acds_common.scenario import MAX_STEPS, load_scenario, shipped_role

from ..arguments import (
    UsageError,
    add_foxglove_options,
    check_output_dir,
    check_output_file,
    domain_in,
    peer_host,
    positive_minutes,
    real_time_factor,
    step_count,
)
from ..interrupts import interruption
from ..workspace import new_run_dir, workspace
from .montecarlo import add_sample_options, sample_for_run

#: The main job (``scenarios/roles.json``), what ``acds run``, ``acds params`` and ``acds contract`` take with no argument.
DEFAULT_SCENARIO = shipped_role('main_job')
#: Entry-point group of run plug-ins: a package's own ``acds run`` options and what the run holds for its nodes while
#: it goes (a bus, a device). Each entry names a module with
#:   ``add_arguments(parser)``: its options (they default to None);
#:   ``prepare(scenario, args, run_dir)``: before anything starts, None when the scenario is not its own, else
#:   a context manager the run is entered into: ``__enter__`` returns the scenario the engine runs (its values set
#:   from the options) and ``__exit__`` releases what it holds; ``paces`` (bool) says it paces the run to the wall
#:   clock itself, so ``--rtf`` applies on the direct engine too. A ValueError from ``prepare`` is a usage error
#:   (one line, exit 2); a RuntimeError from ``__enter__`` fails the run (one line, exit 1).
#:   A session that serves something an outside program joins (a bus) calls its ``served`` attribute, when one is
#:   set, with the placeholders of where it is (``montecarlo --fsw-command`` starts the flight computer then);
#:   ``built_in(raw)`` (optional) gives a sample's merged YAML flown by the built-in law instead (``--paired``).
RUN_PLUGINS = 'acds.run_options'


def run_plugins() -> list:
    """The modules the entry-point group :data:`RUN_PLUGINS` names, in name order."""
    from importlib.metadata import entry_points

    return [ep.load() for ep in sorted(entry_points(group=RUN_PLUGINS), key=lambda e: e.name)]


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
    print(f'[acds] Foxglove live view on ws://{host}:{port}, subprotocol foxglove.sdk.v1 (Foxglove: Open connection → '
          'Foxglove WebSocket; '
          f'layout {workspace() / "foxglove" / "acds_layout.json"})', file=sys.stderr, flush=True)


def cmd_run(args: argparse.Namespace) -> int:
    """Run a scenario through the full process graph (or the direct engine) and print its summary."""
    from acds_runtime.preflight import preflight

    scenario, sample_text = sample_for_run(load_scenario(args.scenario or DEFAULT_SCENARIO), args)
    preflight(scenario)
    steps = args.steps
    if args.until_min is not None:
        steps = max(1, round(args.until_min * 60 / scenario.control_period_s))
        if steps > MAX_STEPS:
            raise UsageError(f'--until-min {args.until_min:g}: {steps:,} steps of {scenario.control_period_s} s, '
                             f'more than the {MAX_STEPS:,} a run may have')
    direct = args.engine == 'direct'
    try:
        external = scenario.external(args.external)
    except ValueError as exc:
        raise UsageError(f'--external: {exc}') from None
    if direct and external:
        raise UsageError('--external: the direct engine runs every node in this process; an external node joins the '
                         'process graph (use --engine graph)')
    overrides = _deadlines(args, scenario, direct)
    check_output_dir('--run-dir' if args.run_dir else 'run folder', Path(args.run_dir or workspace() / 'runs'))
    if args.summary_json:
        check_output_file('--summary-json', Path(args.summary_json))
    if args.domain is not None and not direct:
        from acds_runtime.launcher import DomainLease
        if DomainLease.held(args.domain):  # (the launcher's lease still decides: this only spares a run folder)
            raise UsageError(f'--domain {args.domain}: another run (or acds play) holds this ROS domain now; '
                             'choose another or leave --domain out')
    if args.record is not None and not args.record.strip():
        raise UsageError('--record: an empty path (give the bag folder to create, or leave --record out for '
                         'RUN_DIR/bag)')
    # The default folder is created exclusively (a run started in the same second gets its own).
    run_dir = Path(args.run_dir) if args.run_dir else new_run_dir(scenario.name)
    try:
        sessions = [x for x in (plugin.prepare(scenario, args, run_dir) for plugin in run_plugins()) if x is not None]
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    if direct and args.rtf and not any(x.paces for x in sessions):
        raise UsageError('--rtf paces the process graph\'s clock; the direct engine has none (use --engine graph)')
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
    with contextlib.ExitStack() as held:
        try:
            for session in sessions:
                scenario = held.enter_context(session)
        except RuntimeError as exc:
            print(f'[acds] run failed: {exc}', file=sys.stderr)
            return 1
        except KeyboardInterrupt:
            print('\n[acds] stopped before the run started', file=sys.stderr)
            return 130
        return _run(args, scenario, run_dir, direct, external, overrides, bag, live, echo, steps,
                    paced=bool(args.rtf) or any(x.paces for x in sessions))


def _run(args: argparse.Namespace, scenario, run_dir: Path, direct: bool, external, overrides, bag, live, echo,
         steps, paced: bool) -> int:
    """The run itself, on the engine asked, then its summary, tables and plots. The graph's node processes are
    placed on the machine's two CPUs (:mod:`acds_runtime.placement`) unless the run is ``paced`` to the wall clock, by
    ``--rtf`` or a session such as a bus."""
    from acds_runtime.direct import DirectRun
    from acds_runtime.launcher import GraphRun, LaunchError
    from acds_runtime.report import format_summary
    from acds_runtime.summary import print_tables, write_summary_json

    progress = Progress(scenario.control_period_s)
    options = dict(record=bag, record_storage=args.storage, record_compression=args.compression, live=live)
    if direct:
        run_dir.mkdir(parents=True, exist_ok=True)
        engine = DirectRun(scenario, steps=steps, echo=echo, progress=progress, run_id=run_dir.name, **options)
    else:
        engine = GraphRun(scenario, run_dir, steps=steps, rtf=args.rtf, echo=echo, progress=progress,
                          overrides=overrides, external=args.external, domain=args.domain, peers=args.peer,
                          notice=lambda line: print(line, file=sys.stderr, flush=True), place=not paced, **options)
    print(f'[acds] scenario {scenario.name}: {engine.steps} steps of {scenario.control_period_s} s '
          f'({engine.steps * scenario.control_period_s / 60:.1f} min sim), '
          + ('direct engine (one process, no DDS)' if direct else 'nodes ' + ', '.join(
              f'{i} (external)' if i in external else i for i, _n, _v in scenario.instances()))
          + f'; run folder {run_dir}', file=sys.stderr, flush=True)
    try:
        if direct:
            if engine.live_sink is not None:
                _announce_live(engine.live_sink.port, args.foxglove_host)
            summary, timing = engine.run().summary, None
        else:
            with engine:
                print(f'[acds] ROS domain {engine.lease.domain_id}' + (f'; recording into {bag}' if bag else ''),
                      file=sys.stderr, flush=True)
                if engine.live_sink is not None:
                    _announce_live(engine.live_sink.port, args.foxglove_host)
                result = engine.wait()
                for warning in result.warnings:
                    print(f'[acds] WARNING: {warning}', file=sys.stderr)
                summary, timing = result.summary, result.timing
    except LaunchError as exc:
        print(f'[acds] run failed: {exc}', file=sys.stderr)
        return 1
    except BaseException as caught:
        exc = interruption(caught)
        if exc is None:
            raise
        signum = getattr(exc, 'signum', signal.SIGINT)
        stopped = 'the run stopped' if direct else 'all nodes stopped'
        print(f'\n[acds] stopped by {signal.Signals(signum).name}: {stopped}', file=sys.stderr)
        return 128 + signum
    print('\n' + format_summary(summary))
    print_tables(summary)
    if timing is not None:
        from acds_common.timing import deadline_warnings, table
        print('\nStep wall time per node (last input of step k → its outputs published; the machine\'s, not the data\'s):')
        print('\n'.join(table(timing)))
    if args.summary_json:
        write_summary_json(Path(args.summary_json), summary if timing is None else {**summary, 'timing': timing})
    if bag is not None:
        from ..bag.plots import make_plots
        plot_dir = run_dir / 'plots'  # the run's own folder: never shared with another run recorded beside the bag
        plots = make_plots(bag, plot_dir)
        print(f'[acds] bag {bag} (./scripts/acds info {bag}); {len(plots)} plots in {plot_dir}', file=sys.stderr)
    if timing is not None:
        for warning in deadline_warnings(timing):
            print(f'[acds] WARNING: deadline: {warning}', file=sys.stderr)
    return 0


def deadline(text: str) -> tuple[str, float]:
    """``NODE=MS`` of ``--deadline-ms``: a node and a finite budget > 0, milliseconds."""
    import math

    node, sep, ms = text.partition('=')
    try:
        value = float(ms)
    except ValueError:
        value = math.nan
    if not sep or not node or not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f'expected NODE=MS with a finite MS > 0, got {text!r}')
    return node, value


def _deadlines(args: argparse.Namespace, scenario, direct: bool) -> dict[str, dict[str, object]] | None:
    """The node parameter overrides of ``--deadline-ms`` / ``--deadline-strict`` (checked before anything starts)."""
    if not args.deadline_ms:
        if args.deadline_strict:
            raise UsageError('--deadline-strict needs at least one --deadline-ms NODE=MS')
        return None
    if direct:
        raise UsageError('--deadline-ms: step wall times are measured per node process (the graph engine); the direct '
                         'engine has none (use --engine graph)')
    from acds_common.parameters import node_parameters

    nodes = list(node_parameters(scenario, 1))
    out: dict[str, dict[str, object]] = {}
    for node, ms in args.deadline_ms:
        if node not in nodes:
            raise UsageError(f'--deadline-ms {node}={ms:g}: scenario {scenario.name} runs no such node '
                             f'(its nodes: {", ".join(nodes)})')
        out[node] = {'deadline_ms': ms, 'deadline_strict': args.deadline_strict}
    return out


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``run`` verb."""
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
    g.add_argument('--record', metavar='PATH', help='record the run into this rosbag2 bag (default RUN_DIR/bag; '
                   'the plots go to RUN_DIR/plots either way)')
    g.add_argument('--no-record', action='store_true', help="don't record a bag (nor plot it)")
    from .bag import add_bag_options
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
    p.add_argument('--deadline-ms', type=deadline, action='append', metavar='NODE=MS',
                   help="a node's wall-time budget per step, ms (repeatable): steps over it are counted and reported "
                        'as a warning at the end')
    p.add_argument('--deadline-strict', action='store_true', help='fail the run at the first step over a deadline')
    p.add_argument('--external', action='append', default=[], metavar='NODE[=ROS_NODE_NAME]',
                   help='leave NODE to your own ROS 2 node (repeatable; default ROS node name: NODE): the launcher '
                        'does not start it and waits until your node serves its contract (./scripts/acds contract '
                        'SCENARIO --node NODE)')
    p.add_argument('--domain', type=domain_id, metavar='ID',
                   help='ROS_DOMAIN_ID of the run (default: the first free one, printed), e.g. for an external node')
    p.add_argument('--peer', action='append', default=[], metavar='HOST', type=peer_host,
                   help='another host whose ROS 2 participants discovery contacts (repeatable; ROS_STATIC_PEERS): '
                        'where an external node runs (discovery otherwise stays on this host)')
    for plugin in run_plugins():
        plugin.add_arguments(p)
    p.set_defaults(func=cmd_run)


def domain_id(text: str) -> int:
    """``--domain``: a ROS domain the launcher may lease (its range)."""
    from acds_runtime.launcher import DOMAIN_RANGE

    return domain_in(text, DOMAIN_RANGE)

