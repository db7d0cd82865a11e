"""SSS figures (seed 001): the spin rate (rpm) and the magnetic torque about the spin axis (dyne-cm), for runs
of the SSS ASCS (the mode manager ran with ``modes.system: sss``)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from acds_common import topics, units


def applies(ctx: Any) -> bool:
    """Runs of the SSS mode logic."""
    modes = ctx.section('ascs_mode_manager', 'modes')
    return modes is not None and modes['system'] == 'sss'


def vectors(_ctx: Any) -> dict[str, Callable[[Any], list[float]]]:
    """The magnetic torque."""
    return {topics.TRUTH_TORQUE_MAG: lambda m: [m.vector.x, m.vector.y, m.vector.z]}


def plot(kit: Any) -> None:
    """``sss_spin_rate_torque``: ωz (rpm) and, when recorded, the magnetic torque Tz (dyne-cm)."""
    t_w, w = kit.rates
    if not len(t_w):
        return
    rows = [(t_w, units.rad_s_to_rpm(w[:, 2]), 'spin rate ωz, rpm')]
    t_q, q = kit.series(topics.TRUTH_TORQUE_MAG, 3)
    if len(t_q):
        rows.append((t_q, units.nm_to_dyne_cm(q[:, 2]), 'magnetic torque Tz, dyne-cm'))
    fig, axs = kit.plt.subplots(len(rows), 1, figsize=(8, 2.6 * len(rows) + 0.8), sharex=True, squeeze=False)
    for ax, (tt, y, ylabel) in zip(axs[:, 0], rows, strict=True):
        ax.plot(tt, y, lw=0.8)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
    kit.finish(fig, list(axs[:, 0]), 'sss_spin_rate_torque', 'SSS spin rate and magnetic spin torque')
