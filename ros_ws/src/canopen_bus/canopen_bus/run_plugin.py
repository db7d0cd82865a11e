"""What ``acds run`` does for a scenario with CANopen cards: the bus, the flight computer's heartbeat, the replay.

Declared in the entry-point group ``acds.run_options`` (the run's plug-in protocol, ``acds_cli.verbs.run``):

* :func:`add_arguments` adds ``--can-port``, ``--can-host``, ``--replay-can`` to ``acds run``;
* :func:`prepare` (before anything starts) checks them against the scenario and returns the
  :class:`BusSession` the run is entered into, or None for a scenario without ``canopen_cards``.

On the bus, the session starts the hub (:mod:`canopen_bus.hub`) on HOST:PORT, prints the endpoint and the
command that starts the OreSat C3 against it, and waits (at most the scenario's ``input_timeout``) for the
flight computer's heartbeat; the cards join the hub as a client when the run starts. With ``--replay-can LOG``
no bus is served: the recorded frames are applied at their recorded steps.

A session's ``served`` (None, or a callable a caller sets, e.g. a study that starts the flight computer for each
sample) is called with where the bus is, ``{'can_host', 'can_port'}``, once the hub listens and before the wait for
the heartbeat; what it returns, when not None, is polled during that wait (None: the flight computer is still there;
else one line why it is not, which fails the run at once). :func:`built_in` is the scenario flown by the built-in
law in place of the flight computer (``montecarlo --paired``).
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
C3_COMMAND = './scripts/acds c3 --run-dir {run_dir} --can-host {host} --can-port {port} --detumble {scenario}'


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
        #: Called with ``{'can_host', 'can_port'}`` once the hub listens, before the heartbeat wait (module doc).
        self.served: Any = None
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
        gone: Any = None
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
            c3 = C3_COMMAND.format(host=host, port=self.hub.port, run_dir=Path(sc.get('can_bus', 'can_log')).parent,
                                   scenario=sc.name)
            print(f'[acds] start the flight computer against it, e.g. the OreSat C3: {c3}', file=sys.stderr, flush=True)
            if self.served is not None:
                gone = self.served({'can_host': host, 'can_port': str(self.hub.port)})
        timeout = sc.get('', 'input_timeout')
        print(f'[acds] waiting up to {timeout:g} s (input_timeout) for the flight computer\'s heartbeat '
              f'(node 0x{fc:02X}, COB-ID 0x{0x700 + fc:03X})', file=sys.stderr, flush=True)
        t0 = time.monotonic()
        while gone is not None and not heartbeat.is_set() and time.monotonic() < t0 + timeout:
            why = gone()
            if why is not None:
                self.__exit__(None, None, None)
                raise RuntimeError(f'{why} before its heartbeat (node 0x{fc:02X}) came on {endpoint}')
            heartbeat.wait(min(0.2, max(0.0, t0 + timeout - time.monotonic())))
        if not heartbeat.wait(0 if gone is not None else timeout):
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
        if self.endpoint is not None:
            self._report_flight_computer()

    def _report_flight_computer(self) -> None:
        """What the flight computer did, from the CAN log: printed, and RUN_DIR/flight_computer.json."""
        import json

        from canopen_bus.canlog import CanLogError
        from canopen_bus.flight_report import report, setpoint_objects
        sc = self.scenario
        log = Path(sc.get('can_bus', 'can_log'))
        if not log.is_file():
            return
        try:
            fc = report(log, sc.get('can_bus', 'flight_computer_node_id'), setpoint_objects(sc.get('can_bus', 'mapping')))
        except CanLogError as exc:
            print(f'[acds] flight computer report: {exc}', file=sys.stderr, flush=True)
            return
        for line in fc.lines(sc.control_period_s):
            print(f'[acds] {line}', file=sys.stderr, flush=True)
        (log.parent / 'flight_computer.json').write_text(json.dumps(fc.as_dict(), indent=1) + '\n')


def built_in(raw: dict[str, Any]) -> dict[str, Any] | None:
    """A bus scenario's merged YAML (a Monte Carlo sample's) flown by the built-in law instead of the flight computer
    on the bus: the cards give way to what they stand between, the magnetometer (magnetometer_sim) and the law
    (acds_controller) whose moment command the em_driver follows; every other key (the draws, the control period,
    the dynamics) as it is. None for a scenario without the cards."""
    nodes = list(raw.get('nodes') or [])
    if 'canopen_cards' not in nodes:
        return None
    at = nodes.index('canopen_cards')
    out = {k: v for k, v in raw.items() if k != 'can_bus'}
    out['nodes'] = nodes[:at] + ['magnetometer_sim'] + nodes[at + 1:] + ['acds_controller']
    out['em_driver'] = {**raw.get('em_driver', {}), 'command_source': 'acds_controller'}
    return out


def _devices(scenario: Any) -> list[dict[str, Any]]:
    from canopen_bus.mapping import load_mapping
    return [{'name': m.name, 'node_id': m.node_id} for m in load_mapping(Path(scenario.get('can_bus', 'mapping')))]
