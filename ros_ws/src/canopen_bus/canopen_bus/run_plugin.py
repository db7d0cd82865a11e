"""What ``acds run`` does for a scenario with CANopen cards: the bus, the flight computer's heartbeat, the replay.

Declared in the entry-point group ``acds.run_options`` (the run's plug-in protocol, ``acds_cli.verbs.run``):

* :func:`add_arguments` adds ``--can-port``, ``--can-host``, ``--replay-can`` to ``acds run``;
* :func:`prepare` (before anything starts) checks them against the scenario and returns the
  :class:`BusSession` the run is entered into, or None for a scenario without ``canopen_cards``.

On the bus, the session starts the hub (:mod:`canopen_bus.hub`) on HOST:PORT, prints the endpoint and the
command that starts the OreSat C3 against it, and waits (at most the scenario's ``input_timeout``) for the
flight computer's heartbeat; the cards join the hub as a client when the run starts. With ``--replay-can LOG``
no bus is served: the recorded frames are applied at their recorded steps.
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import sys
import threading
import time
from pathlib import Path
from typing import Any

from canopen_bus.hub import DEFAULT_HOST, DEFAULT_PORT, Hub

#: The command the run prints for starting the OreSat C3 flight software against the bus.
C3_COMMAND = './scripts/acds c3 --can-host {host} --can-port {port}'


def add_arguments(parser: argparse.ArgumentParser) -> None:
    g = parser.add_argument_group('CAN bus (a scenario with the canopen_cards node)')
    g.add_argument('--can-port', type=int, metavar='PORT',
                   help=f'TCP port of the socketcand-protocol bus (default {DEFAULT_PORT}, the port the OreSat C3 '
                        'connects to; 0: any free port)')
    g.add_argument('--can-host', metavar='HOST',
                   help=f'address the bus listens on (default {DEFAULT_HOST}: CAN has no authentication, anyone who '
                        'reaches the port is on the bus)')
    g.add_argument('--replay-can', metavar='LOG',
                   help='fly the setpoints of a recorded run (its RUN_DIR/can.asc) at their recorded steps, without '
                        'the flight computer')


def _with_bus(scenario: Any, **values: Any) -> Any:
    new = copy.copy(scenario.values)
    new['can_bus'] = {**scenario.values['can_bus'], **values}
    return dataclasses.replace(scenario, values=new)


def prepare(scenario: Any, args: argparse.Namespace, run_dir: Path) -> BusSession | None:
    """The bus session of this run (None: the scenario has no CAN cards); ValueError (one line) for an option that
    does not fit."""
    given = [f'--{n.replace("_", "-")}' for n in ('can_port', 'can_host', 'replay_can') if getattr(args, n) is not None]
    if 'canopen_cards' not in scenario.get('', 'nodes'):
        if given:
            raise ValueError(f'{given[0]}: scenario {scenario.name} has no CAN bus (no canopen_cards node)')
        return None
    if args.can_port is not None and not 0 <= args.can_port <= 65535:
        raise ValueError(f'--can-port {args.can_port}: not a TCP port (0..65535)')
    rtf = args.rtf or scenario.get('can_bus', 'rtf')
    if args.replay_can is not None:
        if args.can_port is not None or args.can_host is not None:
            raise ValueError('--replay-can flies a recorded run without a bus: leave --can-port/--can-host out')
        from canopen_bus.canlog import CanLogError, read_replay, recorded_rtf
        log = Path(args.replay_can).resolve()
        try:
            read_replay(log)
        except CanLogError as exc:
            raise ValueError(str(exc)) from None
        rtf = args.rtf or recorded_rtf(log) or rtf  # the heartbeat watch counts the recorded run's steps
        return BusSession(_with_bus(scenario, rtf=rtf, replay_can=str(log)), None)
    if scenario.get('can_bus', 'interface') == 'socketcan':
        channel = scenario.get('can_bus', 'channel')
        if given:
            raise ValueError(f'{given[0]}: can_bus.interface is socketcan ({channel}): there is no hub to place')
        if not Path('/sys/class/net', channel).exists():
            raise ValueError(f'can_bus.interface socketcan: this machine has no network interface {channel} (create '
                             f'one: ip link add dev {channel} type vcan && ip link set up {channel}; or use socketcand)')
        return BusSession(_with_bus(scenario, rtf=rtf, can_log=str(run_dir / 'can.asc')), ('socketcan', channel))
    host = args.can_host or DEFAULT_HOST
    port = DEFAULT_PORT if args.can_port is None else args.can_port
    return BusSession(_with_bus(scenario, rtf=rtf, can_log=str(run_dir / 'can.asc')), (host, port))


class BusSession:
    """The run's bus: entered before the engine starts (returns the scenario the engine runs), left after it."""

    #: It paces the run itself (``acds run --rtf`` is its real-time factor, on either engine).
    paces = True

    def __init__(self, scenario: Any, endpoint: tuple[str, Any] | None) -> None:
        self.scenario, self.endpoint = scenario, endpoint
        self.hub: Hub | None = None
        self.listener: Any = None
        self.notifier: Any = None

    def __enter__(self) -> Any:
        sc = self.scenario
        if self.endpoint is None:
            print(f'[acds] replaying the CAN log {sc.get("can_bus", "replay_can")}: no bus, no flight computer; the '
                  f'heartbeat watched in the steps of R = {sc.get("can_bus", "rtf"):g}', file=sys.stderr, flush=True)
            return sc
        fc = sc.get('can_bus', 'flight_computer_node_id')
        heartbeat = threading.Event()
        cards = ', '.join(f'{m["name"]} 0x{m["node_id"]:02X}' for m in _devices(sc))
        host, port = self.endpoint
        if host == 'socketcan':
            import can
            self.listener = can.Bus(interface='socketcan', channel=port)
            self.notifier = can.Notifier(self.listener, [lambda m: heartbeat.set() if m.arbitration_id == 0x700 + fc
                                                         else None])
            endpoint = f'socketcan:{port}'
            print(f'[acds] CAN bus: the kernel interface {port} (SocketCAN); the cards: {cards}', file=sys.stderr,
                  flush=True)
        else:
            self.hub = Hub(host, port, report=lambda line: print(f'[acds] {line}', file=sys.stderr, flush=True))
            self.hub.start()
            self.hub.observe(lambda f: heartbeat.set() if f.can_id == 0x700 + fc else None)
            endpoint = f'socketcand:{host}:{self.hub.port}'
            print(f'[acds] CAN bus (socketcand protocol) on {host}:{self.hub.port}, channel vcan0; the cards: {cards}',
                  file=sys.stderr, flush=True)
            print(f'[acds] start the flight computer against it, e.g. the OreSat C3: '
                  f'{C3_COMMAND.format(host=host, port=self.hub.port)}', file=sys.stderr, flush=True)
        timeout = sc.get('', 'input_timeout')
        print(f'[acds] waiting up to {timeout:g} s (input_timeout) for the flight computer\'s heartbeat '
              f'(node 0x{fc:02X}, COB-ID 0x{0x700 + fc:03X})', file=sys.stderr, flush=True)
        t0 = time.monotonic()
        if not heartbeat.wait(timeout):
            clients = (', '.join(self.hub.clients()) or 'none') if self.hub is not None else 'not known (SocketCAN)'
            line = (f'no heartbeat from the flight computer (node 0x{fc:02X}, COB-ID 0x{0x700 + fc:03X}) within '
                    f'{timeout:g} s on {endpoint}; clients on the bus: {clients}')
            if sc.get('can_bus', 'on_heartbeat_loss') == 'fail':
                self.__exit__(None, None, None)
                raise RuntimeError(line)
            print(f'[acds] WARNING: {line}; flying on (can_bus.on_heartbeat_loss: fly_on)', file=sys.stderr, flush=True)
        else:
            print(f'[acds] flight computer heartbeat after {time.monotonic() - t0:.1f} s; running at real-time factor '
                  f'{sc.get("can_bus", "rtf"):g}', file=sys.stderr, flush=True)
        if self.notifier is not None:  # the cards open their own socket on the interface
            self.notifier.stop()
            self.listener.shutdown()
            self.notifier = None
        self.scenario = _with_bus(sc, endpoint=endpoint)
        return self.scenario

    def __exit__(self, *exc: Any) -> None:
        if self.notifier is not None:
            self.notifier.stop()
            self.listener.shutdown()
            self.notifier = None
        if self.hub is not None:
            c = self.hub.counters
            print(f'[acds] CAN bus: {c.frames} frames relayed, {c.bad_lines} bad lines, {c.clients_connected} clients '
                  f'connected', file=sys.stderr, flush=True)
            self.hub.stop()
            self.hub = None


def _devices(scenario: Any) -> list[dict[str, Any]]:
    from canopen_bus.mapping import load_mapping
    return [{'name': m.name, 'node_id': m.node_id} for m in load_mapping(Path(scenario.get('can_bus', 'mapping')))]
