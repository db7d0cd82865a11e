"""Formation figures of a bag (spec §10; seed 004): the vehicles in the formation plane, and their dipoles.

``emff_formation_plane``: every vehicle's track in the formation frame's x–y plane (start ○, end ●) and
the baseline length |r_b − r_a| against time; ``emff_dipoles``: each vehicle's achieved dipole |μ| and its
wheel momentum |h| against time. Drawn when the bag's run has vehicles (nodes ``<vehicle>/<node>`` ran); time
axes in sim minutes, SI otherwise.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from acds_common import topics


def applies(ctx: Any) -> bool:
    """Formation runs: nodes of named vehicles ran."""
    return bool(ctx.vehicles)


def vectors(ctx: Any) -> dict[str, Callable[[Any], list[float]]]:
    """The series the figures read, per vehicle: position, dipole, wheel momentum."""
    out: dict[str, Callable[[Any], list[float]]] = {}
    for v in ctx.vehicles:
        out[f'{v}/{topics.TRUTH_ODOMETRY}'] = lambda m: [m.pose.pose.position.x, m.pose.pose.position.y,
                                                          m.pose.pose.position.z]
        out[f'{v}/{topics.DIPOLE_AVG}'] = lambda m: [m.vector.x, m.vector.y, m.vector.z]
        out[f'{v}/{topics.WHEEL_MOMENTUM}'] = lambda m: [m.vector.x, m.vector.y, m.vector.z]
    return out


def plot(kit: Any) -> None:
    """Draw the two formation figures (no mode stream: no event lines)."""
    names, series, plt = kit.ctx.vehicles, kit.series, kit.plt
    fig, (ax_xy, ax_d) = plt.subplots(2, 1, figsize=(8, 9), gridspec_kw={'height_ratios': [2, 1]})
    tracks = {}
    for v in names:
        t, p = series(f'{v}/{topics.TRUTH_ODOMETRY}', 3)
        if not len(t):
            continue
        tracks[v] = (t, p)
        line, = ax_xy.plot(p[:, 0], p[:, 1], lw=1.0, label=v)
        ax_xy.plot(p[0, 0], p[0, 1], 'o', mfc='none', color=line.get_color())
        ax_xy.plot(p[-1, 0], p[-1, 1], 'o', color=line.get_color())
    ax_xy.set_xlabel('x, m (formation frame)')
    ax_xy.set_ylabel('y, m')
    ax_xy.set_aspect('equal', adjustable='datalim')
    ax_xy.legend(fontsize=8)
    ax_xy.grid(alpha=0.3)
    if len(tracks) >= 2:
        (ta, pa), (tb, pb) = (tracks[v] for v in names[:2])
        n = min(len(ta), len(tb))
        ax_d.plot(ta[:n], np.linalg.norm(pb[:n] - pa[:n], axis=1), lw=1.0)
        ax_d.set_ylabel(f'|r_{names[1]} − r_{names[0]}|, m')
    ax_d.grid(alpha=0.3)
    kit.finish(fig, [], 'emff_formation_plane', 'Formation in the plane, and the baseline length')

    fig, (ax_m, ax_h) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for v in names:
        t, m = series(f'{v}/{topics.DIPOLE_AVG}', 3)
        if len(t):
            ax_m.plot(t, np.linalg.norm(m, axis=1), lw=0.8, label=v)
        t, h = series(f'{v}/{topics.WHEEL_MOMENTUM}', 3)
        if len(t):
            ax_h.plot(t, np.linalg.norm(h, axis=1), lw=0.8, label=v)
    ax_m.set_ylabel('|μ| achieved, A·m²')
    ax_h.set_ylabel('|h| wheels, N·m·s')
    for ax in (ax_m, ax_h):
        if ax.get_legend_handles_labels()[0]:  # no wheels in the formation (the airtrack): nothing to label
            ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    kit.finish(fig, [], 'emff_dipoles', 'Dipoles and wheel momentum of each vehicle')
