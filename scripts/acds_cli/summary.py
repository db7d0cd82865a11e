"""Run summaries computed from what the run monitor received (seed units at this edge).

``run_summary`` gathers the common part and asks every module in
``acds_cli/summaries/`` to ``contribute(result, summary)`` its own keys (HEAO
acquisition table, SSS perigee passes, ...); ``print_tables`` lets each
module print its tables.

JSON has no NaN or infinity, so :func:`summary_json` (every summary file:
``run --summary-json``, ``sweep --json``) writes a non-finite number as
``null`` — the summaries' "no value" (like a pass ripple with zero average
torque) — and reports which keys it replaced, so the caller can say so; the
text is written with ``allow_nan=False`` and is always strict JSON.
"""

from __future__ import annotations

import hashlib
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
from acds_common import topics
from acds_common.units import nms_to_ftlbs, tesla_to_gauss
from dynamics.rigid_body_model import quat_to_dcm

from .monitor import RunMonitor


def _summary_modules() -> list:
    import importlib
    import pkgutil

    from . import summaries
    return [importlib.import_module(f'{summaries.__name__}.{m.name}')
            for m in sorted(pkgutil.iter_modules(summaries.__path__), key=lambda m: m.name)]


def run_summary(result: Any) -> dict[str, Any]:
    """The summary of a completed run (``result``: launcher RunResult)."""
    from dynamics.rigid_body_model import inertia_tensor

    sc = result.scenario
    inertia = inertia_tensor(*sc.get('spacecraft', 'inertia')) * sc.get('spacecraft', 'inertia_scale')
    summary: dict[str, Any] = {
        'scenario': sc.name,
        'steps': result.steps,
        'sim_minutes': result.steps * sc.control_period_s / 60,
        'wall_seconds': round(result.wall_seconds, 3),
        **dynamics_summary(result.monitor, inertia),
        'truth_digest': truth_digest(result.monitor),
    }
    for module in _summary_modules():
        module.contribute(result, summary)
    return summary


def _finite(value: Any, where: str, replaced: list[str]) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        replaced.append(where or '(top level)')
        return None
    if isinstance(value, dict):
        return {k: _finite(v, f'{where}.{k}' if where else str(k), replaced) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v, f'{where}[{i}]', replaced) for i, v in enumerate(value)]
    return value


def summary_json(obj: Any) -> tuple[str, list[str]]:
    """Strict JSON text of a summary (or a list of them) with every non-finite number written as ``null``,
    and the keys that were replaced (e.g. ``passes[0].ripple_pct``)."""
    replaced: list[str] = []
    text = json.dumps(_finite(obj, '', replaced), indent=2, allow_nan=False) + '\n'
    return text, replaced


def write_summary_json(path: Path, obj: Any) -> None:
    """Write :func:`summary_json` of ``obj`` to ``path`` (creating its folders); say on stderr which
    non-finite values became null."""
    text, replaced = summary_json(obj)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    if replaced:
        print(f'[acds] {path}: non-finite value(s) written as null (JSON has no NaN/Infinity): {", ".join(replaced)}',
              file=sys.stderr)


def print_tables(summary: dict[str, Any]) -> None:
    """Let each summary module print its tables."""
    for module in _summary_modules():
        module.print_tables(summary)


def truth_digest(monitor: RunMonitor) -> str:
    """SHA-256 over every truth message (serialized CDR), topic by topic in publish order."""
    data = monitor.snapshot()
    h = hashlib.sha256()
    for topic in sorted(topics.resolve(t) for t in topics.TRUTH):
        for raw in data.get(topic, []):
            h.update(topic.encode())
            h.update(raw)
    return h.hexdigest()


def stream_digests(monitor: RunMonitor) -> dict[str, str]:
    """SHA-256 of each topic's message stream (for comparing two runs topic by topic)."""
    out = {}
    for topic, msgs in sorted(monitor.snapshot().items()):
        h = hashlib.sha256()
        for raw in msgs:
            h.update(raw)
        out[topic] = h.hexdigest()
    return out


def dynamics_summary(monitor: RunMonitor, inertia_kg_m2: np.ndarray) -> dict[str, Any]:
    """Momentum and energy drift, final rates and the |B| range seen (issue: free-tumble summary)."""
    odom = monitor.messages(topics.TRUTH_ODOMETRY)
    wheel_msgs = monitor.messages(topics.WHEEL_MOMENTUM)
    b = np.array([[m.magnetic_field.x, m.magnetic_field.y, m.magnetic_field.z]
                  for m in monitor.messages(topics.TRUTH_B_BODY)])
    h_wheel = {m.header.stamp.sec * 10**9 + m.header.stamp.nanosec: np.array([m.vector.x, m.vector.y, m.vector.z])
               for m in wheel_msgs}
    h_norm, energy = [], []
    for m in odom:
        o = m.pose.pose.orientation
        w = m.twist.twist.angular
        omega = np.array([w.x, w.y, w.z])
        t_ns = m.header.stamp.sec * 10**9 + m.header.stamp.nanosec
        h_body = inertia_kg_m2 @ omega + h_wheel.get(t_ns, np.zeros(3))
        h_norm.append(np.linalg.norm(quat_to_dcm(np.array([o.x, o.y, o.z, o.w])) @ h_body))
        energy.append(0.5 * omega @ inertia_kg_m2 @ omega)
    final = odom[-1].twist.twist.angular
    b_g = tesla_to_gauss(np.linalg.norm(b, axis=1))
    return {
        'momentum_drift_rel': float(max(abs(x - h_norm[0]) for x in h_norm) / h_norm[0]) if h_norm[0] else 0.0,
        'energy_drift_rel': float(max(abs(x - energy[0]) for x in energy) / energy[0]) if energy[0] else 0.0,
        'final_rates_deg_s': [float(np.degrees(v)) for v in (final.x, final.y, final.z)],
        'final_momentum_ftlbs': float(nms_to_ftlbs(h_norm[-1])),
        'b_min_gauss': float(b_g.min()),
        'b_max_gauss': float(b_g.max()),
        'truth_messages': sum(len(monitor.snapshot().get(topics.resolve(t), [])) for t in topics.TRUTH),
    }
