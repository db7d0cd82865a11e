"""The live view in Foxglove (issue 12 §4): a real WebSocket client speaks the Foxglove protocol to the bridge.

The client (``websockets``) opens ``foxglove.sdk.v1``, reads ``serverInfo`` and the ``advertise``d channels,
sends ``subscribe`` and decodes the binary message frames (opcode 1, subscription id, timestamp, payload):
ROS 2 CDR for the graph's topics, protobuf ``foxglove.FrameTransforms`` on ``/tf``, JSON on ``/acds/view/*``.
"""

from __future__ import annotations

import json
import math
import struct
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from acds_common import topics
from acds_common.parameters import node_parameters
from acds_common.scenario import load_scenario
from acds_runtime.bag.writer import typestore
from acds_runtime.direct import DirectRun
from acds_runtime.foxglove_bridge import TF_TOPIC, VIEW_MODE, VIEW_RATES, FoxgloveBridge, Frames, frames_of, live_view
from acds_runtime.foxglove_layout import layout_json
from acds_runtime.testing import read_until
from websockets.sync.client import connect

ROOT = Path(__file__).resolve().parents[1]
ODOMETRY = topics.resolve(topics.TRUTH_ODOMETRY)
B_BODY = topics.resolve(topics.TRUTH_B_BODY)
LOCAL = '127.0.0.1'


class FoxgloveClient:
    """A minimal Foxglove WebSocket client: advertise, subscribe, collect message frames by topic."""

    def __init__(self, ws: Any) -> None:
        self.ws = ws
        info = json.loads(self.ws.recv(timeout=10))
        assert info['op'] == 'serverInfo' and 'time' in info['capabilities'], info
        self.channels: dict[int, dict[str, Any]] = {}
        self.received: dict[str, list[tuple[int, bytes]]] = {}
        self.times: list[int] = []

    def by_topic(self, topic: str) -> dict[str, Any]:
        return next(c for c in self.channels.values() if c['topic'] == topic)

    def _frame(self, frame: str | bytes) -> None:
        if isinstance(frame, bytes):
            if frame[0] == 0x01:  # message data: subscription id, log time, payload
                sub, t_ns = struct.unpack_from('<IQ', frame, 1)
                self.received.setdefault(self.channels[sub]['topic'], []).append((t_ns, frame[13:]))
            elif frame[0] == 0x02:  # server time
                self.times.append(struct.unpack_from('<Q', frame, 1)[0])
            return
        msg = json.loads(frame)
        if msg['op'] == 'advertise':
            self.channels.update({c['id']: c for c in msg['channels']})

    def advertised(self, wanted: set[str], timeout_s: float = 10.0) -> None:
        deadline = time.monotonic() + timeout_s
        while not wanted <= {c['topic'] for c in self.channels.values()}:
            self._frame(self.ws.recv(timeout=max(0.01, deadline - time.monotonic())))

    def subscribe(self, wanted: set[str]) -> None:
        subs = [{'id': cid, 'channelId': cid} for cid, c in self.channels.items() if c['topic'] in wanted]
        self.ws.send(json.dumps({'op': 'subscribe', 'subscriptions': subs}))

    def collect(self, done: Callable[[], bool], timeout_s: float) -> None:
        deadline = time.monotonic() + timeout_s
        while not done() and time.monotonic() < deadline:
            try:
                self._frame(self.ws.recv(timeout=0.2))
            except TimeoutError:
                continue
            except Exception:  # noqa: BLE001 (the server closed at the end of the run)
                return


@contextmanager
def foxglove_client(port: int) -> Iterator[FoxgloveClient]:
    """A connected :class:`FoxgloveClient` (subprotocol ``foxglove.sdk.v1``), closed on exit."""
    with connect(f'ws://{LOCAL}:{port}', subprotocols=['foxglove.sdk.v1'], open_timeout=10) as ws:
        yield FoxgloveClient(ws)


def _pb(buf: bytes) -> dict[int, list[Any]]:
    """Protobuf wire format → {field: [values]} (varint, 64-bit as a double, length-delimited as bytes)."""
    out: dict[int, list[Any]] = {}
    i = 0
    while i < len(buf):
        key, i = _varint(buf, i)
        field, wire = key >> 3, key & 7
        if wire == 0:
            value, i = _varint(buf, i)
        elif wire == 1:
            value, i = struct.unpack_from('<d', buf, i)[0], i + 8
        elif wire == 2:
            n, i = _varint(buf, i)
            value, i = buf[i:i + n], i + n
        else:
            raise AssertionError(f'unexpected protobuf wire type {wire}')
        out.setdefault(field, []).append(value)
    return out


def _varint(buf: bytes, i: int) -> tuple[int, int]:
    shift = value = 0
    while True:
        b = buf[i]
        i += 1
        value |= (b & 0x7F) << shift
        shift += 7
        if not b & 0x80:
            return value, i


def frame_transforms(payload: bytes) -> dict[tuple[str, str], tuple[int, tuple[float, ...]]]:
    """A foxglove.FrameTransforms message → {(parent, child): (stamp ns, rotation x, y, z, w)}."""
    out = {}
    for raw in _pb(payload)[1]:
        tf = _pb(raw)
        stamp = _pb(tf[1][0])
        t_ns = stamp.get(1, [0])[0] * 1_000_000_000 + stamp.get(2, [0])[0]
        rot = _pb(tf[5][0])
        out[(tf[2][0].decode(), tf[3][0].decode())] = (t_ns, tuple(rot.get(f, [0.0])[0] for f in (1, 2, 3, 4)))
    return out


def _rotate(q: tuple[float, ...], v: np.ndarray) -> np.ndarray:
    x, y, z, w = q
    u = np.array([x, y, z])
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


def _decode(topic: str, data: bytes) -> Any:
    return typestore().deserialize_cdr(data, topics.type_of(topic))


def _stamp_ns(msg: Any) -> int:
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


def _check_frames(client: FoxgloveClient, frames: Frames) -> None:
    """Each /tf message carries ECI → body = the odometry orientation of its step, the sun line, the magnetometer."""
    odometry = {t: _decode(ODOMETRY, data) for t, data in client.received[ODOMETRY]}
    world, body, sun, mag = frames.world, frames.body, frames.sun, frames.magnetometer
    checked = 0
    for t_ns, payload in client.received[TF_TOPIC]:
        tfs = frame_transforms(payload)
        assert set(tfs) == {(world, body), (world, sun), (body, mag)}
        assert all(stamp == t_ns for stamp, _q in tfs.values())
        if t_ns in odometry:
            o = odometry[t_ns].pose.pose.orientation
            assert tfs[(world, body)][1] == (o.x, o.y, o.z, o.w)
            checked += 1
        # heao_b_acquisition: sun at RA 0, Dec 0 (the vernal equinox direction), so sun-frame z is ECI x.
        assert np.allclose(_rotate(tfs[(world, sun)][1], np.array([0.0, 0.0, 1.0])), [1, 0, 0], atol=1e-12)
        assert tfs[(body, mag)][1] == (0.0, 0.0, 0.0, 1.0)
    assert checked >= 5, f'only {checked} frame transforms matched an odometry message of the same step'


def test_graph_run_serves_truth_and_frames_to_a_foxglove_client(launch_graph: Any) -> None:
    """The six-process graph, paced so the client subscribes early: truth messages and /tf arrive, exact."""
    wanted = {ODOMETRY, B_BODY, TF_TOPIC, topics.CLOCK}
    with (launch_graph('heao_b_acquisition', steps=200, rtf=40.0, live=live_view(0, LOCAL)) as graph,
          foxglove_client(graph.live_sink.port) as client):
        frames = graph.live_sink.frames
        client.advertised(wanted | set(graph.graph.truth_topics()))
        channel = client.by_topic(ODOMETRY)
        assert (channel['encoding'], channel['schemaName'], channel['schemaEncoding']) == (
            'cdr', 'nav_msgs/msg/Odometry', 'ros2msg')
        assert channel['schema'] == typestore().generate_msgdef('nav_msgs/msg/Odometry', ros_version=2)[0]
        assert client.by_topic(TF_TOPIC)['schemaName'] == 'foxglove.FrameTransforms'
        client.subscribe(wanted)

        def enough() -> bool:
            return all(len(client.received.get(t, [])) >= 20 for t in (ODOMETRY, B_BODY, TF_TOPIC))
        reader = threading.Thread(target=client.collect, args=(enough, 60.0))
        reader.start()
        result = graph.wait()
        reader.join()
        kept = {topics.resolve(t): msgs for t, msgs in graph.monitor.snapshot().items()}
    assert result.steps == 200
    assert enough(), {t: len(v) for t, v in client.received.items()}
    for topic in (ODOMETRY, B_BODY):  # the very bytes the nodes published, stamped with sim time
        recorded = set(kept[topic])
        for t_ns, data in client.received[topic]:
            assert data in recorded
            assert t_ns == _stamp_ns(_decode(topic, data))
    _check_frames(client, frames)
    assert client.times and client.times == sorted(client.times), 'the server clock follows /clock'


def test_direct_engine_serves_the_same_view_with_the_scenario_limits() -> None:
    scenario = load_scenario('heao_b_acquisition')
    closes = []

    def bridge_closed_by_the_test(params: dict[str, Any]) -> FoxgloveBridge:
        """The run's bridge, closed once the client holds everything: the engine ends in a fraction of a second,
        and stopping the server then drops what a loaded machine had not sent yet (not what is tested here)."""
        bridge = live_view(0, LOCAL)(params)
        closes.append(bridge.close)
        bridge.close = lambda: None
        return bridge
    run = DirectRun(scenario, steps=30, live=bridge_closed_by_the_test)
    try:
        with foxglove_client(run.live_sink.port) as client:
            wanted = {ODOMETRY, TF_TOPIC, VIEW_RATES, VIEW_MODE}
            client.advertised(wanted)
            client.subscribe(wanted)
            assert run.live_sink.wait_for_subscriptions(wanted, 10.0), 'the client subscriptions never reached the server'
            run.run()
            client.collect(lambda: all(len(client.received.get(t, [])) >= 31 for t in (ODOMETRY, TF_TOPIC)), 30.0)
    finally:
        closes[0]()
    assert len(client.received[ODOMETRY]) == 31 and len(client.received[TF_TOPIC]) == 31
    _check_frames(client, run.live_sink.frames)
    rates = [json.loads(p) for _t, p in client.received[VIEW_RATES]]
    thresholds = [math.degrees(w) for w in scenario.get('modes', 'rate_thresholds')]
    assert [rates[0][f'threshold_{a}_deg_s'] for a in 'xyz'] == pytest.approx(thresholds)
    assert [rates[0][f'{a}_deg_s'] for a in 'xyz'] == pytest.approx([1.0, 1.0, 1.0])  # separation: 1 deg/s per axis
    assert {json.loads(p)['mode'] for _t, p in client.received[VIEW_MODE]} == {'mode_1a'}


def test_layout_file_is_generated_and_names_served_topics() -> None:
    text = (ROOT / 'foxglove' / 'acds_layout.json').read_text()
    assert text == layout_json(), 'regenerate: .venv/bin/python -m acds_runtime.foxglove_layout > foxglove/acds_layout.json'
    bridge = FoxgloveBridge(node_parameters(load_scenario('heao_b_acquisition'), 1, 0.0), port=0, host=LOCAL)
    try:
        served = set(bridge.channels)
        views = {view: json.loads(channel.schema().data)['properties'] for view, channel in bridge.view_channels.items()}
    finally:
        bridge.close()
    paths = []

    def walk(node: Any) -> None:
        if isinstance(node, dict):
            for key, value in node.items():
                if key in ('value', 'topicToRender') and isinstance(value, str):
                    paths.append(value)
                walk(value)
        elif isinstance(node, list):
            for item in node:
                walk(item)
    walk(json.loads(text))
    assert len(paths) > 15
    for path in paths:
        topic, _, field = path.partition('.')
        assert topic in served or topic in views, f'layout path {path}: topic not served'
        if topic in views:
            assert field in views[topic], f'layout path {path}: the view has no field {field}'


def test_play_serves_a_bag_the_same_way(tmp_path: Path, play_domain: int) -> None:
    """``acds play BAG --foxglove 0``: waits for the client, then serves the bag's truth and its frames."""
    import os
    import re
    import subprocess
    import sys

    bag = tmp_path / 'bag'
    DirectRun(load_scenario('heao_b_acquisition'), steps=30, record=bag).run()
    env = dict(os.environ)
    play = subprocess.Popen([sys.executable, '-m', 'acds_cli', 'play', str(bag), '--domain', str(play_domain),
                             '--foxglove', '0', '--wait', '60'], stderr=subprocess.PIPE, text=True, env=env)
    try:
        said = read_until(play, lambda line: 'Foxglove live view on ws://' in line)
        port = int(re.findall(r'Foxglove live view on ws://127\.0\.0\.1:(\d+)', said)[-1])
        with foxglove_client(port) as client:
            wanted = {ODOMETRY, TF_TOPIC}
            client.advertised(wanted)
            client.subscribe(wanted)
            client.collect(lambda: False, 30.0)  # until play ends and closes the server
        assert play.wait(timeout=60) == 0
    finally:
        if play.poll() is None:
            play.kill()
            play.wait()
    assert len(client.received[ODOMETRY]) == 31
    _check_frames(client, frames_of(node_parameters(load_scenario('heao_b_acquisition'), 1, 0.0)))
