"""The socketcand-protocol hub against python-can's unmodified ``socketcand`` client (spec §13)."""

import socket
import threading
import time

import can
import pytest
from canopen_bus.hub import Frame, Hub, format_frame, parse_send


def _client(hub: Hub) -> can.BusABC:
    return can.Bus(interface='socketcand', channel='vcan0', host=hub.host, port=hub.port)


def _recv(bus: can.BusABC, timeout: float = 5.0) -> can.Message:
    msg = bus.recv(timeout)
    assert msg is not None, f'no frame within {timeout} s'
    return msg


@pytest.fixture
def hub():
    lines: list[str] = []
    with Hub('127.0.0.1', 0, report=lines.append) as h:
        h.lines = lines
        yield h


def test_frames_are_relayed_between_clients_and_local_ports(hub):
    seen: list[Frame] = []
    got = threading.Event()

    def on_frame(frame):
        seen.append(frame)
        got.set()
    port = hub.local_port('card', on_frame)
    logged: list[Frame] = []
    hub.observe(logged.append)
    a, b = _client(hub), _client(hub)
    try:
        a.send(can.Message(arbitration_id=0x638, data=[0x2B, 0x07, 0x40, 0x04, 0xE8, 0x03, 0, 0], is_extended_id=False))
        msg = _recv(b)
        expected = (0x638, bytes([0x2B, 7, 0x40, 4, 0xE8, 3, 0, 0]), False)
        assert (msg.arbitration_id, bytes(msg.data), msg.is_extended_id) == expected
        assert got.wait(5.0) and seen[0].can_id == 0x638 and seen[0].source.startswith('client 1')
        # An in-process port's frame reaches both clients, an empty payload and an extended id included.
        port.send(0x1B8, b'')
        port.send(0x1ABCDE, b'\x01\x02', extended=True)
        for bus in (a, b):
            m1, m2 = _recv(bus), _recv(bus)
            assert (m1.arbitration_id, bytes(m1.data), m1.is_extended_id) == (0x1B8, b'', False)
            assert (m2.arbitration_id, bytes(m2.data), m2.is_extended_id) == (0x1ABCDE, b'\x01\x02', True)
        # The sender does not hear its own frame back.
        assert a.recv(0.2) is None
        assert [f.can_id for f in logged] == [0x638, 0x1B8, 0x1ABCDE]
        assert hub.counters.bad_lines == 0
    finally:
        a.shutdown()
        b.shutdown()


def test_a_frame_sent_right_after_rawmode_does_not_break_the_handshake(hub):
    """Frames flow all the time on a live bus: a client that joins meanwhile must still get its ``< ok >`` alone."""
    port = hub.local_port('card')
    stop = threading.Event()

    def chatter():
        while not stop.is_set():
            port.send(0x1B8, b'\x00\x01')
            time.sleep(0.0005)
    t = threading.Thread(target=chatter)
    t.start()
    try:
        for _ in range(5):
            bus = _client(hub)
            assert _recv(bus).arbitration_id == 0x1B8
            bus.shutdown()
    finally:
        stop.set()
        t.join()


def _raw(hub: Hub) -> socket.socket:
    s = socket.create_connection((hub.host, hub.port), timeout=5.0)
    assert s.recv(64) == b'< hi >'
    s.sendall(b'< open vcan0 >')
    assert s.recv(64) == b'< ok >'
    s.sendall(b'< rawmode >')
    assert s.recv(64) == b'< ok >'
    return s


def _wait(pred, what: str, timeout: float = 5.0):
    end = time.monotonic() + timeout
    while not pred():
        if time.monotonic() > end:
            raise AssertionError(f'{what} not within {timeout} s')
        time.sleep(0.01)


def test_bad_lines_are_named_counted_and_the_hub_survives(hub):
    rogue = _raw(hub)
    good = _client(hub)
    try:
        rogue.sendall(b'< send 7FF 9 1 2 3 4 5 6 7 8 9 >< send 123 2 1 >< send XYZ 0 >< bogus >garbage< send 800 0 >')
        _wait(lambda: hub.counters.bad_lines == 6, 'six bad lines counted')
        assert len(hub.lines) >= 6
        text = '\n'.join(hub.lines)
        for needle in ('length 9 outside 0..8', 'length 2 but 1 data bytes', 'not hex', "'< bogus >'", 'out of range',
                       "'garbage' (text outside"):
            assert needle in text
        # The hub still relays: the rogue's next good frame reaches the good client.
        rogue.sendall(b'< send 1B8 2 a b >')
        msg = _recv(good)
        assert (msg.arbitration_id, bytes(msg.data)) == (0x1B8, b'\x0a\x0b')
    finally:
        rogue.close()
        good.shutdown()


def test_a_client_that_disconnects_and_reconnects_is_named_and_served(hub):
    a = _client(hub)
    a.shutdown()
    _wait(lambda: hub.counters.clients_disconnected == 1, 'the disconnect seen')
    b, c = _client(hub), _client(hub)
    try:
        b.send(can.Message(arbitration_id=0x701, data=[5], is_extended_id=False))
        assert _recv(c).arbitration_id == 0x701
        assert any('client 1' in line and 'disconnected' in line for line in hub.lines)
    finally:
        b.shutdown()
        c.shutdown()


def test_a_flood_of_frames_from_a_rogue_client_is_all_relayed(hub):
    """1,000 frames at once: none lost on the way to another client (the hub buffers, never drops)."""
    rogue = _raw(hub)
    listener = _client(hub)
    try:
        rogue.sendall(b''.join(f'< send 2{i % 256:02X} 1 {i % 256:x} >'.encode() for i in range(1000)))
        got = 0
        while got < 1000:
            _recv(listener)
            got += 1
        assert hub.counters.frames == 1000 and hub.counters.bad_lines == 0
    finally:
        rogue.close()
        listener.shutdown()


def test_line_codecs():
    assert parse_send('< send 1B8 3 1 a ff >') == (0x1B8, b'\x01\x0a\xff', False)
    assert format_frame(Frame(0x1B8, b'\x01\xff', 12.5, 'x')) == '< frame 1B8 12.500000 01FF >'
    assert format_frame(Frame(0x80, b'', 1.9999999, 'x')) == '< frame 080 2.000000  >'


def test_a_taken_port_is_named():
    with Hub('127.0.0.1', 0) as first:
        with pytest.raises(OSError, match=f'cannot listen on 127.0.0.1:{first.port}'):
            Hub('127.0.0.1', first.port).start()


def test_a_client_that_reads_nothing_is_dropped_and_the_others_are_served(hub, monkeypatch):
    """A client that never reads would make the hub buffer forever: past MAX_BACKLOG unread it is dropped."""
    import canopen_bus.hub as hub_module
    monkeypatch.setattr(hub_module, 'MAX_BACKLOG', 64 << 10)
    deaf = _raw(hub)
    port = hub.local_port('card')
    try:
        for i in range(250_000):  # ~10 MB: more than the loopback socket buffers hold
            port.send(0x1B8, bytes([i % 256] * 8))
            if i % 10_000 == 0 and any('reads nothing' in line for line in hub.lines):
                break
        _wait(lambda: any('reads nothing' in line for line in hub.lines), 'the deaf client dropped', timeout=30.0)
        good = _client(hub)
        port.send(0x701, b'\x05')
        assert _recv(good).arbitration_id == 0x701
        good.shutdown()
    finally:
        deaf.close()
