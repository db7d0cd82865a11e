"""Cold-gas acquisition figures (seed 002 §3.1, §5), from ``cold_gas/state`` and the truth: runs in which the
cold_gas node ran.

* ``cold_gas_thruster_raster``: one row per thruster T1…T6 (its signed axis), a mark at every control step it
  fired, its shade the fraction of the step it thrust;
* ``cold_gas_propellant_pressure``: GN₂ left and used (lb); tank and feed pressure (psia);
* ``cold_gas_rates_sun_angle``: body rates (deg/s) and the z-to-sun angle (deg) with the gas phases, the hand-over
  to the wheels and the capture marked (the mode transitions, as on every time plot).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from acds_common import topics, units
from acds_common.thrusters import DEFAULT_LAYOUT, LAYOUTS, arrangement, arrangement_from_section

#: The ``cold_gas/state`` values a plot keeps, in this order.
STATE_KEYS = ('thrust_n', *(f'thrust_time_T{j}_s' for j in range(1, 7)), 'propellant_kg', 'used_kg',
              'tank_pressure_pa', 'feed_pressure_pa')


def state_vector(m: Any) -> list[float]:
    """The plotted numbers of one ``cold_gas/state`` message."""
    kv = {v.key: v.value for v in m.status[0].values}
    return [float(kv[k]) for k in STATE_KEYS]


def applies(ctx: Any) -> bool:
    """Runs with the cold-gas subsystem in the graph."""
    return 'cold_gas' in ctx.nodes


def vectors(_ctx: Any) -> dict[str, Callable[[Any], list[float]]]:
    """The subsystem's state."""
    return {topics.COLD_GAS_STATE: state_vector}


def plot(kit: Any) -> None:
    """Draw the three figures (module docstring)."""
    t, s = kit.series(topics.COLD_GAS_STATE, len(STATE_KEYS))
    if not len(t):
        return
    gas, plt, finish, dt_s = kit.ctx.section('cold_gas', 'cold_gas'), kit.plt, kit.finish, kit.dt_s
    arr = arrangement_from_section(gas) if gas else arrangement(*LAYOUTS[DEFAULT_LAYOUT])
    fig, ax = plt.subplots(figsize=(8, 3.6))
    for j in range(6):
        fired = s[:, 1 + j] > 0.0
        ax.scatter(t[fired], np.full(fired.sum(), j + 1), c=s[fired, 1 + j] / dt_s, cmap='viridis', vmin=0.0,
                   vmax=1.0, marker='|', s=120, linewidths=1.2)
    ax.set_yticks(range(1, 7), [f'T{j + 1} ({arr.axis_names(j)})' for j in range(6)])
    ax.set_ylim(0.4, 6.6)
    ax.set_ylabel('thruster (torque axis)')
    ax.grid(alpha=0.3)
    sm = plt.cm.ScalarMappable(cmap='viridis', norm=plt.Normalize(0.0, 1.0))
    fig.colorbar(sm, ax=ax, label='thrust time / step')
    finish(fig, [ax], 'cold_gas_thruster_raster', 'Cold-gas thruster firings (one mark per step fired)')

    fig, axs = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    axs[0].plot(t, s[:, 7] / units.LB_KG, lw=0.9, label='GN₂ left')
    axs[0].plot(t, s[:, 8] / units.LB_KG, lw=0.9, label='GN₂ used')
    axs[0].set_ylabel('GN₂, lb')
    axs[1].plot(t, s[:, 9] / units.PSI_PA, lw=0.9, label='tank')
    axs[1].plot(t, s[:, 10] / units.PSI_PA, lw=0.9, label='feed (regulated)')
    axs[1].set_yscale('log')
    axs[1].set_ylabel('pressure, psia')
    for ax in axs:
        ax.legend(fontsize=8, loc='best')
        ax.grid(alpha=0.3)
    finish(fig, list(axs), 'cold_gas_propellant_pressure', 'Cold-gas propellant and pressures')

    (t_w, w), sun_angle = kit.rates, kit.sun_angle
    if not len(t_w):
        return
    panels = 2 if sun_angle is not None else 1
    fig, axs = plt.subplots(panels, 1, figsize=(8, 3 * panels + 0.8), sharex=True, squeeze=False)
    for i, a in enumerate('xyz'):
        axs[0, 0].plot(t_w, np.degrees(w[:, i]), lw=0.8, label=f'ω{a}')
    axs[0, 0].set_ylabel('body rate, deg/s')
    if sun_angle is not None:
        axs[1, 0].plot(t_w, sun_angle, lw=0.8, label='z to sun')
        axs[1, 0].set_ylabel('z body to sun line, deg')
    for ax in axs[:, 0]:
        ax.legend(fontsize=8, loc='best')
        ax.grid(alpha=0.3)
    finish(fig, list(axs[:, 0]), 'cold_gas_rates_sun_angle',
           'Rates and sun angle: gas rate damping, gas sun acquisition, hand-over to the wheels, capture')
