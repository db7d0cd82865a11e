"""Live view in Foxglove: a run's (or a bag's) topics over the Foxglove WebSocket protocol (issue 12 §4).

:class:`FoxgloveBridge` starts a ``foxglove-sdk`` WebSocket server (``ws://127.0.0.1:8765`` by default;
protocol ``foxglove.sdk.v1``) and is fed every message once, as a sink: by the run monitor (raw CDR, the
per-process graph), by the direct engine (CDR and the value it already holds) or by ``acds play`` (a
bag). What a client sees:

* every graph topic under its own name (``/acds/...``, ``/clock``), CDR-encoded, with its ROS 2 schema
  (``ros2msg`` text from the rosbags type store, as rosbag2 stores it in MCAP), stamped with sim time;
  the server's clock (``Capability.Time``) follows ``/clock``, so Foxglove's timeline is sim time;
* ``/tf`` (``foxglove.FrameTransforms``), one message per step of ``truth/odometry``: ECI → body (the
  attitude, q body→ECI), ECI → sun frame (z to the sun, y in the ecliptic: the sun line; fixed for the
  run, from the scenario's sun) and body → magnetometer (identity: the model's fluxgate axes are the body
  axes, the seeds give no mounting). Translations are zero: the frames share one origin, so the 3D panel
  shows the body tumbling about the sun line; the orbit position stays in ``truth/odometry``;
* ``/acds/view/*`` (JSON): what the layout plots in the study's units, with the scenario's limits beside
  each value so a plot draws them as lines: body rates and their magnitudes (deg/s) with the Mode 1A → 1B
  thresholds (where the mode logic compares |ω_i| with them: the missions' ``acds.limits`` plug-ins,
  :func:`acds_common.plugins.limits`), the sun
  angle (z body to the sun line, deg) with the capture cone, wheel momentum (ft-lb-s), the moment command
  (A·m²) with ±its saturation, and the mode. They are derived for the view only (never recorded).

Frames and limits come from the run's node parameters (:func:`acds_common.parameters.node_parameters`, also
stored in a bag as ``acds.params``), so a run and its bag are served alike. Derived messages are computed
only while a client subscribes to them. A slow client drops the oldest messages (the SDK's backlog):
pace the run (``--rtf``) or the replay (``--rate``) to watch every step.
"""

from __future__ import annotations

import json
import math
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from acds_common import topics, units
from acds_common.attitude import dcm_to_quat
from acds_common.cdr import Codec, stamp_ns
from acds_common.environment import Sun, SunConfig, ecliptic_normal_eci, sun_frame_dcm
from acds_common.frames import SUN_FRAME
from acds_common.graph import build_graph
from acds_common.mode_report import ModeReport
from acds_common.plugins import limits
from acds_common.scenario import SCHEMA
from foxglove.channels import FrameTransformsChannel
from foxglove.messages import FrameTransform, FrameTransforms, Quaternion, Timestamp, Vector3
from foxglove.websocket import Capability, ServerListener

import foxglove
from foxglove import Channel, Schema

from .bag.writer import typestore
from .launcher import LaunchError

#: The frame tree topic (Foxglove's 3D panel reads ``foxglove.FrameTransforms`` from any topic).
TF_TOPIC = '/tf'
#: Derived, view-only JSON topics.
VIEW_PREFIX = '/acds/view/'
VIEW_RATES = VIEW_PREFIX + 'rates'
VIEW_SUN_ANGLE = VIEW_PREFIX + 'sun_angle'
VIEW_WHEEL_MOMENTUM = VIEW_PREFIX + 'wheel_momentum'
VIEW_MOMENT = VIEW_PREFIX + 'moment_command'
VIEW_MODE = VIEW_PREFIX + 'mode'
_AXES = ('x', 'y', 'z')


class BridgeError(LaunchError):
    """The live view cannot start (port taken, bad host); the message is one line (a run fails with it)."""


def _param(params: dict[str, dict[str, Any]], node: str, section: str, key: str) -> Any:
    """A scenario value as node ``node`` received it (None when that node is not in the graph)."""
    return params.get(node, {}).get(SCHEMA[section][key].param_name(section, key))


def _json_schema(name: str, fields: dict[str, str]) -> Schema:
    """A named JSON Schema of a flat object ({field: 'number' | 'string'})."""
    body = {'type': 'object', 'properties': {f: {'type': t} for f, t in fields.items()}}
    return Schema(name=name, encoding='jsonschema', data=json.dumps(body).encode())


def _numbers(*fields: str) -> dict[str, str]:
    return dict.fromkeys(fields, 'number')


@dataclass(frozen=True)
class Frames:
    """Frame names of the graph (from its declared ``frame_id``s) and the fixed ECI → sun-frame rotation."""

    world: str
    body: str
    sun: str
    magnetometer: str | None
    sun_rotation_xyzw: tuple[float, float, float, float]


def frames_of(params: dict[str, dict[str, Any]]) -> Frames:
    """The frames of the graph built from ``params`` (its declared ``frame_id``s; the sun frame, in which no topic
    is expressed, :data:`acds_common.frames.SUN_FRAME`), its rotation from rigid_body's ``sun`` section."""
    graph = build_graph(params)
    outs = {out.topic: out for _spec, out in graph.outputs()}
    odom = outs[topics.TRUTH_ODOMETRY]
    sun = Sun(SunConfig(right_ascension_rad=_param(params, 'rigid_body', 'sun', 'right_ascension'),
                        declination_rad=_param(params, 'rigid_body', 'sun', 'declination')))
    rows = sun_frame_dcm(sun.direction_eci(0.0), ecliptic_normal_eci())  # rows: sun-frame axes in ECI
    q = dcm_to_quat(rows.T)  # sun frame → ECI
    mag = outs.get(topics.MAG_FIELD)
    return Frames(odom.frame_id, odom.child_frame_id, SUN_FRAME, mag.frame_id if mag is not None else None,
                  tuple(float(c) for c in q))


class FoxgloveBridge:
    """Serve the topics of a graph (its node ``params``) to Foxglove on ``host:port``; call it with each message.

    ``types`` (absolute topic → ROS type) defaults to the graph's outputs and ``/clock``; a bag passes
    its own. ``port`` 0 picks a free port (:attr:`port` says which).
    """

    def __init__(self, params: dict[str, dict[str, Any]], *, port: int, host: str,
                 types: dict[str, str] | None = None, name: str = 'acds') -> None:
        if types is None:
            graph = build_graph(params)
            types = {topics.resolve(out.topic): out.msg_type for _spec, out in graph.outputs()}
            types[topics.CLOCK] = topics.TYPES[topics.CLOCK]
        self.frames = frames_of(params)
        self._context = foxglove.Context()
        self._subscriptions = _Listener()
        try:
            self.server = foxglove.start_server(name=name, host=host, port=port, capabilities=[Capability.Time],
                                                context=self._context, server_listener=self._subscriptions)
        except (RuntimeError, ValueError, OSError) as exc:
            raise BridgeError(f'Foxglove server on {host}:{port}: {exc}') from None
        store = typestore()
        self._codecs = {topic: Codec(ty) for topic, ty in types.items()}
        self.channels = {topic: Channel(topic, message_encoding='cdr', context=self._context, schema=Schema(
            name=ty, encoding='ros2msg', data=store.generate_msgdef(ty, ros_version=2)[0].encode()))
            for topic, ty in sorted(types.items())}
        self._tf = FrameTransformsChannel(TF_TOPIC, context=self._context)
        self._limits = {  # None: not in this graph (or not this mode logic's)
            'rates': limits(params).get('rate_thresholds'),
            'cone': _param(params, 'ascs_mode_manager', 'modes', 'capture_cone'),
            'max_moment': _param(params, 'acds_controller', 'controller', 'max_moment_am2'),
        }
        views = {
            VIEW_RATES: (topics.GYRO, 'acds.view.Rates', _numbers(*(f'{a}_deg_s' for a in _AXES),
                                                                  *(f'abs_{a}_deg_s' for a in _AXES),
                                                                  *(f'threshold_{a}_deg_s' for a in _AXES))),
            VIEW_SUN_ANGLE: (topics.TRUTH_SUN_COSINES, 'acds.view.SunAngle',
                             _numbers('sun_angle_deg', 'capture_cone_deg')),
            VIEW_WHEEL_MOMENTUM: (topics.WHEEL_MOMENTUM, 'acds.view.WheelMomentum',
                                  _numbers(*(f'{a}_ft_lb_s' for a in _AXES))),
            VIEW_MOMENT: (topics.MOMENT_COMMAND, 'acds.view.MomentCommand',
                          _numbers(*(f'{a}_am2' for a in _AXES), 'max_am2', 'min_am2')),
            VIEW_MODE: (topics.MODE, 'acds.view.Mode', {'mode': 'string'}),
        }
        self._views: dict[str, tuple[str, Any]] = {}
        for view, (source, schema_name, fields) in views.items():
            if topics.resolve(source) in types:
                self._views[topics.resolve(source)] = (view, Channel(
                    view, message_encoding='json', schema=_json_schema(schema_name, fields), context=self._context))
        self._odometry = topics.resolve(topics.TRUTH_ODOMETRY)
        self._clock_ns = 0
        self.error: str | None = None
        self._lock = threading.Lock()

    # ---- serving --------------------------------------------------------------------------------------
    @property
    def view_channels(self) -> dict[str, Any]:
        """The derived JSON channels by topic (``/acds/view/...``)."""
        return {view: channel for view, channel in self._views.values()}

    @property
    def port(self) -> int:
        """The port the server listens on."""
        return int(self.server.port)

    def wait_for_client(self, timeout_s: float) -> bool:
        """Wait until a client subscribes to a channel and the SDK routes every channel subscribed by then to it
        (True), or ``timeout_s`` passed (False): what ``acds play`` logs after this reaches the client from its
        first message (the listener hears of a subscription before its sink is attached: a play that started on
        the subscription alone lost 7 of a bag's 31 odometry messages under load)."""
        deadline = time.monotonic() + timeout_s
        if not self._subscriptions.wait(lambda subscribed: bool(subscribed), timeout_s):
            return False
        return self.wait_for_subscriptions(self._subscriptions.topics(), max(0.0, deadline - time.monotonic()))

    def wait_for_subscriptions(self, wanted: set[str], timeout_s: float) -> bool:
        """Wait until clients subscribe to every topic of ``wanted`` and the SDK routes each of those channels to
        them (True), or ``timeout_s`` passed (False). The listener hears of a subscription before the server has
        attached its sink to the channel: until then a message logged there reaches nobody."""
        deadline = time.monotonic() + timeout_s
        if not self._subscriptions.wait(lambda subscribed: wanted <= subscribed, timeout_s):
            return False
        channels = {**self.channels, TF_TOPIC: self._tf, **self.view_channels}
        while not all(channels[t].has_sinks() for t in wanted):
            if time.monotonic() > deadline:
                return False
            self._subscriptions.wait(lambda _subscribed: False, 0.01)  # poll the SDK's routing, with the deadline
        return True

    def __call__(self, topic: str, data: bytes, value: Any = None) -> None:
        """One message of ``topic`` (absolute): raw CDR, and its decoded value when the caller holds it.

        Never raises (it runs in the monitor's thread): a failure is printed once and the view stops.
        """
        if self.error is not None:
            return
        try:
            self._serve(topic, data, value)
        except Exception as exc:  # noqa: BLE001 (the run goes on without its live view, and says so)
            with self._lock:
                if self.error is None:
                    self.error = f'{type(exc).__name__}: {exc}'
                    print(f'[foxglove] live view stopped on {topic}: {self.error}', file=sys.stderr, flush=True)

    def _serve(self, topic: str, data: bytes, value: Any) -> None:
        channel = self.channels.get(topic)
        if channel is None:
            return
        codec = self._codecs[topic]
        if topic == topics.CLOCK:
            self._clock_ns = t_ns = stamp_ns(data)
            self.server.broadcast_time(t_ns)
        else:
            t_ns = stamp_ns(data) if codec.stamped else self._clock_ns
        channel.log(data, log_time=t_ns)
        view = self._views.get(topic)
        wants_tf = topic == self._odometry and self._tf.has_sinks()
        if not wants_tf and (view is None or not view[1].has_sinks()):
            return
        if value is None:
            value = codec.decode(data)[1]
        if wants_tf:
            self._tf.log(self.transforms(t_ns, value.orientation), log_time=t_ns)
        if view is not None:
            message = self._view_message(view[0], value)
            if message is not None:
                view[1].log(message, log_time=t_ns)

    def transforms(self, t_ns: int, q_body_to_eci: tuple[float, float, float, float]) -> FrameTransforms:
        """The step's frame tree: ECI → body (``q_body_to_eci``), ECI → sun frame, body → magnetometer."""
        stamp = Timestamp(sec=t_ns // 1_000_000_000, nsec=t_ns % 1_000_000_000)

        def tf(parent: str, child: str, q: tuple[float, ...]) -> FrameTransform:
            return FrameTransform(timestamp=stamp, parent_frame_id=parent, child_frame_id=child,
                                  translation=Vector3(x=0.0, y=0.0, z=0.0),
                                  rotation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3]))

        f = self.frames
        items = [tf(f.world, f.body, q_body_to_eci), tf(f.world, f.sun, f.sun_rotation_xyzw)]
        if f.magnetometer is not None:
            items.append(tf(f.body, f.magnetometer, (0.0, 0.0, 0.0, 1.0)))
        return FrameTransforms(transforms=items)

    def _view_message(self, view: str, value: Any) -> dict[str, Any] | None:
        """The derived view message of one source value, study units (:mod:`acds_common.units`)."""
        lim = self._limits
        if view == VIEW_RATES:
            out = {f'{a}_deg_s': math.degrees(w) for a, w in zip(_AXES, value[0], strict=True)}
            out.update({f'abs_{a}': abs(out[a]) for a in out})
            if lim['rates'] is not None:
                out.update({f'threshold_{a}_deg_s': math.degrees(w) for a, w in zip(_AXES, lim['rates'], strict=True)})
            return out
        if view == VIEW_SUN_ANGLE:
            out = {'sun_angle_deg': math.degrees(math.acos(max(-1.0, min(1.0, value[2]))))}
            if lim['cone'] is not None:
                out['capture_cone_deg'] = math.degrees(lim['cone'])
            return out
        if view == VIEW_WHEEL_MOMENTUM:
            return {f'{a}_ft_lb_s': h / units.FT_LB_S_NMS for a, h in zip(_AXES, value, strict=True)}
        if view == VIEW_MOMENT:
            out = {f'{a}_am2': m for a, m in zip(_AXES, value, strict=True)}
            if lim['max_moment'] is not None:
                out.update(max_am2=lim['max_moment'], min_am2=-lim['max_moment'])
            return out
        report = ModeReport.decode(value)
        return None if report is None else {'mode': report.mode}

    def close(self) -> None:
        """Stop the server (clients see the connection close)."""
        self.server.stop()


class _Listener(ServerListener):
    """foxglove-sdk server listener: the topics clients subscribed to (``acds play`` waits for a client)."""

    def __init__(self) -> None:
        self._changed = threading.Condition()
        self._subscribed: set[str] = set()

    def on_subscribe(self, _client: Any, channel: Any) -> None:
        with self._changed:
            self._subscribed.add(channel.topic)
            self._changed.notify_all()

    def wait(self, done: Callable[[set[str]], bool], timeout_s: float) -> bool:
        """Wait until ``done(subscribed topics)`` holds (True), or ``timeout_s`` passed (False)."""
        with self._changed:
            return self._changed.wait_for(lambda: done(self._subscribed), timeout_s)

    def topics(self) -> set[str]:
        """The topics subscribed so far."""
        with self._changed:
            return set(self._subscribed)


def live_view(port: int, host: str) -> Callable[[dict[str, dict[str, Any]]], FoxgloveBridge]:
    """A factory for the engines (``live=``): called with the run's node parameters, returns the bridge."""
    return lambda params: FoxgloveBridge(params, port=port, host=host)


__all__ = ['TF_TOPIC', 'BridgeError', 'FoxgloveBridge', 'Frames', 'frames_of',
           'live_view']
