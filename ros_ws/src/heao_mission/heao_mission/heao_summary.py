"""HEAO acquisition / normal-mode summary: the Table 4-7 columns and the wheel and moment peaks.

Contributed when the graph ran the HEAO mode manager (``modes.system: heao`` and node
``ascs_mode_manager`` in the graph). Times come from the ``mode`` stream (one message per
step: mode, this step's transition cause, captured flag); wheel momenta from
``wheels/momentum`` (h(t_k) every step; the final value is h(t_N) = h_{N−1} + ḣ_{N−1}·Δt);
moments from ``controller/moment_command``.

Wheel saturation: the first step at which any body-axis |h_i| reaches the wheels' capacity
on that axis (the dynamics core's :meth:`ReactionWheels.capacity_per_axis_nms`, the Table
4-6 box; relative tolerance 1e-9), checked on every step's momentum, not on the wheels'
20-step diagnostics. For the three-orthogonal wheels this is exactly "a wheel is at its
capacity"; for the 4-wheel cluster it is the axis-box criterion.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from acds_common import topics
from acds_common.mode_report import ModeValueReader, mode_state, transitions
from acds_common.modes import GAS_MODES
from acds_common.step_blocks import first, norms, running_max, running_max_3
from acds_common.units import nms_to_ftlbs

_MODE, _WHEEL_MOMENTUM, _WHEEL_TORQUE, _MOMENT_COMMAND = (
    topics.resolve(t) for t in (topics.MODE, topics.WHEEL_MOMENTUM, topics.WHEEL_TORQUE, topics.MOMENT_COMMAND))
_NULL_KEYS = ('time_magnetics_only_min', 'time_wheels_magnetics_min', 'acquisition_time_min',
              'final_wheel_momentum_ftlbs', 'peak_wheel_momentum_ftlbs', 'peak_moment_am2',
              'wheel_saturation_time_min', 'mode_transitions')


def acquisition_times(history: list[tuple[float, str, str, bool]]) -> dict[str, float | None]:
    """Table 4-7 times (min): magnetics only (start → first Mode 1B), wheels + magnetics (1B → capture), total."""
    if not history:
        return {'time_magnetics_only_min': None, 'time_wheels_magnetics_min': None, 'acquisition_time_min': None}
    t0, mode0 = history[0][0], history[0][1]
    t_1b = t0 if mode0 == 'mode_1b' else next((t for t, m, _, _ in history if m == 'mode_1b'), None)
    t_cap = next((t for t, m, _, c in history if c and m == 'mode_1b'), None)
    if mode0 not in ('mode_1a', 'mode_1b', *GAS_MODES):  # a normal-mode run: no acquisition
        t_1b = t_cap = None
    return {  # an acquisition on gas (seed 002 §3.1) has no magnetics-only phase; its gas phases: cold_gas.cold_gas_summary
        'time_magnetics_only_min': None if t_1b is None or mode0 in GAS_MODES else (t_1b - t0) / 60,
        'time_wheels_magnetics_min': None if t_1b is None or t_cap is None else (t_cap - t_1b) / 60,
        'acquisition_time_min': None if t_cap is None else (t_cap - t0) / 60,
    }


def saturated(h_nms: np.ndarray, capacity_nms: np.ndarray) -> bool:
    """Whether any body-axis |h_i| has reached its capacity (relative tolerance 1e-9)."""
    return bool(np.any(np.abs(h_nms) >= np.asarray(capacity_nms) * (1.0 - 1e-9)))


#: The summary keys this module contributes (:data:`acds_common.plugins.KEYS_ATTRIBUTE`).
SUMMARY_KEYS = (*_NULL_KEYS, 'final_mode')


def applies(scenario: Any) -> bool:
    """The HEAO keys come from runs of the HEAO mode manager."""
    return scenario.get('modes', 'system') in ('heao', 'heao_cold_gas') and 'ascs_mode_manager' in scenario.get('', 'nodes')


def null_keys(summary: dict[str, Any]) -> None:
    """The summary's key set is the same for every run (null: not applicable)."""
    for key in _NULL_KEYS:
        summary.setdefault(key, None)


class Accumulator:
    """Streaming HEAO summary: mode change points, wheel momentum peaks and final value, moment peaks."""

    topics = (topics.MODE, topics.WHEEL_MOMENTUM, topics.WHEEL_TORQUE, topics.MOMENT_COMMAND)

    def __init__(self, scenario: Any) -> None:
        from dynamics.wheels_model import ReactionWheels, WheelsConfig

        self.dt_s = scenario.control_period_s
        failed = scenario.get('wheels', 'failed_wheel')
        self.capacity = ReactionWheels(WheelsConfig(layout=scenario.get('wheels', 'layout'),
                                                    failed_wheel=failed if failed >= 0 else None)
                                       ).capacity_per_axis_nms()
        self._saturation_at = tuple((np.asarray(self.capacity) * (1.0 - 1e-9)).tolist())  # as saturated()
        #: The mode history's change points: (t_s, mode, cause, captured), what the times need.
        self.history: list[tuple[float, str, str, bool]] = []
        self._last_state: tuple[str, bool] | None = None
        #: (mode, cause, captured) of the step's ``mode`` value, read when a new value arrives.
        self._mode_state = ModeValueReader(mode_state)
        # Running peaks and last values as float triples (every step; arrays only in contribute).
        self.peak_h = (0.0, 0.0, 0.0)
        self.peak_rss = 0.0
        self.last_h: tuple[int, tuple[float, ...]] | None = None
        self.last_hdot: tuple[int, tuple[float, ...]] | None = None
        self.saturation_s: float | None = None
        self.peak_m: tuple[float, ...] | None = None

    def _wheel(self, t_s: float, h: tuple[float, ...]) -> None:
        ph = self.peak_h
        ax, ay, az = abs(h[0]), abs(h[1]), abs(h[2])
        # Running maxima as max(peak, value) gives them (the peak unless the value is larger), without the calls.
        self.peak_h = (ax if ax > ph[0] else ph[0], ay if ay > ph[1] else ph[1], az if az > ph[2] else ph[2])
        rss = math.sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2])
        if rss > self.peak_rss:
            self.peak_rss = rss
        if self.saturation_s is None:
            cx, cy, cz = self._saturation_at
            if ax >= cx or ay >= cy or az >= cz:
                self.saturation_s = t_s

    def step(self, k: int, values: dict[str, Any]) -> None:
        """One step: keep the mode history's change points and the running peaks."""
        t = k * self.dt_s
        state = self._mode_state(values.get(_MODE))
        if state is not None:
            mode, cause, captured = state
            if cause or (mode, captured) != self._last_state:
                self.history.append((t, mode, cause, captured))
                self._last_state = (mode, captured)
        h = values.get(_WHEEL_MOMENTUM)
        if h is not None:
            self.last_h = (k, h)
            self._wheel(t, h)
        hdot = values.get(_WHEEL_TORQUE)
        if hdot is not None:
            self.last_hdot = (k, hdot)
        m = values.get(_MOMENT_COMMAND)
        if m is not None:
            pm = self.peak_m or (0.0, 0.0, 0.0)
            mx, my, mz = abs(m[0]), abs(m[1]), abs(m[2])
            self.peak_m = (mx if mx > pm[0] else pm[0], my if my > pm[1] else pm[1], mz if mz > pm[2] else pm[2])

    def step_block(self, k0: int, columns: dict[str, np.ndarray]) -> None:
        """:meth:`step` of each row of a block of steps (``RunObserver.feed_block``), at once and to the same bits
        (:mod:`acds_common.step_blocks`). A block carries no ``mode`` value (no step of it changes the mode), so
        the mode history is :meth:`step`'s."""
        h = columns.get(_WHEEL_MOMENTUM)
        if h is not None and len(h):
            self.last_h = (k0 + len(h) - 1, tuple(h[-1].tolist()))
            self._wheel_rows(k0, h)
        hdot = columns.get(_WHEEL_TORQUE)
        if hdot is not None and len(hdot):
            self.last_hdot = (k0 + len(hdot) - 1, tuple(hdot[-1].tolist()))
        m = columns.get(_MOMENT_COMMAND)
        if m is not None and len(m):
            self.peak_m = running_max_3(self.peak_m or (0.0, 0.0, 0.0), np.abs(m))

    def _wheel_rows(self, k0: int, h: np.ndarray) -> None:
        """:meth:`_wheel` of each row of a block's wheel momenta (rows of steps k0, k0 + 1, …)."""
        habs = np.abs(h)
        self.peak_h = running_max_3(self.peak_h, habs)
        self.peak_rss = running_max(self.peak_rss, norms(h))
        if self.saturation_s is None:
            at = first(np.any(habs >= np.array(self._saturation_at), axis=1))
            if at is not None:
                self.saturation_s = (k0 + at) * self.dt_s

    def contribute(self, summary: dict[str, Any]) -> None:
        """Add the HEAO keys (Table 4-7 columns, peaks, transitions)."""
        summary.update(acquisition_times(self.history))
        if self.last_h is not None:
            final = np.array(self.last_h[1])
            if self.last_hdot is not None and self.last_hdot[0] == self.last_h[0]:  # h(t_N) = h_N−1 + ḣ·Δt
                final = final + np.array(self.last_hdot[1]) * self.dt_s
                self._wheel((self.last_h[0] + 1) * self.dt_s, tuple(final.tolist()))
            peak = nms_to_ftlbs(np.array(self.peak_h))
            summary['final_wheel_momentum_ftlbs'] = float(np.linalg.norm(nms_to_ftlbs(final)))
            summary['peak_wheel_momentum_ftlbs'] = {'x': float(peak[0]), 'y': float(peak[1]), 'z': float(peak[2]),
                                                    'rss': float(nms_to_ftlbs(self.peak_rss))}
            summary['wheel_saturation_time_min'] = None if self.saturation_s is None else self.saturation_s / 60
        summary['peak_moment_am2'] = None if self.peak_m is None else {
            'x': float(self.peak_m[0]), 'y': float(self.peak_m[1]), 'z': float(self.peak_m[2])}
        summary['mode_transitions'] = transitions(self.history)
        summary['final_mode'] = self.history[-1][1] if self.history else None


#: What a dispersion study of a scenario this summary does not apply to lacks (``acds montecarlo``'s note).
STUDY_NOT_APPLICABLE = ('does not run the HEAO mode manager, so the acquisition quantities (times to Mode 1B and to '
                        'capture, wheel momentum at capture) stay empty')


def study_row(summary: dict[str, Any]) -> dict[str, Any]:
    """A Monte Carlo sample's columns from its summary (:func:`acds_runtime.dispersion_report.make_row`): the Table
    4-7 quantities in study units, whether Mode 1B and capture were reached, the peaks and, for a cold-gas
    acquisition (no magnetics-only phase; Mode 1B from the hand-over), its ``gas_*`` keys."""
    peak_h = summary.get('peak_wheel_momentum_ftlbs') or {}
    peak_m = summary.get('peak_moment_am2') or {}
    gas = 'gas_used_lb' in summary
    return {
        **({} if gas else {'time_magnetics_only_min': summary.get('time_magnetics_only_min')}),
        'time_wheels_magnetics_min': summary.get('time_wheels_magnetics_min'),
        'acquisition_time_min': summary.get('acquisition_time_min'),
        'mode_1b_reached': summary.get('gas_handover_min' if gas else 'time_magnetics_only_min') is not None,
        'captured': summary.get('acquisition_time_min') is not None,
        'sim_minutes': summary.get('sim_minutes'),
        'final_wheel_momentum_ftlbs': summary.get('final_wheel_momentum_ftlbs'),
        **{f'peak_wheel_momentum_{a}_ftlbs': peak_h.get(a) for a in ('x', 'y', 'z', 'rss')},
        **{f'peak_moment_{a}_am2': peak_m.get(a) for a in ('x', 'y', 'z')},
        'peak_moment_am2': max(peak_m.values()) if peak_m else None,
        'wheel_saturation_time_min': summary.get('wheel_saturation_time_min'),
        'final_mode': summary.get('final_mode'),
        'truth_digest': summary.get('truth_digest'),
        **{k: v for k, v in summary.items() if k.startswith('gas_')},
    }


def _fmt(x: float | None, spec: str = '.1f') -> str:
    return '—' if x is None else format(x, spec)


def print_tables(summary: dict[str, Any]) -> None:
    """The Table 4-7 columns for the run, and its mode transitions."""
    if summary.get('mode_transitions') is None:
        return
    print('\nTable 4-7 columns (times in minutes, momentum in ft-lb-sec; — = not reached in this run)')
    print(f'  {"case":28s} {"magnetics only":>14s} {"wheels+magnetics":>16s} {"acquisition":>11s} '
          f'{"final |h|":>9s}')
    print(f'  {summary["scenario"]:28s} {_fmt(summary["time_magnetics_only_min"]):>14s} '
          f'{_fmt(summary["time_wheels_magnetics_min"]):>16s} {_fmt(summary["acquisition_time_min"]):>11s} '
          f'{_fmt(summary["final_wheel_momentum_ftlbs"], ".2f"):>9s}')
    peak_h, peak_m = summary.get('peak_wheel_momentum_ftlbs'), summary.get('peak_moment_am2')
    if peak_h:
        print(f'  peak wheel momentum x/y/z/rss: {peak_h["x"]:.2f} / {peak_h["y"]:.2f} / {peak_h["z"]:.2f} / '
              f'{peak_h["rss"]:.2f} ft-lb-sec; first wheel saturation: '
              f'{_fmt(summary["wheel_saturation_time_min"])} min')
    if peak_m:
        print(f'  peak moment command x/y/z: {peak_m["x"]:.0f} / {peak_m["y"]:.0f} / {peak_m["z"]:.0f} A·m²')
    for tr in summary.get('mode_transitions') or []:
        print(f'  t={tr["t_min"]:8.2f} min  {tr["from"]} -> {tr["to"]}: {tr["cause"] or ""}')
