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

from typing import Any

import numpy as np
from acds_common import topics
from acds_common.units import nms_to_ftlbs

_NULL_KEYS = ('time_magnetics_only_min', 'time_wheels_magnetics_min', 'acquisition_time_min',
              'final_wheel_momentum_ftlbs', 'peak_wheel_momentum_ftlbs', 'peak_moment_am2',
              'wheel_saturation_time_min', 'mode_transitions')


def _t_ns(msg: Any) -> int:
    return msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec


def mode_history(mode_msgs: list[Any]) -> list[tuple[float, str, str, bool]]:
    """[(t_s, mode, cause, captured)] per step from the ``mode`` messages."""
    out = []
    for msg in mode_msgs:
        status = next((s for s in msg.status if s.name == 'ascs_mode_manager'), None)
        if status is None:
            continue
        values = {kv.key: kv.value for kv in status.values}
        out.append((_t_ns(msg) / 1e9, values.get('mode', status.message), values.get('cause', ''),
                    values.get('captured') == 'true'))
    return out


def transitions(history: list[tuple[float, str, str, bool]]) -> list[dict[str, Any]]:
    """Mode changes and the acquisition capture as [{t_min, from, to, cause}] (capture: to = 'capture')."""
    out: list[dict[str, Any]] = []
    prev_mode, prev_captured = None, None
    for t, mode, cause, captured in history:
        if prev_mode is not None and mode != prev_mode:
            out.append({'t_min': t / 60, 'from': prev_mode, 'to': mode, 'cause': cause or None})
        if captured and prev_captured is False and (prev_mode == mode or prev_mode is None):
            out.append({'t_min': t / 60, 'from': mode, 'to': 'capture', 'cause': cause or None})
        prev_mode, prev_captured = mode, captured
    return out


def acquisition_times(history: list[tuple[float, str, str, bool]]) -> dict[str, float | None]:
    """Table 4-7 times (min): magnetics only (start → first Mode 1B), wheels + magnetics (1B → capture), total."""
    if not history:
        return {'time_magnetics_only_min': None, 'time_wheels_magnetics_min': None, 'acquisition_time_min': None}
    t0, mode0 = history[0][0], history[0][1]
    t_1b = t0 if mode0 == 'mode_1b' else next((t for t, m, _, _ in history if m == 'mode_1b'), None)
    t_cap = next((t for t, m, _, c in history if c and m == 'mode_1b'), None)
    if mode0 not in ('mode_1a', 'mode_1b'):  # a normal-mode run: no acquisition
        t_1b = t_cap = None
    return {
        'time_magnetics_only_min': None if t_1b is None else (t_1b - t0) / 60,
        'time_wheels_magnetics_min': None if t_1b is None or t_cap is None else (t_cap - t_1b) / 60,
        'acquisition_time_min': None if t_cap is None else (t_cap - t0) / 60,
    }


def wheel_series(h_msgs: list[Any], hdot_msgs: list[Any], dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """(t_s, h N·m·s) per step, plus the final h(t_N) = h_{N−1} + ḣ_{N−1}·Δt."""
    if not h_msgs:
        return np.zeros(0), np.zeros((0, 3))
    t = np.array([_t_ns(m) / 1e9 for m in h_msgs])
    h = np.array([[m.vector.x, m.vector.y, m.vector.z] for m in h_msgs])
    if hdot_msgs and _t_ns(hdot_msgs[-1]) == _t_ns(h_msgs[-1]):
        last = hdot_msgs[-1].vector
        h = np.vstack([h, h[-1] + np.array([last.x, last.y, last.z]) * dt_s])
        t = np.append(t, t[-1] + dt_s)
    return t, h


def first_saturation_s(t_s: np.ndarray, h_nms: np.ndarray, capacity_nms: np.ndarray) -> float | None:
    """First time any |h_i| reaches capacity_i (relative tolerance 1e-9), None if never."""
    if len(t_s) == 0:
        return None
    hit = np.any(np.abs(h_nms) >= np.asarray(capacity_nms) * (1.0 - 1e-9), axis=1)
    idx = np.flatnonzero(hit)
    return float(t_s[idx[0]]) if len(idx) else None


def contribute(result: Any, summary: dict[str, Any]) -> None:
    """Add the HEAO keys when the graph ran the HEAO mode manager."""
    from dynamics.wheels_model import ReactionWheels, WheelsConfig

    sc = result.scenario
    if sc.get('modes', 'system') != 'heao' or 'ascs_mode_manager' not in sc.get('', 'nodes'):
        for key in _NULL_KEYS:  # the summary's key set is the same for every run (null: not applicable)
            summary.setdefault(key, None)
        return
    mon = result.monitor
    dt = sc.control_period_s
    history = mode_history(mon.messages(topics.MODE))
    summary.update(acquisition_times(history))
    t, h = wheel_series(mon.messages(topics.WHEEL_MOMENTUM), mon.messages(topics.WHEEL_TORQUE), dt)
    if len(h):
        h_ft = nms_to_ftlbs(h)
        peak = np.max(np.abs(h_ft), axis=0)
        summary['final_wheel_momentum_ftlbs'] = float(np.linalg.norm(h_ft[-1]))
        summary['peak_wheel_momentum_ftlbs'] = {'x': float(peak[0]), 'y': float(peak[1]), 'z': float(peak[2]),
                                                'rss': float(np.max(np.linalg.norm(h_ft, axis=1)))}
        failed = sc.get('wheels', 'failed_wheel')
        wheels = ReactionWheels(WheelsConfig(layout=sc.get('wheels', 'layout'),
                                             failed_wheel=failed if failed >= 0 else None))
        sat = first_saturation_s(t, h, wheels.capacity_per_axis_nms())
        summary['wheel_saturation_time_min'] = None if sat is None else sat / 60
    else:
        summary.update(final_wheel_momentum_ftlbs=None, peak_wheel_momentum_ftlbs=None,
                       wheel_saturation_time_min=None)
    moments = mon.messages(topics.MOMENT_COMMAND)
    if moments:
        m = np.max(np.abs([[x.vector.x, x.vector.y, x.vector.z] for x in moments]), axis=0)
        summary['peak_moment_am2'] = {'x': float(m[0]), 'y': float(m[1]), 'z': float(m[2])}
    else:
        summary['peak_moment_am2'] = None
    summary['mode_transitions'] = transitions(history)
    summary['final_mode'] = history[-1][1] if history else None


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
