"""``acds bench``'s bus figures (entry-point group ``acds.bench``): the hub's frames/s through one client pair.

Two python-can ``socketcand`` clients on a hub of their own (a free loopback port): one sends
:data:`FRAMES` 8-byte frames as fast as its TCP socket takes them, the other receives them; the figure is frames
delivered per second of wall time from the first send to the last receipt (bounded: the receiver waits at most
:data:`TIMEOUT_S`, and the count delivered is what is reported).
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Any

FRAMES = 20000
TIMEOUT_S = 60.0


def hub_frames_per_s(frames: int = FRAMES) -> dict[str, Any]:
    import can

    from canopen_bus.hub import Hub

    logging.getLogger('can.interfaces.socketcand').setLevel(logging.ERROR)
    hub = Hub('127.0.0.1', 0, report=lambda _line: None).start()
    rx = tx = None
    try:
        tx = can.Bus(interface='socketcand', channel='vcan0', host='127.0.0.1', port=hub.port)
        rx = can.Bus(interface='socketcand', channel='vcan0', host='127.0.0.1', port=hub.port)
        probe = can.Message(arbitration_id=0x7FF, data=b'', is_extended_id=False)
        t_end = time.monotonic() + TIMEOUT_S
        while True:  # the hub relays to a client a moment after its rawmode reply: probe until one arrives
            assert time.monotonic() < t_end, f'the hub relayed no frame in {TIMEOUT_S} s'
            tx.send(probe)
            if rx.recv(0.05) is not None:
                break
        while rx.recv(0.05) is not None:
            pass
        got, done = [0], threading.Event()

        def receive() -> None:
            t_end = time.monotonic() + TIMEOUT_S
            while got[0] < frames and time.monotonic() < t_end:
                if rx.recv(0.5) is not None:
                    got[0] += 1
            done.set()

        reader = threading.Thread(target=receive, daemon=True)
        reader.start()
        msg = can.Message(arbitration_id=0x1B8, data=bytes(range(8)), is_extended_id=False)
        t0 = time.perf_counter()
        for _ in range(frames):
            tx.send(msg)
        done.wait(TIMEOUT_S + 1.0)
        elapsed = time.perf_counter() - t0
    finally:
        for bus in (tx, rx):
            if bus is not None:
                bus.shutdown()
        hub.stop()
    return {'hub_frames_sent': frames, 'hub_frames_delivered': got[0], 'hub_frames_per_s': round(got[0] / elapsed, 1)}


def bench(_args: Any) -> tuple[dict[str, Any], list[str]]:
    """The ``acds.bench`` protocol: (JSON fields, printed lines)."""
    r = hub_frames_per_s()
    return r, [f'CAN hub, one client pair (socketcand, 8-byte frames): {r["hub_frames_per_s"]:10.1f} frames/s  '
               f'({r["hub_frames_delivered"]} of {r["hub_frames_sent"]} delivered)']
