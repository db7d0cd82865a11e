"""``acds c3``: start the user's OreSat C3, unmodified, against a running bus scenario (spec §13).

    acds c3 [--run-dir RUN] [--can-host 127.0.0.1] [--can-port 29536] [--detumble SCENARIO] [--seconds S]

starts the C3 (:mod:`canopen_bus.c3_runner`: private mount namespace, user nobody, mock hardware, flight mode off,
its output in ``RUN/c3/``, by default a new folder ``runs/c3_<UTC time>`` of the workspace) on the socketcand bus
at HOST:29536, and with ``--detumble`` acts as its operator: once
its heartbeat (COB-ID 0x701) is on the bus, it sets the C3's ADCS manager to DETUMBLE with the orbit the scenario's
flight software carries (``controller.detumble_orbit_period_s`` and ``magnetic_inclination_rad``) by SDO to node
0x01, and prints what the C3 reads back. It runs until the C3 ends, ``--seconds`` pass, or Ctrl-C/SIGTERM, then
stops the C3 and waits for it (no orphan).
"""

from __future__ import annotations

import argparse
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from .c3_runner import C3_NODE_ID, C3_SOCKETCAND_PORT, CHANNEL, C3Error, C3Process, checkout_root

#: How long the operator waits for the C3's first heartbeat (its start imports scipy and skyfield: ~3–20 s here).
HEARTBEAT_WAIT_S = 60.0


def detumble_orbit(scenario_name: str) -> tuple[float, float]:
    """The orbit period (s) and inclination (rad) the scenario's flight software carries."""
    from acds_common.scenario import load_scenario

    scenario = load_scenario(scenario_name)
    return scenario.get('controller', 'detumble_orbit_period'), scenario.get('controller', 'magnetic_inclination')


def wait_heartbeat(network, node_id: int, timeout_s: float) -> float:
    """Block until ``node_id``'s heartbeat is on the bus; returns the wait, s (raises TimeoutError naming it)."""
    seen = threading.Event()
    network.subscribe(0x700 + node_id, lambda *_a: seen.set())
    t0 = time.monotonic()
    if not seen.wait(timeout_s):
        raise TimeoutError(f'no heartbeat from node {node_id:#04x} (COB-ID {0x700 + node_id:#05x}) within {timeout_s:g} s')
    return time.monotonic() - t0


def operate_detumble(host: str, port: int, orbit_period_s: float, inclination_rad: float,
                     heartbeat_timeout_s: float = HEARTBEAT_WAIT_S) -> dict[str, float]:
    """Connect to the bus, wait for the C3's heartbeat, command DETUMBLE with the orbit; returns the read-back."""
    import canopen

    from .c3_commands import command_detumble, connect

    network = canopen.Network()
    network.connect(interface='socketcand', channel=CHANNEL, host=host, port=port)
    try:
        wait_heartbeat(network, C3_NODE_ID, heartbeat_timeout_s)
        return command_detumble(connect(network), orbit_period_s, inclination_rad)
    finally:
        network.disconnect()


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser('c3', help='start the OreSat C3 flight software against a running bus scenario',
                       description=__doc__.split('\n\n')[1] if __doc__ else None)
    p.add_argument('--run-dir', type=Path, default=None,
                   help="the bus run's folder: the C3's output goes to RUN/c3/ (default: a new runs/c3_<UTC time>)")
    p.add_argument('--can-host', default='127.0.0.1', help='the bus (socketcand hub) host (default 127.0.0.1)')
    p.add_argument('--can-port', type=int, default=C3_SOCKETCAND_PORT,
                   help=f'the hub port; the C3 only connects to {C3_SOCKETCAND_PORT}')
    p.add_argument('--detumble', metavar='SCENARIO',
                   help="set the C3's ADCS manager to DETUMBLE with this scenario's orbit once its heartbeat is on")
    p.add_argument('--seconds', type=float, default=None, help='stop the C3 after this many seconds (default: never)')
    p.add_argument('--verbose', action='store_true', help="the C3's own -v (debug log)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if args.run_dir is None:
        args.run_dir = checkout_root() / 'runs' / time.strftime('c3_%Y%m%d_%H%M%S', time.gmtime())
    try:  # the run prints its folder before it has made it: made here if need be
        args.run_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        print(f'acds c3: error: --run-dir {args.run_dir}: {exc.strerror}', file=sys.stderr)
        return 2
    orbit = detumble_orbit(args.detumble) if args.detumble else None
    c3 = C3Process(args.run_dir / 'c3', host=args.can_host, port=args.can_port, verbose=args.verbose)
    try:
        c3.check()
    except C3Error as e:
        print(f'acds c3: error: {e}', file=sys.stderr)
        return 2
    with c3:
        print(f'[c3] OreSat C3 pid {c3.pid} on socketcand {args.can_host}:{args.can_port} ({CHANNEL}), log {c3.log_path}',
              file=sys.stderr, flush=True)
        t0 = time.monotonic()
        try:
            if orbit:
                back = operate_detumble(args.can_host, args.can_port, *orbit)
                print(f'[c3] ADCS manager set by SDO to node 0x01: control_mode {back["control_mode"]} (DETUMBLE), '
                      f'orbital_period {back["orbital_period"]:.1f} s, orbital_inclination '
                      f'{back["orbital_inclination"]:.2f} deg; its first setpoint comes when its 300 s IDLE sleep '
                      'ends (adcs_manager.py on_loop)', file=sys.stderr, flush=True)
            while c3.alive() and (args.seconds is None or time.monotonic() - t0 < args.seconds):
                try:
                    c3.proc.wait(0.5)
                except subprocess.TimeoutExpired:
                    pass
        except KeyboardInterrupt:
            pass
        except TimeoutError as e:
            print(f'[c3] {e}', file=sys.stderr)
            return 1
    print(f'[c3] C3 stopped (exit {c3.proc.returncode}) after {time.monotonic() - t0:.0f} s', file=sys.stderr)
    return 0


def _interrupt(_signum: int, _frame: object) -> None:
    raise KeyboardInterrupt


def main(argv: list[str] | None = None) -> int:
    """``python -m canopen_bus.c3_cli``: SIGTERM and SIGHUP stop the C3 like Ctrl-C."""
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, _interrupt)
    parser = argparse.ArgumentParser(prog='acds')
    register(parser.add_subparsers(dest='verb', required=True))
    args = parser.parse_args(['c3', *(sys.argv[1:] if argv is None else argv)])
    return args.func(args)


if __name__ == '__main__':
    sys.exit(main())
