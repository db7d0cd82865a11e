"""Bag verbs: record, play, compare, plot, info, recover (rosbag2 bags on top of ``rosbags``).

Every verb that reads a bag reads it strictly read-only (:mod:`acds_runtime.bag.reader`); bad options and
paths that are not bags are one line and exit 2 before anything starts.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..arguments import add_foxglove_options, domain_in
from ..bag import FORMATS

STORAGE_HELP = 'mcap (default) or sqlite3'
COMPRESSION_HELP = 'zstd (MCAP chunks, the default for mcap, as rosbag2 writes) or none (sqlite3: always none)'


def add_bag_options(p: argparse.ArgumentParser, storage: bool = True) -> None:
    """``--storage`` and ``--compression``, as every verb that writes a bag takes them."""
    from acds_runtime.bag import COMPRESSIONS, STORAGE_NAMES

    if storage:
        p.add_argument('--storage', choices=STORAGE_NAMES, default='mcap', help=STORAGE_HELP)
    p.add_argument('--compression', choices=COMPRESSIONS, help=COMPRESSION_HELP)


def wait_seconds(text: str) -> float:
    """``play --wait``: a finite number of seconds >= 0."""
    import math

    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f'expected a finite number of seconds >= 0, got {text!r}')
    return value


def _record(args: argparse.Namespace) -> int:
    from ..bag.recorder import main_record
    return main_record(args)


def lease_play_domain(domain: int | None) -> Any:
    """The domain ``play`` publishes into, leased for as long as it plays (a :class:`DomainLease`).

    ``play`` never publishes into a domain a running graph (or another play) holds: it would inject data into that
    run. Holding the lease, no run started while it plays lands on its domain either: that run would meet the
    player's publishers as an intruder and fail."""
    import os

    from acds_runtime.bag.writer import BagError
    from acds_runtime.launcher import DomainLease, LaunchError

    if domain is not None:
        target = domain
    else:
        text = os.environ.get('ROS_DOMAIN_ID', '') or '0'
        try:
            target = domain_in(text)
        except argparse.ArgumentTypeError as exc:
            raise BagError(f'ROS_DOMAIN_ID {text!r}: {exc} (or give --domain)') from None
    try:
        return DomainLease(target)
    except LaunchError:
        raise BagError(f'domain {target} belongs to a running graph (acds run) or another acds play: playing into it '
                       'would inject data into that one; choose a free --domain') from None


def _play(args: argparse.Namespace) -> int:
    from acds_runtime.bag.reader import open_bag
    from acds_runtime.bag.writer import BagError

    from ..bag import stop_on_signals
    from ..bag.player import Player, check_rate, parse_remaps

    stop = stop_on_signals()
    live = lease = None
    try:
        check_rate(args.rate)
        remap = parse_remaps(args.remap)
        lease = lease_play_domain(args.domain)
        bag = open_bag(args.bag)
        if args.foxglove is not None:
            live = _live_view(bag, args.foxglove, args.foxglove_host)
        player = Player(bag, domain_id=args.domain, select=args.topics, remap=remap, sink=live)
    except BagError as exc:
        if live is not None:
            live.close()
        if lease is not None:
            lease.close()
        print(f'acds play: {exc}', file=sys.stderr)
        return 2
    try:
        if live is not None:
            print(f'[play] Foxglove live view on ws://{args.foxglove_host}:{live.port} (subprotocol foxglove.sdk.v1): '
                  f'waiting up to {args.wait:g} s '
                  'for a Foxglove client', file=sys.stderr, flush=True)
            if not _wait(live.wait_for_client, args.wait, stop) and not stop.is_set():
                print(f'[play] no Foxglove client after {args.wait:g} s: playing anyway', file=sys.stderr)
        elif args.wait > 0 and not _wait(player.wait_for_subscribers, args.wait, stop) and not stop.is_set():
            print(f'[play] no subscriber after {args.wait:g} s: playing anyway', file=sys.stderr)
        pace = f'at {args.rate:g}x real time' if args.rate > 0 else 'as fast as possible'
        print(f'[play] {bag.path} → domain {args.domain if args.domain is not None else "(ROS_DOMAIN_ID)"}: '
              f'{len(player.topics)} topics {pace}', file=sys.stderr)
        n = player.play(rate=args.rate, stop=stop)
        print(f'[play] published {n} messages{" (stopped)" if stop.is_set() else ""}', file=sys.stderr)
    finally:
        player.close()
        if live is not None:
            live.close()
        lease.close()
    return 0


def _wait(ready: Any, timeout_s: float, stop: Any) -> bool:
    """``ready(timeout_s)`` polled in slices of at most 0.1 s, so that Ctrl-C / SIGTERM (``stop``) ends the wait at
    once (True: ready; False: the timeout passed or ``stop`` was set)."""
    import time

    deadline = time.monotonic() + timeout_s
    while not stop.is_set():
        left = deadline - time.monotonic()
        if left <= 0:
            return False
        if ready(min(left, 0.1)):
            return True
    return False


def _live_view(bag: Any, port: int, host: str) -> Any:
    """The Foxglove bridge of a bag: its topics and types, frames and limits from its recorded node parameters."""
    import yaml
    from acds_runtime.bag.writer import BagError
    from acds_runtime.foxglove_bridge import BridgeError, FoxgloveBridge

    params = yaml.safe_load(bag.info.get('params', '') or '{}') or {}
    if 'rigid_body' not in params:
        raise BagError(f'bag {bag.path}: no recorded node parameters (acds.params), which the Foxglove view needs '
                       'for its frames and limits (bags of acds run and acds record --run-dir have them)')
    try:
        return FoxgloveBridge(params, port=port, host=host, types=dict(bag.types))
    except BridgeError as exc:
        raise BagError(str(exc)) from None


def _compare(args: argparse.Namespace) -> int:
    from acds_runtime.bag.writer import BagError

    from ..bag.compare import EXIT_DIFFERENT, EXIT_ERROR, EXIT_SAME, check_tolerance, parse_sets, run_compare

    try:
        check_tolerance(args.tolerance)
        result = run_compare(args.bag, args.node, tolerance=args.tolerance, scenario=args.scenario,
                             sets=parse_sets(args.set))
    except BagError as exc:
        print(f'acds compare: {exc}', file=sys.stderr)
        return EXIT_ERROR
    print(result.report())
    return EXIT_SAME if result.ok else EXIT_DIFFERENT


def _plot(args: argparse.Namespace) -> int:
    from acds_runtime.bag.writer import BagError

    from ..bag.plots import make_plots

    try:
        paths = make_plots(args.bag, args.out, args.format)
    except BagError as exc:
        print(f'acds plot: {exc}', file=sys.stderr)
        return 2
    for p in paths:
        print(p)
    if not paths:
        print('[plot] no plottable topics in the bag', file=sys.stderr)
    return 0


def _info(args: argparse.Namespace) -> int:
    from acds_runtime.bag.writer import BagError

    from ..bag.info import bag_info

    try:
        print(bag_info(args.bag, scenario=not args.no_scenario))
    except BagError as exc:
        print(f'acds info: {exc}', file=sys.stderr)
        return 2
    return 0


def _recover(args: argparse.Namespace) -> int:
    from acds_runtime.bag.recover import recover_bag
    from acds_runtime.bag.writer import BagError

    try:
        src, copy = recover_bag(args.src, args.dest, args.compression)
    except BagError as exc:
        print(f'acds recover: {exc}', file=sys.stderr)
        return 2
    print(f'[recover] {src.path}: read {src.unclosed} ({src.total} messages), not changed; wrote {copy.path}: '
          f'{copy.total} messages on {len(copy.types)} topics, with metadata.yaml and its run data', file=sys.stderr)
    print(copy.path)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add the bag verbs."""
    p = sub.add_parser('record', help='record a running graph into a rosbag2 bag (until Ctrl-C / SIGTERM)',
                       description='Join a running graph (its ROS domain) and record its topics as raw CDR into '
                                   'a rosbag2 bag (MCAP by default) until SIGINT/SIGTERM. Buffered messages are '
                                   'flushed every second: a killed recorder loses at most the last second.')
    p.add_argument('path', help='bag folder to create (must not exist)')
    add_bag_options(p)
    p.add_argument('--topics', nargs='+', metavar='TOPIC', help='record only these topics (default: all)')
    p.add_argument('--domain', type=domain_in,
                   help='ROS domain id of the graph (printed by acds run, in RUN/domain_id)')
    p.add_argument('--run-dir', help='run folder of the graph: domain, scenario and parameters are read from it (and '
                                     'the control period and per-step topics that the gap check needs)')
    p.add_argument('--allow-gaps', action='store_true',
                   help='exit 0 even when steps are missing between a topic\'s first and last (they are stored in '
                        'the bag\'s metadata either way)')
    p.set_defaults(func=_record)

    p = sub.add_parser('play', help="publish a bag's messages (raw, original types, /clock)",
                       description="Publish a bag's messages with their original types and /clock, in sim-time "
                                   'order, as fast as possible or at --rate times real time.')
    p.add_argument('bag')
    p.add_argument('--topics', nargs='+', metavar='TOPIC', help='play only these topics (/clock always)')
    p.add_argument('--rate', type=float, default=0.0, help='sim time per wall time (default 0: as fast as possible)')
    p.add_argument('--remap', nargs='+', metavar='FROM:=TO', help='publish topic FROM under the name TO')
    p.add_argument('--domain', type=domain_in, help='ROS domain id to publish on (default: ROS_DOMAIN_ID)')
    p.add_argument('--wait', type=wait_seconds, default=2.0,
                   help='wait up to this many s for a subscriber (with --foxglove: for a Foxglove client; default 2)')
    add_foxglove_options(p, "the bag's messages")
    p.set_defaults(func=_play)

    p = sub.add_parser('compare', help="replay-regression: one node against a bag's recorded inputs",
                       description='Run NODE alone in its own ROS domain against the recorded inputs of BAG, in '
                                   'lockstep, and compare its outputs with the recorded ones step by step. Exit 0 '
                                   'when identical (or within --tolerance), 1 naming the first differing topic, '
                                   'step and field, 2 on a set-up error.')
    p.add_argument('bag')
    p.add_argument('--node', required=True, help='node to re-run (e.g. reaction_wheels, acds_controller; a formation '
                   "vehicle's: VEHICLE/NODE, e.g. a/em_driver)")
    p.add_argument('--tolerance', type=float, default=0.0, help='absolute float tolerance (default 0: identical)')
    p.add_argument('--scenario', help="take the node's parameters from this scenario instead of the bag's")
    p.add_argument('--set', nargs='+', metavar='PARAM:=VALUE', help='override node parameters (YAML values)')
    p.set_defaults(func=_compare)

    p = sub.add_parser('plot', help="the study's figures from a bag (PNG, SVG or PDF)",
                       description='Direction cosines, body rates, wheel momenta, magnetic moments, field/momentum '
                                   "angle, sun angle, mode timeline (and each mission plug-in's figures), study units; every "
                                   'time plot marks the mode transitions and capture, the limits where they apply.')
    p.add_argument('bag')
    p.add_argument('--out', help='output folder (default: plots/ beside the bag)')
    p.add_argument('--format', choices=FORMATS, default='png', help='file format (default png)')
    p.set_defaults(func=_plot)

    p = sub.add_parser('info', help="a bag's topics, types, counts, sim-time span and scenario",
                       description="Print a bag's topics, types, message counts, sim-time span and the scenario "
                                   'it was recorded with.')
    p.add_argument('bag')
    p.add_argument('--no-scenario', action='store_true', help="don't print the scenario text")
    p.set_defaults(func=_info)

    p = sub.add_parser('recover', help='write a repaired copy of an unclosed bag (SRC is never changed)',
                       description="Rebuild a bag whose recorder died (no metadata.yaml) from what reached the disk: "
                                   'MCAP up to its last complete chunk, sqlite3 up to its last committed transaction, '
                                   "with the run's data from SRC/acds_run.yaml. Writes DEST (index, metadata.yaml, "
                                   'acds custom data); SRC is only read.')
    p.add_argument('src', help='the bag folder (or its storage file) to repair')
    p.add_argument('dest', help='bag folder to create for the repaired copy (must not exist)')
    add_bag_options(p, storage=False)
    p.set_defaults(func=_recover)
