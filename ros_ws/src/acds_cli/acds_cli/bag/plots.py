"""``acds plot``: a bag → figures in the layout and units of the study's figures (PNG, SVG or PDF).

The common figures (after seed 002's): Fig. 4-14 (direction cosines B33, B23, B13 against the sun frame),
Figs. 4-15 … 4-17 (roll/pitch/yaw responses: body rate deg/s, wheel momentum ft-lb-sec, magnetic moment A·m²),
Fig. 4-18 / 4-43 / 4-51 (magnetic moments and the angle between the Earth field and the momentum vector), the
sun angle (body z to the sun line),
plus the mode timeline. A figure whose topics are absent is skipped. Each mission's own figures are plug-ins
(entry-point group ``acds.plots``, :mod:`acds_cli.bag.mission_plots`), chosen by the nodes that ran and the
sections they received.

What an ACS engineer reads at a glance: every time plot marks the mode
transitions and the acquisition capture (labelled vertical lines, from the
``mode`` stream), the rate plots carry the mode logic's rate thresholds, the
moment plots ± the maximum moment, the sun-angle plot the capture cone — all
taken from the parameters the nodes ran with (stored in the bag; the thresholds and the cone as the
missions' ``acds.limits`` plug-ins read them, :func:`acds_common.plugins.limits`). Each title
names the scenario and the run. Time axes are sim minutes. The series are
gathered in one streaming pass over the bag (only the plotted fields are kept),
and the output folder is checked before the bag is read.
"""

from __future__ import annotations

import math
from array import array
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from acds_common import topics, units
from acds_common.mode_report import ModeReport, transitions
from acds_common.parameters import ConfigError, normalize, section
from acds_common.plugins import limits
from acds_runtime.bag.reader import Bag, open_bag
from acds_runtime.bag.writer import BagError, check_out_dir, typestore

from . import FORMATS, mission_plots

AXES = (('x', 'roll'), ('y', 'pitch'), ('z', 'yaw'))
#: The sun-angle plot's sections of the time owner's parameters (the rigid body's environment).

Gathered = dict[str, tuple[array, Any]]


#: The most steps a plotted series keeps: a longer run is plotted at every k-th step (the same steps on every
#: topic, so series still combine at common stamps), and plotting takes bounded memory at any run length.
MAX_PLOT_STEPS = 20_000


def _gather(bag: Bag, vectors: dict[str, Callable[[Any], list[float]]],
            texts: dict[str, Callable[[Any], Any]], max_steps: int = MAX_PLOT_STEPS) -> Gathered:
    """{topic: (timestamps ns, values)} in one pass over the bag: numbers packed as doubles, other values a list.

    Numeric series keep at most about ``max_steps`` steps (every k-th control step, k from the longest series);
    the ``texts`` (the mode stream: every transition) are kept whole, and a text message whose bytes after its stamp
    are those of the one before is not deserialized again: its getter's value is the one before (a ``texts`` getter
    reads no stamp; the mode changes a few times in a run of tens of thousands of steps).
    """
    ts = typestore()
    getters = {topics.resolve(t): get for t, get in (*vectors.items(), *texts.items()) if bag.has(t)}
    whole = {topics.resolve(x) for x in texts}
    out: Gathered = {t: (array('q'), [] if t in whole else array('d')) for t in getters}
    dt = bag.control_period_ns or 0
    longest = max((bag.count(t) for t in getters if t not in whole), default=0)
    stride = max(1, math.ceil(longest / max_steps)) if dt > 0 else 1
    last: dict[str, tuple[bytes, Any]] = {}
    for topic, t, data in bag.messages(getters):
        if stride > 1 and topic not in whole and (t // dt) % stride:
            continue
        stamps, values = out[topic]
        stamps.append(t)
        if topic in whole:
            body = data[12:]  # after the encapsulation and the header's stamp
            seen = last.get(topic)
            if seen is None or seen[0] != body:
                seen = last[topic] = body, getters[topic](ts.deserialize_cdr(data, bag.types[topic]))
            values.append(seen[1])
        else:
            values.extend(getters[topic](ts.deserialize_cdr(data, bag.types[topic])))
    return out


def _series(gathered: Gathered, topic: str, width: int = 3) -> tuple[np.ndarray, np.ndarray]:
    stamps, values = gathered.get(topics.resolve(topic), ((), ()))
    if not len(stamps):
        return np.zeros(0), np.zeros((0, width))
    return np.asarray(stamps, dtype=float) / 60e9, np.asarray(values, dtype=float).reshape(-1, width)


def _v3(v: Any) -> list[float]:
    return [v.x, v.y, v.z]


def odometry_values(m: Any) -> list[float]:
    """ω body (rad/s) and q body→ECI (x, y, z, w) of a ``truth/odometry`` message."""
    q = m.pose.pose.orientation
    return [*_v3(m.twist.twist.angular), q.x, q.y, q.z, q.w]


def mode_of(m: Any) -> tuple[str, str, bool]:
    """(mode, this step's transition cause, captured) of a ``mode`` message ('', '', False when empty)."""
    if not m.status:
        return '', '', False
    report = ModeReport.from_values(m.status[0].message, ((v.key, v.value) for v in m.status[0].values))
    return report.mode, report.cause, report.captured


def _angle_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    na, nb = np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1)
    with np.errstate(invalid='ignore', divide='ignore'):
        c = np.einsum('ij,ij->i', a, b) / (na * nb)
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))


def _common(t1: np.ndarray, t2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Indices of equal timestamps in two sorted series."""
    _, i1, i2 = np.intersect1d(np.round(t1 * 60e9).astype(np.int64), np.round(t2 * 60e9).astype(np.int64),
                               return_indices=True)
    return i1, i2


def sun_angle_deg(q_body_to_eci_xyzw: np.ndarray, sun_eci_unit: np.ndarray) -> np.ndarray:
    """Angle (deg) between body z and the sun line, per sample: z_body in ECI is the third column of
    R(q) (body → ECI), (2(xz + yw), 2(yz − xw), 1 − 2(x² + y²)); ``sun_eci_unit`` (n, 3) or (3,)."""
    x, y, z, w = (np.asarray(q_body_to_eci_xyzw, dtype=float)[:, i] for i in range(4))
    z_eci = np.column_stack([2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)])
    cos = np.einsum('ij,ij->i', z_eci, np.broadcast_to(sun_eci_unit, z_eci.shape))
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


@dataclass
class RunContext:
    """What the figures mark, from the bag: the run's name and the parameters its nodes ran with."""

    scenario: str
    run_id: str
    params: dict[str, dict[str, Any]] = field(default_factory=dict)
    #: Every node that ran, as the bag records its parameters (a vehicle's: ``<vehicle>/<node>``).
    nodes: tuple[str, ...] = ()
    #: Mode transitions and capture: [{t_min, from, to, cause}] (:func:`acds_common.mode_report.transitions`).
    events: list[dict[str, Any]] = field(default_factory=list)

    @property
    def vehicles(self) -> list[str]:
        """The formation's vehicles, by name; [] for a single vehicle: those the formation dynamics flew
        (``formation_vehicles``, with vehicles that run no node, e.g. a passive vehicle) and the
        prefixes of the vehicles' nodes."""
        flown = self.params.get('formation_dynamics', {}).get('formation_vehicles') or ()
        return sorted({*flown, *(node.rpartition('/')[0] for node in self.nodes if '/' in node)})

    def section(self, node: str, name: str) -> dict[str, Any] | None:
        """{field: SI value} of scenario section ``name`` as node ``node`` received it (None: not recorded)."""
        return section(self.params[node], name) if node in self.params else None

    def rate_thresholds_deg_s(self) -> np.ndarray | None:
        """The body-rate thresholds the mode logic compares |ω_i| with, deg/s per axis (None: no mission's
        :func:`acds_common.plugins.limits` gives them for this run)."""
        thresholds = limits(self.params).get('rate_thresholds')
        return None if thresholds is None else np.degrees(thresholds)

    def capture_cone_deg(self) -> float | None:
        """The acquisition capture cone, deg (None: no mission's :func:`acds_common.plugins.limits` gives one)."""
        cone = limits(self.params).get('capture_cone')
        return None if cone is None else math.degrees(cone)

    def max_moment_am2(self) -> tuple[np.ndarray, str] | None:
        """± the maximum moment per axis (A·m²) and what it is: the controller's command saturation, else the
        coils' (the em_driver's ``coil_max_moment_am2``)."""
        controller = self.section('acds_controller', 'controller')
        if controller is not None:
            return np.full(3, controller['max_moment_am2']), 'command limit'
        driver = self.section('em_driver', 'em_driver')
        return None if driver is None else (np.asarray(driver['coil_max_moment_am2'], dtype=float), 'coil maximum')

    def sun_eci(self) -> np.ndarray | None:
        """The scenario's sun direction in ECI (the rigid body's sun model; fixed over a run)."""
        if 'rigid_body' not in self.params:
            return None
        from dynamics.configuration import RIGID_BODY_SECTIONS, build_rigid_body
        model = build_rigid_body(*(self.section('rigid_body', s) for s in RIGID_BODY_SECTIONS))
        return model.sun.direction_eci(0.0)


def run_context(bag: Bag) -> RunContext:
    """The scenario, run id and node parameters stored in the bag (parameters it cannot normalize are left out)."""
    recorded = yaml.safe_load(bag.info.get('params', '') or '{}') or {}
    params = {}
    for node, given in recorded.items():
        try:
            params[node] = normalize(node, given)
        except (ConfigError, KeyError):
            continue
    name = bag.info.get('scenario_name', bag.path.name)
    return RunContext(name, bag.info.get('run_id') or bag.path.name, params, tuple(sorted(recorded)))


def _mark_events(axs: list[Any], events: list[dict[str, Any]]) -> None:
    """Vertical lines at each mode transition and capture on every axes; labels on the top one."""
    for tr in events:
        capture = tr['to'] == 'capture'
        for i, ax in enumerate(axs):
            ax.axvline(tr['t_min'], color='tab:red' if capture else 'tab:gray', ls='--', lw=0.9,
                       label=f'_event {tr["to"]}')
            if i == 0:
                ax.text(tr['t_min'], 1.0, f' {tr["to"]}', transform=ax.get_xaxis_transform(), rotation=90,
                        va='top', ha='right', fontsize=7, color='tab:red' if capture else 'dimgray')


def _hlines(ax: Any, value: float, label: str, *, both: bool = True) -> None:
    """A labelled limit line at ``value`` (and at −value when ``both``)."""
    for v in ((value, -value) if both else (value,)):
        ax.axhline(v, color='tab:orange', ls=':', lw=1.0, label=label if v == value else f'_{label}')
    ax.legend(fontsize=7, loc='best')


def figures(bag: Bag) -> list[tuple[str, Any]]:
    """Every figure the bag's topics allow: [(file stem, matplotlib figure)]."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    ctx = run_context(bag)
    vectors: dict[str, Callable[[Any], list[float]]] = {
        topics.TRUTH_SUN_COSINES: lambda m: _v3(m.vector),
        topics.TRUTH_ODOMETRY: odometry_values,
        topics.WHEEL_MOMENTUM: lambda m: _v3(m.vector),
        topics.DIPOLE_AVG: lambda m: _v3(m.vector),
        topics.TRUTH_B_BODY: lambda m: _v3(m.magnetic_field),
    }
    if not bag.has(topics.TRUTH_ODOMETRY):
        vectors[topics.GYRO] = lambda m: _v3(m.angular_velocity)
    missions = mission_plots.chosen(ctx)
    for mission in missions:
        vectors.update(mission.vectors(ctx))

    data = _gather(bag, vectors, {topics.MODE: mode_of})
    mode_stamps, mode_values = data.get(topics.resolve(topics.MODE), ((), []))
    history = [(t / 1e9, *v) for t, v in zip(mode_stamps, mode_values, strict=True)]
    ctx.events = transitions(history)
    out: list[tuple[str, Any]] = []

    def finish(fig: Any, axs: list[Any], stem: str, title: str) -> None:
        _mark_events(axs, ctx.events)
        fig.suptitle(f'{title}\n{ctx.scenario} — run {ctx.run_id}', fontsize=10)
        fig.supxlabel('time, min')
        fig.tight_layout()
        out.append((stem, fig))

    # Fig. 4-14: direction cosines against the sun frame
    if bag.has(topics.TRUTH_SUN_COSINES):
        t, b = _series(data, topics.TRUTH_SUN_COSINES)
        fig, axs = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
        for ax, (i, label) in zip(axs, ((2, 'B33'), (1, 'B23'), (0, 'B13')), strict=True):
            ax.plot(t, b[:, i], lw=0.8)
            ax.set_ylabel(label)
            ax.set_ylim(-1.05, 1.05)
            ax.grid(alpha=0.3)
        finish(fig, list(axs), 'fig_4-14_direction_cosines', 'Direction cosines, body vs sun frame (cf. Fig. 4-14)')

    t_w, wq = _series(data, topics.TRUTH_ODOMETRY, 7)
    w, quat = wq[:, :3], wq[:, 3:]
    if not len(t_w):
        t_w, w = _series(data, topics.GYRO)
    t_h, h = _series(data, topics.WHEEL_MOMENTUM)
    t_m, mm = _series(data, topics.DIPOLE_AVG)
    thresholds, max_moment = ctx.rate_thresholds_deg_s(), ctx.max_moment_am2()

    # Figs. 4-15 … 4-17: per-axis responses
    if len(t_w) or len(t_h) or len(t_m):
        for fig_no, (i, (axis, label)) in zip(('4-15', '4-16', '4-17'), enumerate(AXES), strict=True):
            rows = [(t_w, np.degrees(w[:, i]) if len(t_w) else None, f'ω{axis}, deg/s', 'rate'),
                    (t_h, units.nms_to_ftlbs(h[:, i]) if len(t_h) else None, f'h{axis}, ft-lb-sec', ''),
                    (t_m, mm[:, i] if len(t_m) else None, f'M{axis}, A·m²', 'moment')]
            rows = [r for r in rows if r[1] is not None]
            fig, axs = plt.subplots(len(rows), 1, figsize=(8, 2.3 * len(rows) + 0.8), sharex=True, squeeze=False)
            for ax, (tt, y, ylabel, kind) in zip(axs[:, 0], rows, strict=True):
                ax.plot(tt, y, lw=0.8)
                ax.set_ylabel(ylabel)
                ax.grid(alpha=0.3)
                if kind == 'rate' and thresholds is not None:
                    _hlines(ax, thresholds[i], f'Mode 1B threshold ±{thresholds[i]:.3g} deg/s')
                if kind == 'moment' and max_moment is not None:
                    _hlines(ax, max_moment[0][i], f'{max_moment[1]} ±{max_moment[0][i]:.4g} A·m²')
            finish(fig, list(axs[:, 0]), f'fig_{fig_no}_{label}_response',
                   f'{label.capitalize()} ({axis}) response (cf. Fig. {fig_no})')

    # Fig. 4-18 (and 4-43, 4-51): magnetic moments and the field / momentum angle
    if len(t_m) or (bag.has(topics.TRUTH_B_BODY) and (len(t_h) or len(t_w))):
        t_b, b_body = _series(data, topics.TRUTH_B_BODY)
        panels: list[tuple[str, list[tuple[np.ndarray, np.ndarray, str]], bool]] = []
        if len(t_m):
            panels.append(('magnetic moment, A·m²', [(t_m, mm[:, i], f'M{a}') for i, (a, _) in enumerate(AXES)], True))
        angles = []
        if len(t_b) and len(t_h):
            ib, ih = _common(t_b, t_h)
            if np.linalg.norm(h[ih], axis=1).max(initial=0.0) > 0:
                angles.append((t_b[ib], _angle_deg(b_body[ib], h[ih]), 'B vs wheel momentum h'))
        spacecraft = ctx.section('rigid_body', 'spacecraft')
        if len(t_b) and len(t_w) and spacecraft is not None:
            from acds_common.inertia import inertia_tensor
            inertia = inertia_tensor(*spacecraft['inertia']) * spacecraft['inertia_scale']
            ib, iw = _common(t_b, t_w)
            big_h = w[iw] @ inertia.T
            if len(t_h):
                _, ih2 = _common(t_w[iw], t_h)
                if len(ih2) == len(iw):
                    big_h = big_h + h[ih2]
            angles.append((t_b[ib], _angle_deg(b_body[ib], big_h), 'B vs total momentum H'))
        if angles:
            panels.append(('angle B / momentum, deg', angles, False))
        if panels:
            fig, axs = plt.subplots(len(panels), 1, figsize=(8, 3 * len(panels) + 0.8), sharex=True, squeeze=False)
            for ax, (ylabel, lines, moments) in zip(axs[:, 0], panels, strict=True):
                for tt, y, lab in lines:
                    ax.plot(tt, y, lw=0.8, label=lab)
                ax.set_ylabel(ylabel)
                ax.legend(fontsize=8, loc='best')
                ax.grid(alpha=0.3)
                if moments and max_moment is not None:
                    _hlines(ax, float(np.max(max_moment[0])), f'{max_moment[1]} ±{np.max(max_moment[0]):.4g} A·m²')
            finish(fig, list(axs[:, 0]), 'fig_4-18_magnetics',
                   'Magnetic moments and field / momentum angle (cf. Figs. 4-18, 4-43, 4-51)')

    # sun angle: body z to the sun line, from the attitude and the scenario's sun
    sun = ctx.sun_eci()
    if len(quat) and sun is not None:
        angle, cone = sun_angle_deg(quat, sun), ctx.capture_cone_deg()
        fig, ax = plt.subplots(figsize=(8, 3.6))
        ax.plot(t_w, angle, lw=0.8)
        ax.set_ylabel('z body to sun line, deg')
        ax.set_ylim(0.0, min(180.0, 1.15 * max(float(angle.max()), cone or 0.0)) or 180.0)
        ax.grid(alpha=0.3)
        if cone is not None:
            _hlines(ax, cone, f'capture cone {cone:.3g}°', both=False)
        finish(fig, [ax], 'sun_angle', 'Sun angle: body z to the sun line')

    # mode timeline
    if history:
        changes = [(t / 60, m) for i, (t, m, _c, _k) in enumerate(history) if i == 0 or m != history[i - 1][1]]
        changes.append((history[-1][0] / 60, history[-1][1]))
        names = list(dict.fromkeys(n for _, n in changes))
        fig, ax = plt.subplots(figsize=(8, 1.4 + 0.35 * len(names)))
        ax.step([t for t, _ in changes], [names.index(n) for _, n in changes], where='post', lw=1.2)
        ax.set_yticks(range(len(names)), names)
        ax.set_ylabel('mode')
        ax.grid(alpha=0.3)
        finish(fig, [ax], 'mode_timeline', 'Mode timeline')

    # the mission's own figures (plug-ins)
    kit = mission_plots.PlotKit(ctx, lambda topic, width: _series(data, topic, width), (t_w, w),
                                sun_angle_deg(quat, sun) if len(quat) and sun is not None else None,
                                (bag.control_period_ns or 0) / 1e9, plt, finish)
    for mission in missions:
        mission.plot(kit)
    return out


def check_format(fmt: str) -> str:
    """``--format``: one of :data:`FORMATS` (one-line :class:`BagError` otherwise)."""
    if fmt not in FORMATS:
        raise BagError(f'plot --format {fmt!r}: choose one of {", ".join(FORMATS)}')
    return fmt


def make_plots(bag_path: Path | str, out_dir: Path | str | None = None, fmt: str = 'png') -> list[Path]:
    """Write every figure the bag's topics allow as ``fmt`` (png | svg | pdf); return the file paths."""
    import matplotlib.pyplot as plt

    check_format(fmt)
    out = Path(out_dir) if out_dir is not None else None
    if out is not None:
        check_out_dir(out)  # before reading anything
    bag = open_bag(bag_path)
    if out is None:
        out = bag.path.parent / 'plots'
        check_out_dir(out)
    figs = figures(bag)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for stem, fig in figs:
        path = out / f'{stem}.{fmt}'
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written
