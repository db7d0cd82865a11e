"""``acds plot``: a bag → PNGs in the layout and units of the study's figures.

HEAO (seed 002): Fig. 4-14 (direction cosines B33, B23, B13 against the sun
frame), Figs. 4-15 … 4-17 (roll/pitch/yaw responses: body rate deg/s, wheel
momentum ft-lb-sec, magnetic moment A·m²), Fig. 4-18 / 4-43 / 4-51 (magnetic
moments and the angle between the Earth field and the momentum vector),
plus the mode timeline. SSS (seed 001): spin rate (rpm) and the magnetic
torque about the spin axis (dyne-cm). Torque-rod runs (seed 003, the bag holds
``em_driver/power``): body rates and |ω| (deg/s, with the summary's 0.1°/s threshold),
dipole commands (A·m²) and rod currents (mA). Formations (seed 004): ``formation_plots``.
A figure whose topics are absent is skipped.
Time axes are sim minutes. The series are gathered in one streaming pass over
the bag (only the plotted fields are kept), and the output folder is checked
before the bag is read.
"""

from __future__ import annotations

from array import array
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from acds_common import topics, units
from acds_runtime.bag.writer import check_out_dir, typestore

from . import formation_plots
from .reader import Bag, open_bag

AXES = (('x', 'roll'), ('y', 'pitch'), ('z', 'yaw'))


Gathered = dict[str, tuple[array, Any]]


def _gather(bag: Bag, vectors: dict[str, Callable[[Any], list[float]]],
            texts: dict[str, Callable[[Any], str]]) -> Gathered:
    """{topic: (timestamps ns, values)} in one pass over the bag: 3-vectors packed as doubles, texts as a list."""
    ts = typestore()
    getters = {topics.resolve(t): get for t, get in (*vectors.items(), *texts.items()) if bag.has(t)}
    out: Gathered = {t: (array('q'), [] if t in {topics.resolve(x) for x in texts} else array('d')) for t in getters}
    for topic, t, data in bag.messages(getters):
        stamps, values = out[topic]
        stamps.append(t)
        got = getters[topic](ts.deserialize_cdr(data, bag.types[topic]))
        if isinstance(values, array):
            values.extend(got)
        else:
            values.append(got)
    return out


def _series(gathered: Gathered, topic: str) -> tuple[np.ndarray, np.ndarray]:
    stamps, values = gathered.get(topics.resolve(topic), ((), ()))
    if not len(stamps):
        return np.zeros(0), np.zeros((0, 3))
    return np.asarray(stamps, dtype=float) / 60e9, np.asarray(values, dtype=float).reshape(-1, 3)


def _v3(v: Any) -> list[float]:
    return [v.x, v.y, v.z]


def _inertia(bag: Bag) -> np.ndarray | None:
    params = yaml.safe_load(bag.info.get('params', '') or '{}') or {}
    rb = params.get('rigid_body', {})
    if 'spacecraft_inertia_kg_m2' not in rb:
        return None
    from dynamics.rigid_body_model import inertia_tensor
    j = inertia_tensor(*rb['spacecraft_inertia_kg_m2'])
    return j * float(rb.get('spacecraft_inertia_scale', 1.0))


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


def make_plots(bag_path: Path | str, out_dir: Path | str | None = None) -> list[Path]:
    """Write every figure the bag's topics allow; return the PNG paths."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    out = Path(out_dir) if out_dir is not None else None
    if out is not None:
        check_out_dir(out)  # before reading anything
    bag = open_bag(bag_path)
    if out is None:
        out = bag.path.parent / 'plots'
        check_out_dir(out)
    name = bag.info.get('scenario_name', bag.path.name)
    vectors: dict[str, Callable[[Any], list[float]]] = {
        topics.TRUTH_SUN_COSINES: lambda m: _v3(m.vector),
        topics.TRUTH_ODOMETRY: lambda m: _v3(m.twist.twist.angular),
        topics.WHEEL_MOMENTUM: lambda m: _v3(m.vector),
        topics.DIPOLE_AVG: lambda m: _v3(m.vector),
        topics.TRUTH_B_BODY: lambda m: _v3(m.magnetic_field),
    }
    if not bag.has(topics.TRUTH_ODOMETRY):
        vectors[topics.GYRO] = lambda m: _v3(m.angular_velocity)
    if name.startswith('sss'):
        vectors[topics.TRUTH_TORQUE_MAG] = lambda m: _v3(m.vector)
    rods = bag.has(topics.COIL_POWER)
    if rods:
        vectors[topics.MOMENT_COMMAND] = lambda m: _v3(m.vector)
        vectors[topics.COIL_CURRENT] = lambda m: _v3(m.vector)
    formation = formation_plots.vehicles(bag)
    vectors.update(formation_plots.formation_vectors(formation))
    data = _gather(bag, vectors, {topics.MODE: lambda m: m.status[0].message if m.status else ''})
    out.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []

    def save(fig: Any, stem: str, title: str) -> None:
        fig.suptitle(f'{title}\n{name}', fontsize=10)
        fig.supxlabel('time, min')
        fig.tight_layout()
        path = out / f'{stem}.png'
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)

    # Fig. 4-14: direction cosines against the sun frame
    if bag.has(topics.TRUTH_SUN_COSINES):
        t, b = _series(data, topics.TRUTH_SUN_COSINES)
        fig, axs = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
        for ax, (i, label) in zip(axs, ((2, 'B33'), (1, 'B23'), (0, 'B13')), strict=True):
            ax.plot(t, b[:, i], lw=0.8)
            ax.set_ylabel(label)
            ax.set_ylim(-1.05, 1.05)
            ax.grid(alpha=0.3)
        save(fig, 'fig_4-14_direction_cosines', 'Direction cosines, body vs sun frame (cf. Fig. 4-14)')

    t_w, w = _series(data, topics.TRUTH_ODOMETRY)
    if not len(t_w):
        t_w, w = _series(data, topics.GYRO)
    t_h, h = _series(data, topics.WHEEL_MOMENTUM)
    t_m, mm = _series(data, topics.DIPOLE_AVG)

    # Figs. 4-15 … 4-17: per-axis responses
    if len(t_w) or len(t_h) or len(t_m):
        for fig_no, (i, (axis, label)) in zip(('4-15', '4-16', '4-17'), enumerate(AXES), strict=True):
            rows = [(t_w, np.degrees(w[:, i]) if len(t_w) else None, f'ω{axis}, deg/s'),
                    (t_h, units.nms_to_ftlbs(h[:, i]) if len(t_h) else None, f'h{axis}, ft-lb-sec'),
                    (t_m, mm[:, i] if len(t_m) else None, f'M{axis}, A·m²')]
            rows = [r for r in rows if r[1] is not None]
            fig, axs = plt.subplots(len(rows), 1, figsize=(8, 2.3 * len(rows) + 0.8), sharex=True, squeeze=False)
            for ax, (tt, y, ylabel) in zip(axs[:, 0], rows, strict=True):
                ax.plot(tt, y, lw=0.8)
                ax.set_ylabel(ylabel)
                ax.grid(alpha=0.3)
            save(fig, f'fig_{fig_no}_{label}_response', f'{label.capitalize()} ({axis}) response (cf. Fig. {fig_no})')

    # Fig. 4-18 (and 4-43, 4-51): magnetic moments and the field / momentum angle
    if len(t_m) or (bag.has(topics.TRUTH_B_BODY) and (len(t_h) or len(t_w))):
        t_b, b_body = _series(data, topics.TRUTH_B_BODY)
        rows: list[tuple[str, list[tuple[np.ndarray, np.ndarray, str]]]] = []
        if len(t_m):
            rows.append(('magnetic moment, A·m²', [(t_m, mm[:, i], f'M{a}') for i, (a, _) in enumerate(AXES)]))
        angles = []
        if len(t_b) and len(t_h):
            ib, ih = _common(t_b, t_h)
            if np.linalg.norm(h[ih], axis=1).max(initial=0.0) > 0:
                angles.append((t_b[ib], _angle_deg(b_body[ib], h[ih]), 'B vs wheel momentum h'))
        inertia = _inertia(bag)
        if len(t_b) and len(t_w) and inertia is not None:
            ib, iw = _common(t_b, t_w)
            big_h = w[iw] @ inertia.T
            if len(t_h):
                _, ih2 = _common(t_w[iw], t_h)
                if len(ih2) == len(iw):
                    big_h = big_h + h[ih2]
            angles.append((t_b[ib], _angle_deg(b_body[ib], big_h), 'B vs total momentum H'))
        if angles:
            rows.append(('angle B / momentum, deg', angles))
        if rows:
            fig, axs = plt.subplots(len(rows), 1, figsize=(8, 3 * len(rows) + 0.8), sharex=True, squeeze=False)
            for ax, (ylabel, lines) in zip(axs[:, 0], rows, strict=True):
                for tt, y, lab in lines:
                    ax.plot(tt, y, lw=0.8, label=lab)
                ax.set_ylabel(ylabel)
                ax.legend(fontsize=8, loc='best')
                ax.grid(alpha=0.3)
            save(fig, 'fig_4-18_magnetics', 'Magnetic moments and field / momentum angle (cf. Figs. 4-18, 4-43, 4-51)')

    # mode timeline
    if bag.has(topics.MODE):
        stamps, names_at = data[topics.resolve(topics.MODE)]
        modes = [(ts / 60e9, n) for ts, n in zip(stamps, names_at, strict=True)]
        names = list(dict.fromkeys(n for _, n in modes))
        fig, ax = plt.subplots(figsize=(8, 1.0 + 0.35 * len(names)))
        ax.step([t for t, _ in modes], [names.index(n) for _, n in modes], where='post', lw=1.2)
        ax.set_yticks(range(len(names)), names)
        ax.set_ylabel('mode')
        ax.grid(alpha=0.3)
        save(fig, 'mode_timeline', 'Mode timeline')

    # SSS: spin rate and magnetic torque about the spin axis
    if name.startswith('sss') and len(t_w):
        rows2 = [(t_w, units.rad_s_to_rpm(w[:, 2]), 'spin rate ωz, rpm')]
        if bag.has(topics.TRUTH_TORQUE_MAG):
            t_q, q = _series(data, topics.TRUTH_TORQUE_MAG)
            rows2.append((t_q, units.nm_to_dyne_cm(q[:, 2]), 'magnetic torque Tz, dyne-cm'))
        fig, axs = plt.subplots(len(rows2), 1, figsize=(8, 2.6 * len(rows2) + 0.8), sharex=True, squeeze=False)
        for ax, (tt, y, ylabel) in zip(axs[:, 0], rows2, strict=True):
            ax.plot(tt, y, lw=0.8)
            ax.set_ylabel(ylabel)
            ax.grid(alpha=0.3)
        save(fig, 'sss_spin_rate_torque', 'SSS spin rate and magnetic spin torque')

    # Torque rods (seed 003): rates, |ω|, dipole commands, rod currents
    if rods and len(t_w):
        from acds_runtime.summaries.oresat import DETUMBLED_RATE_DEG_S
        t_c, cmd = _series(data, topics.MOMENT_COMMAND)
        t_i, cur = _series(data, topics.COIL_CURRENT)
        rate = np.degrees(w)
        fig, axs = plt.subplots(4, 1, figsize=(8, 10), sharex=True)
        for i, (a, _) in enumerate(AXES):
            axs[0].plot(t_w, rate[:, i], lw=0.8, label=f'ω{a}')
        axs[0].set_ylabel('body rate, deg/s')
        axs[1].semilogy(t_w, np.linalg.norm(rate, axis=1), lw=0.8, label='|ω|')
        axs[1].axhline(DETUMBLED_RATE_DEG_S, color='k', ls='--', lw=0.8, label=f'{DETUMBLED_RATE_DEG_S:g}°/s')
        axs[1].set_ylabel('|ω|, deg/s')
        for ax, (tt, y, ylabel, lab) in zip(axs[2:], ((t_c, cmd, 'dipole command, A·m²', 'M'),
                                                    (t_i, cur * 1e3, 'rod current, mA', 'I')), strict=True):
            for i, (a, _) in enumerate(AXES):
                if len(tt):
                    ax.plot(tt, y[:, i], lw=0.6, label=f'{lab}{a}')
            ax.set_ylabel(ylabel)
        for ax in axs:
            ax.legend(fontsize=8, loc='upper right')
            ax.grid(alpha=0.3)
        save(fig, 'torque_rod_detumble', 'Torque-rod detumble: rates, |ω|, dipole commands, rod currents')

    if formation:
        formation_plots.plot_formation(formation, lambda topic: _series(data, topic), plt, save)
    return written
