"""A CAN bus over TCP in the socketcand protocol, as python-can's ``socketcand`` client speaks it (spec §13).

No kernel CAN is needed: every client (the flight computer, a monitor, a rogue) connects by TCP, and every
frame one client sends is relayed to all the others and to the in-process ports (the emulated cards, the CAN
log). One thread owns the sockets (a selector loop); in-process ports hand their frames to it through a queue.

The protocol's quirks (spec §13, checked against python-can 4.6.1 ``can/interfaces/socketcand``):

- the server greets ``< hi >``; ``< open CHANNEL >`` and ``< rawmode >`` are each answered ``< ok >``, and
  the client reads each reply with one ``recv`` that must hold that reply alone, so a client gets no frame
  until ``RAWMODE_HOLDOFF_S`` after its rawmode reply (its frames are queued meanwhile, none is dropped);
- frames to a client are ``< frame ID SEC.USEC HEXDATA >``, ID exactly 3 hex digits for a standard
  identifier (8 for an extended one), the data as one hex string (an empty payload keeps the space);
- frames from a client are ``< send ID LEN B0 B1 … >`` in hex.

Bad input (a malformed line, a bad length, a command the hub does not serve) gets one line naming the client
and the line, is counted, and the hub goes on. The hub listens on 127.0.0.1 unless told otherwise: CAN has
no authentication, anyone who reaches the port is on the bus.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import queue
import selectors
import socket
import sys
import threading
import time
from collections.abc import Callable

#: socketcand's registered port, the one OLAF's ``-p`` defaults to (spec §13).
DEFAULT_PORT = 29536
DEFAULT_HOST = '127.0.0.1'
#: How long after its rawmode ``< ok >`` a client gets its first frame: python-can reads that reply with one
#: ``recv`` and fails if a frame shares it (spec §13). Frames are queued, not dropped, meanwhile.
RAWMODE_HOLDOFF_S = 0.05
#: A line longer than this without its closing ``>`` is malformed (the longest valid line is ~40 characters).
MAX_LINE = 200
#: Bytes a client may leave unread before the hub drops it (one line): ~100,000 frames, minutes of a busy bus.
MAX_BACKLOG = 4 << 20
MAX_STD_ID = 0x7FF
MAX_EXT_ID = 0x1FFFFFFF


@dataclasses.dataclass(frozen=True)
class Frame:
    """One CAN frame on the bus: identifier, payload, and the wall time (s, epoch) the hub took it in."""

    can_id: int
    data: bytes
    wall_time: float
    source: str
    extended: bool = False


class BadLine(ValueError):
    """A socketcand line the hub cannot take (the message names what is wrong)."""


def parse_send(line: str) -> tuple[int, bytes, bool]:
    """``< send ID LEN B0 … >`` → (id, data, extended); raises BadLine naming the fault."""
    parts = line[1:-1].split()
    if len(parts) < 3 or parts[0] != 'send':
        raise BadLine('not a `< send ID LEN B0 … >` line')
    try:
        can_id = int(parts[1], 16)
        length = int(parts[2], 16)
        data = bytes(int(b, 16) for b in parts[3:])
    except ValueError as exc:
        raise BadLine(f'not hex ({exc})') from None
    extended = len(parts[1]) > 3
    if can_id > (MAX_EXT_ID if extended else MAX_STD_ID):
        raise BadLine(f'identifier 0x{can_id:X} out of range')
    if not 0 <= length <= 8:
        raise BadLine(f'length {length} outside 0..8')
    if len(data) != length:
        raise BadLine(f'length {length} but {len(data)} data bytes')
    return can_id, data, extended


def format_frame(frame: Frame) -> str:
    """The ``< frame … >`` line python-can's client parses (3 hex digits for a standard id, spec §13)."""
    can_id = f'{frame.can_id:08X}' if frame.extended else f'{frame.can_id:03X}'
    sec = int(frame.wall_time)
    usec = int(round((frame.wall_time - sec) * 1e6))
    if usec >= 1_000_000:
        sec, usec = sec + 1, usec - 1_000_000
    return f'< frame {can_id} {sec}.{usec:06d} {frame.data.hex().upper()} >'


@dataclasses.dataclass
class _Client:
    sock: socket.socket
    name: str
    state: str = 'greeted'          # greeted → open → raw
    inbuf: str = ''
    outbuf: bytearray = dataclasses.field(default_factory=bytearray)
    held: collections.deque = dataclasses.field(default_factory=collections.deque)
    release_at: float = float('inf')
    frames_in: int = 0


@dataclasses.dataclass
class HubCounters:
    """What the hub has seen: frames relayed, bad lines, clients."""

    frames: int = 0
    bad_lines: int = 0
    clients_connected: int = 0
    clients_disconnected: int = 0


class LocalPort:
    """An in-process member of the bus: ``send`` puts a frame on it; ``on_frame`` gets every other frame
    (called on the hub's thread)."""

    def __init__(self, hub: Hub, name: str, on_frame: Callable[[Frame], None] | None):
        self.hub, self.name, self.on_frame = hub, name, on_frame

    def send(self, can_id: int, data: bytes, extended: bool = False) -> None:
        self.hub._submit(Frame(can_id, bytes(data), time.time(), self.name, extended))


class Hub:
    """The socketcand-protocol bus: a TCP server on (host, port) relaying every frame to every other member.

    ``report`` gets each one-line event (bad line, client in/out); ``observers`` see every frame relayed, in
    bus order (the CAN log).
    """

    def __init__(self, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT, *,
                 report: Callable[[str], None] | None = None):
        self.host = host
        self._requested_port = port
        self.port: int | None = None
        self.report = report or (lambda line: print(line, file=sys.stderr, flush=True))
        self.counters = HubCounters()
        self._local: list[LocalPort] = []
        self._observers: list[Callable[[Frame], None]] = []
        self._inbox: queue.SimpleQueue[Frame] = queue.SimpleQueue()
        self._clients: dict[int, _Client] = {}
        self._sel = selectors.DefaultSelector()
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._server: socket.socket | None = None
        self._serial = 0

    # -- members --------------------------------------------------------------------------------------------
    def local_port(self, name: str, on_frame: Callable[[Frame], None] | None = None) -> LocalPort:
        """An in-process member (an emulated card); add before ``start``."""
        port = LocalPort(self, name, on_frame)
        self._local.append(port)
        return port

    def observe(self, observer: Callable[[Frame], None]) -> None:
        """See every frame relayed (on the hub's thread, in bus order)."""
        self._observers.append(observer)

    @property
    def endpoint(self) -> str:
        return f'{self.host}:{self.port}'

    def clients(self) -> list[str]:
        return [c.name for c in self._clients.values()]

    # -- life -------------------------------------------------------------------------------------------------
    def start(self) -> Hub:
        """Bind and listen (raises OSError naming the address when it is taken), then serve on a thread."""
        server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            server.bind((self.host, self._requested_port))
        except OSError as exc:
            server.close()
            raise OSError(f'CAN hub: cannot listen on {self.host}:{self._requested_port}: {exc.strerror}') from exc
        server.listen(16)
        server.setblocking(False)
        self._server = server
        self.port = server.getsockname()[1]
        self._sel.register(server, selectors.EVENT_READ, 'accept')
        self._sel.register(self._wake_r, selectors.EVENT_READ, 'wake')
        self._thread = threading.Thread(target=self._loop, name='can-hub', daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._wake()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        for client in list(self._clients.values()):
            self._drop(client, None)
        for sock in (self._server, self._wake_r, self._wake_w):
            if sock is not None:
                sock.close()
        self._sel.close()

    def __enter__(self) -> Hub:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    # -- the loop ------------------------------------------------------------------------------------------
    def _wake(self) -> None:
        try:
            self._wake_w.send(b'\0')
        except (BlockingIOError, OSError):
            pass

    def _submit(self, frame: Frame) -> None:
        self._inbox.put(frame)
        self._wake()

    def _loop(self) -> None:
        while not self._stop.is_set():
            now = time.time()
            pending = [c.release_at for c in self._clients.values() if c.held]
            timeout = max(0.0, min(pending) - now) if pending else None
            for key, mask in self._sel.select(timeout):
                if key.data == 'accept':
                    self._accept()
                elif key.data == 'wake':
                    try:
                        while self._wake_r.recv(4096):
                            pass
                    except BlockingIOError:
                        pass
                else:
                    client = key.data
                    if mask & selectors.EVENT_READ:
                        self._read(client)
                    if mask & selectors.EVENT_WRITE and client.sock.fileno() in self._clients:
                        self._flush(client)
            while True:
                try:
                    frame = self._inbox.get_nowait()
                except queue.Empty:
                    break
                self._relay(frame, sender=None)
            now = time.time()
            for client in list(self._clients.values()):
                if client.held and now >= client.release_at:
                    while client.held:
                        client.outbuf += client.held.popleft()
                    self._flush(client)

    def _accept(self) -> None:
        try:
            sock, addr = self._server.accept()
        except BlockingIOError:
            return
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._serial += 1
        client = _Client(sock, f'client {self._serial} ({addr[0]}:{addr[1]})')
        self._clients[sock.fileno()] = client
        self._sel.register(sock, selectors.EVENT_READ, client)
        self.counters.clients_connected += 1
        self.report(f'CAN hub: {client.name} connected')
        self._write(client, '< hi >')

    def _drop(self, client: _Client, why: str | None) -> None:
        fd = client.sock.fileno()
        if fd in self._clients:
            del self._clients[fd]
            try:
                self._sel.unregister(client.sock)
            except (KeyError, ValueError):
                pass
        client.sock.close()
        if why is not None:
            self.counters.clients_disconnected += 1
            self.report(f'CAN hub: {client.name} {why} after {client.frames_in} frames')

    def _read(self, client: _Client) -> None:
        try:
            data = client.sock.recv(65536)
        except (ConnectionError, OSError):
            data = b''
        if not data:
            self._drop(client, 'disconnected')
            return
        client.inbuf += data.decode('ascii', errors='replace')
        while True:
            start = client.inbuf.find('<')
            if start > 0 and client.inbuf[:start].strip():
                self._bad(client, client.inbuf[:start].strip(), 'text outside `< … >`')
            if start < 0:
                if client.inbuf.strip():
                    if len(client.inbuf) > MAX_LINE:
                        self._bad(client, client.inbuf[:40] + '…', 'text outside `< … >`')
                        client.inbuf = ''
                else:
                    client.inbuf = ''
                return
            end = client.inbuf.find('>', start)
            if end < 0:
                client.inbuf = client.inbuf[start:]
                if len(client.inbuf) > MAX_LINE:
                    self._bad(client, client.inbuf[:40] + '…', f'no closing `>` within {MAX_LINE} characters')
                    client.inbuf = ''
                return
            line = client.inbuf[start:end + 1]
            client.inbuf = client.inbuf[end + 1:]
            self._line(client, line)

    def _bad(self, client: _Client, line: str, why: str) -> None:
        self.counters.bad_lines += 1
        self.report(f'CAN hub: {client.name}: bad line {line!r} ({why}); bad lines so far {self.counters.bad_lines}')

    def _line(self, client: _Client, line: str) -> None:
        words = line[1:-1].split()
        verb = words[0] if words else ''
        if client.state == 'greeted' and verb == 'open' and len(words) == 2:
            client.state = 'open'
            self._write(client, '< ok >')
        elif client.state == 'open' and verb == 'rawmode' and len(words) == 1:
            client.state = 'raw'
            self._write(client, '< ok >')
            client.release_at = time.time() + RAWMODE_HOLDOFF_S
        elif client.state == 'raw' and verb == 'send':
            try:
                can_id, data, extended = parse_send(line)
            except BadLine as exc:
                self._bad(client, line, str(exc))
                return
            client.frames_in += 1
            self._relay(Frame(can_id, data, time.time(), client.name, extended), sender=client)
        else:
            self._bad(client, line, f'not served in state {client.state}')

    def _relay(self, frame: Frame, sender: _Client | None) -> None:
        self.counters.frames += 1
        for observer in self._observers:
            observer(frame)
        for port in self._local:
            if port.name != frame.source and port.on_frame is not None:
                port.on_frame(frame)
        text = format_frame(frame).encode('ascii')
        now = time.time()
        for client in list(self._clients.values()):
            if client is sender or client.state != 'raw':
                continue
            if client.held or now < client.release_at:
                client.held.append(text)
            else:
                client.outbuf += text
                self._flush(client)

    def _write(self, client: _Client, line: str) -> None:
        client.outbuf += line.encode('ascii')
        self._flush(client)

    def _flush(self, client: _Client) -> None:
        try:
            sent = client.sock.send(client.outbuf) if client.outbuf else 0
        except BlockingIOError:
            sent = 0
        except (ConnectionError, OSError):
            self._drop(client, 'disconnected')
            return
        del client.outbuf[:sent]
        if len(client.outbuf) > MAX_BACKLOG:
            self._drop(client, f'reads nothing ({len(client.outbuf):,} bytes unread): dropped')
            return
        events = selectors.EVENT_READ | (selectors.EVENT_WRITE if client.outbuf else 0)
        try:
            self._sel.modify(client.sock, events, client)
        except (KeyError, ValueError):
            pass


def main(argv: list[str] | None = None) -> int:
    """Serve the bus standalone until SIGINT/SIGTERM (``python -m canopen_bus.hub``)."""
    import signal
    parser = argparse.ArgumentParser(prog='canopen_bus_hub', description=__doc__.splitlines()[0])
    parser.add_argument('--can-host', default=DEFAULT_HOST,
                        help='address to listen on (default 127.0.0.1: CAN has no authentication)')
    parser.add_argument('--can-port', type=int, default=DEFAULT_PORT, help=f'TCP port (default {DEFAULT_PORT})')
    args = parser.parse_args(argv)
    done = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, lambda *_: done.set())
    try:
        hub = Hub(args.can_host, args.can_port).start()
    except OSError as exc:
        print(exc, file=sys.stderr)
        return 2
    print(f'CAN hub (socketcand protocol) on {hub.endpoint}; channel name any (e.g. vcan0)', flush=True)
    done.wait()
    hub.stop()
    c = hub.counters
    print(f'CAN hub: {c.frames} frames relayed, {c.bad_lines} bad lines, {c.clients_connected} clients', flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
