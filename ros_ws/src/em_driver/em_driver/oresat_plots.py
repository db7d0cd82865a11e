"""Torque-rod figures (seed 003): body rates and |ω| (deg/s, with the summary's detumbled threshold,
``dynamics.detumbled_rate``), dipole commands (A·m²) and rod currents (mA), for runs whose em_driver drives torque rods
(``em_driver.driver_kind: torque_rod``)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from acds_common import topics


def applies(ctx: Any) -> bool:
    """Runs of the torque-rod drivers."""
    driver = ctx.section('em_driver', 'em_driver')
    return driver is not None and driver['driver_kind'] == 'torque_rod'


def vectors(_ctx: Any) -> dict[str, Callable[[Any], list[float]]]:
    """Dipole commands and rod currents."""
    return {topics.MOMENT_COMMAND: lambda m: [m.vector.x, m.vector.y, m.vector.z],
            topics.COIL_CURRENT: lambda m: [m.vector.x, m.vector.y, m.vector.z]}


def plot(kit: Any) -> None:
    """``torque_rod_detumble``: rates, |ω| against the detumbled threshold, dipole commands, rod currents."""
    from acds_common.scenario import SCHEMA

    rate = SCHEMA['dynamics']['detumbled_rate']  # as the run's rigid_body received it (a bag from before the key: its default)
    threshold_deg_s = math.degrees(kit.ctx.params.get('rigid_body', {}).get(
        rate.param_name('dynamics', 'detumbled_rate'), rate.default))
    t_w, w = kit.rates
    if not len(t_w):
        return
    t_c, cmd = kit.series(topics.MOMENT_COMMAND, 3)
    t_i, cur = kit.series(topics.COIL_CURRENT, 3)
    rate = np.degrees(w)
    fig, axs = kit.plt.subplots(4, 1, figsize=(8, 10), sharex=True)
    for i, a in enumerate('xyz'):
        axs[0].plot(t_w, rate[:, i], lw=0.8, label=f'ω{a}')
    axs[0].set_ylabel('body rate, deg/s')
    axs[1].semilogy(t_w, np.linalg.norm(rate, axis=1), lw=0.8, label='|ω|')
    axs[1].axhline(threshold_deg_s, color='k', ls='--', lw=0.8, label=f'{threshold_deg_s:g}°/s')
    axs[1].set_ylabel('|ω|, deg/s')
    for ax, (tt, y, ylabel, lab) in zip(axs[2:], ((t_c, cmd, 'dipole command, A·m²', 'M'),
                                                (t_i, cur * 1e3, 'rod current, mA', 'I')), strict=True):
        for i, a in enumerate('xyz'):
            if len(tt):
                ax.plot(tt, y[:, i], lw=0.6, label=f'{lab}{a}')
        ax.set_ylabel(ylabel)
    for ax in axs:
        ax.legend(fontsize=8, loc='upper right')
        ax.grid(alpha=0.3)
    kit.finish(fig, list(axs), 'torque_rod_detumble', 'Torque-rod detumble: rates, |ω|, dipole commands, rod currents')
