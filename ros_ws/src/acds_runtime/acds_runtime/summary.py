"""Run summaries, computed while the run goes (seed units at this edge), in bounded memory.

A :class:`RunObserver` is fed every message of a run — serialized bytes by the run monitor
(per-process graph) or values by the direct engine — decodes only the topics its summary
modules read (a module summarises single-vehicle runs, or formations when it sets
``FORMATIONS = True``), joins them by step and hands complete steps, in step order, to each summary module the
installed packages declare (entry-point group ``acds.summaries``, :mod:`acds_common.plugins`:
``Accumulator(scenario)`` with ``step(k, values)``, ``event(topic,
value)``, ``contribute(summary)`` and optionally ``step_block(k0, columns)``). The direct engine's
compiled blocks of steps come as rows of float64 per topic (:meth:`RunObserver.feed_block`), the same
summary and digest as their steps fed one by one. It keeps only what the summaries keep (running peaks,
change points), never the messages, so its memory does not grow with the run's length.
``print_tables`` lets each module print its tables.

The truth digest is SHA-256 over, for each truth topic (the time owner's per-step outputs,
:meth:`acds_common.graph.Graph.truth_topics`) in sorted order, its name and the SHA-256 of its
serialized messages in step order: equal data ⇒ equal digest, in either engine.

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
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from acds_common import plugins, topics
from acds_common.attitude import dcm
from acds_common.cdr import Codec
from acds_common.environment import orbit_from_section
from acds_common.graph import Graph
from acds_common.inertia import inertia_tensor
from acds_common.step_blocks import first, nonzero, norms, running_max, running_min
from acds_common.units import nms_to_ftlbs, tesla_to_gauss
from acds_common.vec3 import dot, mat3, mv, norm
from dynamics import integration_accuracy as accuracy

#: Per-step topics the common (dynamics) summary reads.
ODOMETRY, B_BODY, WHEEL_H, WHEEL_HDOT, TORQUE_MAG, TORQUE_GG = (topics.resolve(t) for t in (
    topics.TRUTH_ODOMETRY, topics.TRUTH_B_BODY, topics.WHEEL_MOMENTUM, topics.WHEEL_TORQUE, topics.TRUTH_TORQUE_MAG,
    topics.TRUTH_TORQUE_GG))
#: The rows of the odometry (:class:`acds_common.cdr.RowLayout`): position 0:3, q 3:7, velocity 7:10, ω 10:13.
_ODOMETRY_ROWS = Codec(topics.type_of(ODOMETRY)).layout


#: The summary keys of the runtime itself (:meth:`RunObserver.summary`, :class:`DynamicsSummary`): no package's
#: summary module may declare them (:func:`acds_common.plugins.check_summary_keys`).
COMMON_KEYS = ('scenario', 'steps', 'sim_minutes', 'wall_seconds', 'step_angle_max_rad', 'integration', 'torque_free',
               'momentum_drift_rel', 'energy_drift_rel', 'final_rates_deg_s', 'final_momentum_ftlbs', 'b_min_gauss',
               'b_max_gauss', 'truth_messages', 'truth_digest')


def _summary_modules() -> list:
    """The summary modules the installed packages declare (:data:`acds_common.plugins.SUMMARIES`, in name order),
    after checking that no two declare the same key."""
    plugins.check_summary_keys(COMMON_KEYS)
    return plugins.modules(plugins.SUMMARIES)


class DynamicsSummary:
    """Final rates and momentum, the |B| range seen (every single-vehicle run); the integration's health.

    Integration health, always: the largest step angle θ = (|ω| + 2 ω_orbit)·Δt/substeps over the
    run's steps (``step_angle_max_rad``) against the bounds of :mod:`dynamics.integration_accuracy`
    (``integration``: ok, or the warning bound it passed). A run is torque-free when every step's
    magnetic, gravity-gradient and wheel torque is zero: |H| in ECI and the rotational energy are then
    constants of the motion and their largest relative change is integration error
    (``momentum_drift_rel``, ``energy_drift_rel``; null otherwise, where the change is physics).
    """

    topics = (ODOMETRY, B_BODY, WHEEL_H, WHEEL_HDOT, TORQUE_MAG, TORQUE_GG)

    @staticmethod
    def applies(scenario: Any) -> bool:
        """A single vehicle's run (a formation's vehicles are summarised by a summary module with ``FORMATIONS``)."""
        return not scenario.formation

    def __init__(self, scenario: Any) -> None:
        sc = scenario
        self.inertia = inertia_tensor(*sc.get('spacecraft', 'inertia')) * sc.get('spacecraft', 'inertia_scale')
        self._inertia = mat3(self.inertia)
        self.h0: float | None = None
        self.e0: float | None = None
        self.max_dh = 0.0
        self.max_de = 0.0
        self.final_rates = (0.0, 0.0, 0.0)
        self.final_h = 0.0
        self.b_min = math.inf
        self.b_max = 0.0
        self.torque_free = True
        self._substep_s = sc.control_period_s / sc.get('dynamics', 'substeps')
        self._orbit_rate = accuracy.orbit_rate_max_rad_s(orbit_from_section(sc.values['orbit']))
        self.max_omega = 0.0
        self._last: tuple[Any, Any] | None = None  # (odometry, wheel momentum) of the last step

    def _h_e(self, omega: Any, q: Any, wheel: Any, sqrt: Callable[[Any], Any] = math.sqrt) -> tuple[Any, Any]:
        """|H| in ECI (body + wheels) and the rotational energy of one step's truth (floats, vec3), or of each
        row of a block (each component a column, ``sqrt=np.sqrt``: the same operations, so the same bits)."""
        iw = mv(self._inertia, omega)
        h_body = iw if wheel is None else (iw[0] + wheel[0], iw[1] + wheel[1], iw[2] + wheel[2])
        h = mv(dcm(q), h_body)
        return sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]), 0.5 * dot(omega, iw)

    def step(self, _k: int, values: dict[str, Any]) -> None:
        """One step's truth. The drifts are kept while the run is torque-free only (they are reported only
        then); the final momentum is computed once, from the last step's truth (:meth:`contribute`)."""
        if self.torque_free and any(v is not None and any(v) for v in (values.get(t) for t in self.topics[3:])):
            self.torque_free = False
        odom = values.get(ODOMETRY)
        if odom is not None:
            self._last = (odom, values.get(WHEEL_H))
            omega = norm(odom.angular)
            if omega > self.max_omega:  # max(max_omega, omega), without the call (every step)
                self.max_omega = omega
            if self.h0 is None or self.torque_free:
                h, e = self._h_e(odom.angular, odom.orientation, self._last[1])
                if self.h0 is None:
                    self.h0, self.e0 = h, e
                self.max_dh = max(self.max_dh, abs(h - self.h0))
                self.max_de = max(self.max_de, abs(e - self.e0))
        b = values.get(B_BODY)
        if b is not None:
            g = tesla_to_gauss(norm(b[0]))
            if g < self.b_min:  # min(b_min, g) and max(b_max, g), without the calls
                self.b_min = g
            if g > self.b_max:
                self.b_max = g

    def step_block(self, _k0: int, columns: dict[str, np.ndarray]) -> None:
        """:meth:`step` of each row of a block (:meth:`RunObserver.feed_block`), at once and to the same bits
        (:mod:`acds_common.step_blocks`): the run stops being torque-free at the first row with a torque; the
        drifts take the rows before it (H₀ and E₀, which only the drifts of a torque-free run read, from the first
        of them)."""
        free = self._free_rows(columns)
        odom = columns.get(ODOMETRY)
        if odom is not None and len(odom):
            wheel = columns.get(WHEEL_H)
            self._last = (_ODOMETRY_ROWS.unflatten(odom[-1].tolist()),
                          None if wheel is None else tuple(wheel[-1].tolist()))
            self.max_omega = running_max(self.max_omega, norms(odom[:, 10:13]))
            self._drift_rows(odom[:free], wheel)
        b = columns.get(B_BODY)
        if b is not None:
            g = tesla_to_gauss(norms(b))
            self.b_min, self.b_max = running_min(self.b_min, g), running_max(self.b_max, g)

    def _free_rows(self, columns: dict[str, np.ndarray]) -> int:
        """How many rows of the block come while the run is still torque-free (0 once it is not); clears
        :attr:`torque_free` at the first row with a torque (:meth:`step`'s ``any(v)`` of a vector)."""
        if not self.torque_free:
            return 0
        torques = [nonzero(columns[t]) for t in self.topics[3:] if t in columns]
        n = max((len(c) for c in columns.values()), default=0)
        at = first(np.logical_or.reduce(torques)) if torques else None
        if at is None:
            return n
        self.torque_free = False
        return at

    def _drift_rows(self, odom: np.ndarray, wheel: np.ndarray | None) -> None:
        """The drifts of |H| and E over the rows ``odom`` (and ``wheel``) of a block, as :meth:`step` gives them
        row by row (the first row of the run sets H₀ and E₀)."""
        if not len(odom):
            return
        h, e = self._h_e(tuple(odom[:, 10:13].T), tuple(odom[:, 3:7].T),
                         None if wheel is None else tuple(wheel[:len(odom)].T), np.sqrt)
        if self.h0 is None:
            self.h0, self.e0 = float(h[0]), float(e[0])
        self.max_dh = running_max(self.max_dh, np.abs(h - self.h0))
        self.max_de = running_max(self.max_de, np.abs(e - self.e0))

    def contribute(self, summary: dict[str, Any]) -> None:
        """Add the dynamics keys."""
        if self._last is not None:
            odom, wheel = self._last
            self.final_rates, self.final_h = odom.angular, self._h_e(odom.angular, odom.orientation, wheel)[0]
        theta = (self.max_omega + 2.0 * self._orbit_rate) * self._substep_s
        summary.update({
            'step_angle_max_rad': theta,
            'integration': ('ok' if theta <= accuracy.STEP_ANGLE_WARN_RAD else
                            f'WARNING: step angle above {accuracy.STEP_ANGLE_WARN_RAD:g} rad '
                            f'(raise dynamics.substeps; {accuracy.STUDY})'),
            'torque_free': self.torque_free,
            'momentum_drift_rel': (self.max_dh / self.h0 if self.h0 else 0.0) if self.torque_free else None,
            'energy_drift_rel': (self.max_de / self.e0 if self.e0 else 0.0) if self.torque_free else None,
            'final_rates_deg_s': [math.degrees(v) for v in self.final_rates],
            'final_momentum_ftlbs': float(nms_to_ftlbs(self.final_h)),
            'b_min_gauss': self.b_min if math.isfinite(self.b_min) else None,
            'b_max_gauss': self.b_max,
        })


class RunObserver:
    """The streaming summary of one run (module docstring)."""

    def __init__(self, scenario: Any, graph: Graph) -> None:
        self.scenario = scenario
        self.dt_ns = round(scenario.control_period_s * 1e9)
        self.parts: list[Any] = [DynamicsSummary(scenario)] if DynamicsSummary.applies(scenario) else []
        self.parts += [m.Accumulator(scenario) for m in _summary_modules()
                       if getattr(m, 'FORMATIONS', False) == scenario.formation and m.applies(scenario)]
        wanted = {topics.resolve(t) for p in self.parts for t in p.topics}
        per_step = {spec.topic(out.topic) for spec, out in graph.outputs() if out.every_step}
        self.per_step = sorted(wanted & per_step)
        self.truth = graph.truth_topics()
        self.events = {topics.resolve(t) for p in self.parts for t in getattr(p, 'event_topics', ())}
        self.codecs = {t: Codec(topics.type_of(t)) for t in (*self.per_step, *self.events)}
        #: Step → {per-step topic: value} of the steps not complete yet (:meth:`reads_per_step`).
        self.pending: dict[int, dict[str, Any]] = {}
        self._next = 0
        self._digests = {t: hashlib.sha256() for t in self.truth}
        #: The direct engine's truth messages not hashed yet (:meth:`truth_sink`, :meth:`flush_truth`).
        self._truth_buffers: dict[str, list[bytes]] = {}
        #: How many per-step topics make a step complete.
        self.per_step_count = len(self.per_step)
        self._event_parts = [part for part in self.parts if hasattr(part, 'event')]
        self.truth_messages = 0
        #: The codecs the truth topics are published with (their frame ids): what :meth:`feed_block` encodes.
        self._truth_codecs = {spec.topic(out.topic): Codec(out.msg_type, out.frame_id, out.child_frame_id)
                              for spec, out in graph.outputs() if spec.topic(out.topic) in self._digests}
        #: Per topic a block of steps carries (:meth:`feed_block`), its rows: every truth topic and every per-step
        #: topic a summary reads whose type has fixed layout (not the mode, a DiagnosticArray).
        self.block_topics = {t: c.layout for t, c in {**self.codecs, **self._truth_codecs}.items()
                             if c.layout is not None and (t in self._digests or t in self.per_step)}
        self._block_parts = [part for part in self.parts if hasattr(part, plugins.STEP_BLOCK_ATTRIBUTE)]
        self._row_parts = [part for part in self.parts if not hasattr(part, plugins.STEP_BLOCK_ATTRIBUTE)]
        #: The summary modules a block of steps would not reach whole, with the topics it does not carry for them:
        #: a module without ``step_block`` that reads a per-step topic of no fixed layout (the mode, every step).
        #: :meth:`feed_block` refuses blocks while there is one (the engine feeds such a run one step at a time).
        self.without_blocks = {type(part).__module__: missing for part in self._row_parts
                               if (missing := sorted({topics.resolve(t) for t in part.topics} & set(self.per_step)
                                                     - set(self.block_topics)))}

    def reads(self) -> set[str]:
        """Absolute names of every topic the summaries and the truth digest read (what :meth:`feed_raw` uses)."""
        return {*self.per_step, *self.truth, *self.events}

    # ---- feeding ------------------------------------------------------------------------------------
    def feed_raw(self, topic: str, data: bytes) -> None:
        """A serialized message of ``topic`` (absolute name), as the monitor receives it."""
        digest = self._digests.get(topic)
        if digest is not None:
            digest.update(data)
            self.truth_messages += 1
        codec = self.codecs.get(topic)
        if codec is not None:
            t_ns, value = codec.decode(data)
            self.feed_value(topic, t_ns // self.dt_ns, value)

    def truth_sink(self, topic: str) -> Callable[[bytes], None] | None:
        """For the direct engine: what takes each serialized message of ``topic`` (absolute) when it is a truth
        topic, else None: the engine encodes nothing else it does not record. The messages are kept until
        :meth:`flush_truth` hashes them into the digest in one update (the same digest: SHA-256 streams)."""
        if topic not in self._digests:
            return None
        return self._truth_buffers.setdefault(topic, []).append

    def flush_truth(self) -> None:
        """Hash and count the messages :meth:`truth_sink` kept (the engine calls it now and then: bounded memory)."""
        for topic, buffer in self._truth_buffers.items():
            if buffer:
                self._digests[topic].update(b''.join(buffer))
                self.truth_messages += len(buffer)
                buffer.clear()

    def reads_per_step(self, topic: str) -> bool:
        """For the direct engine: whether the summaries read per-step ``topic``; its values then go into
        :attr:`pending` (step → {topic: value}), and :meth:`drain` is called once a step's are all there
        (:attr:`per_step_count`): :meth:`feed_value` without a call per value."""
        return topic in self.codecs and topic not in self.events

    def event_sink(self, topic: str) -> Callable[[str, Any], None] | None:
        """For the direct engine: what takes each value of event ``topic`` when a summary reads it, else None."""
        return self._feed_event if topic in self.events else None

    @property
    def next_step(self) -> int:
        """The first step not handed to the summaries yet (every step before it is complete and fed)."""
        return self._next

    def drain(self) -> None:
        """Hand the complete steps of :attr:`pending` to the summaries, in step order."""
        self._drain(final=False)

    def feed_value(self, topic: str, k: int, value: Any) -> None:
        """A decoded value of step k (of a topic no summary reads: nothing)."""
        if topic not in self.codecs:
            return
        if topic in self.events:
            self._feed_event(topic, value)
        else:
            self._feed_step(topic, k, value)

    def _feed_event(self, topic: str, value: Any) -> None:
        for part in self._event_parts:
            part.event(topic, value)

    def _feed_step(self, topic: str, k: int, value: Any) -> None:
        values = self.pending.get(k)
        if values is None:
            values = self.pending[k] = {}
        values[topic] = value
        if len(values) >= self.per_step_count:  # step k complete: it (and what waited for it) can go
            self._drain(final=False)

    def _drain(self, final: bool) -> None:
        pending = self.pending
        while self._next in pending:
            values = pending[self._next]
            if not final and len(values) < self.per_step_count:
                return
            del pending[self._next]
            for part in self.parts:
                part.step(self._next, values)
            self._next += 1
        if final and pending:  # steps after a gap (never in a complete run): in order
            self._next = min(pending)
            self._drain(final=True)

    def feed_block(self, k0: int, n: int, columns: dict[str, np.ndarray], first: dict[str, int] | None = None) -> None:
        """Steps k0 … k0 + n − 1 at once (the direct engine's compiled blocks), exactly as their values fed one by one.

        ``columns`` holds, per topic of :attr:`block_topics`, float64 rows (m × the width of its
        :class:`acds_common.cdr.RowLayout`), row i the value stamped step ``first[topic] + i`` (``first`` defaults
        to k0; a producer's ``stamp_offset`` shifts it, so a block of loop steps k0 … hands the time owner's rows
        from k0 + 1). Every truth topic is there (m may be 0); the truth messages are encoded at once
        (:meth:`acds_common.cdr.Codec.encode_block`: the same bytes, so the same digest). The steps every topic's
        rows cover and nothing fed before touches go to each summary module at once (``Accumulator.step_block``;
        without one, each step's values unflattened to ``step``); the block's other steps (its edges: the values
        a step fed one by one left in :attr:`pending`) are joined and fed one by one; rows past k0 + n wait in
        :attr:`pending` for their steps' other values. (A step completed before, like step k0 when every topic is
        one step ahead, is not fed again: the block's steps start at the first step not fed yet.)

        A per-step topic without fixed layout (the mode) is not in a block: the block's steps carry no value of it,
        which a summary reads as "no change". The engine runs the steps that change the mode in Python and feeds
        them one by one (:meth:`feed_value`, :attr:`pending`); a summary module without ``step_block`` that reads
        such a topic (:attr:`without_blocks`) makes blocks refused (ValueError). Steps are fed once each, in order: a
        block after a step not fed yet (k0 beyond it), or with rows of a step fed already, raises ValueError."""
        spans = self._spans(k0, n, columns, first or {})
        start, end = self._next, max(self._next, k0 + n)
        self._hash_block(columns, spans)
        with np.errstate(all='ignore'):  # a NaN or an infinity goes on silently, as in Python's float arithmetic
            for a, b, joined in self._segments(start, end, spans):
                if joined:
                    self._step_joined(a, columns, spans)
                else:
                    self._step_rows(a, b, columns, spans)
        self._park(end, columns, spans)
        self._next = end
        self._drain(final=False)

    def _spans(self, k0: int, n: int, columns: dict[str, np.ndarray], first: dict[str, int]) -> dict[str, tuple[int, int]]:
        """(first step, row count) of each topic of a block, after checking the block comes in order (no step
        before k0 left unfed, no row of a step fed already) and whole (every truth topic)."""
        self._drain(final=False)
        spans = {t: (first.get(t, k0), len(rows)) for t, rows in columns.items()}
        early = [t for t, (f, m) in spans.items() if f < self._next and m]
        if k0 > self._next or early:
            raise ValueError(f'a block of steps {k0}…{k0 + n - 1} fed when step {self._next} is the next to feed'
                             f'{" with rows of steps fed already: " + ", ".join(early) if early else ""}: '
                             'steps must be fed once each, in order')
        missing = [t for t in self._digests if t not in columns]
        if missing:
            raise ValueError(f'a block of steps {k0}…{k0 + n - 1} lacks the truth topic(s) {", ".join(missing)}')
        if self.without_blocks:
            raise ValueError('blocks of steps do not carry what ' + '; '.join(
                f'{module} reads every step ({", ".join(ts)})' for module, ts in self.without_blocks.items()))
        return spans

    def _hash_block(self, columns: dict[str, np.ndarray], spans: dict[str, tuple[int, int]]) -> None:
        """The truth messages of a block into the digests, after the messages kept before it (:meth:`flush_truth`)."""
        self.flush_truth()
        for topic, digest in self._digests.items():
            f, m = spans[topic]
            digest.update(self._truth_codecs[topic].encode_block(np.arange(f, f + m, dtype=np.int64) * self.dt_ns,
                                                                 columns[topic]))
            self.truth_messages += m

    def _segments(self, start: int, end: int, spans: dict[str, tuple[int, int]]) -> list[tuple[int, int, bool]]:
        """The block's steps [start, end) as runs [a, b): the runs the rows of every topic the summaries read cover
        with nothing pending, and each other step alone, to be joined (an edge: a row missing, or values fed before)."""
        read = [spans[t] for t in self.per_step if t in spans]
        lo = max([start, *(f for f, _m in read)])
        hi = min([end, *(f + m for f, m in read)])
        edges = {*range(start, min(lo, end)), *range(max(hi, start), end), *(k for k in self.pending if start <= k < end)}
        runs, a = [], start
        for e in [*sorted(edges), end]:
            if a < e:
                runs.append((a, e, False))
            if e < end:
                runs.append((e, e + 1, True))
            a = e + 1
        return runs

    def _rows_of(self, columns: dict[str, np.ndarray], spans: dict[str, tuple[int, int]], a: int, b: int
                 ) -> dict[str, np.ndarray]:
        """The rows of steps [a, b) of the per-step topics the summaries read (every topic covers them)."""
        return {t: columns[t][a - spans[t][0]:b - spans[t][0]] for t in self.per_step if t in columns}

    def _step_rows(self, a: int, b: int, columns: dict[str, np.ndarray], spans: dict[str, tuple[int, int]]) -> None:
        """Steps [a, b), all rows: to each summary module's ``step_block``, or row by row unflattened to its ``step``."""
        rows = self._rows_of(columns, spans, a, b)
        for part in self._block_parts:
            part.step_block(a, rows)
        if self._row_parts:
            lists = {t: (self.block_topics[t].unflatten, r.tolist()) for t, r in rows.items()}
            for i in range(b - a):
                values = {t: unflatten(r[i]) for t, (unflatten, r) in lists.items()}
                for part in self._row_parts:
                    part.step(a + i, values)

    def _values_at(self, k: int, columns: dict[str, np.ndarray], spans: dict[str, tuple[int, int]]
                   ) -> dict[str, Any]:
        """Step k's values of the block's rows that hold it (unflattened), for the per-step topics read."""
        out = {}
        for t in self.per_step:
            f, m = spans.get(t, (0, 0))
            if f <= k < f + m:
                out[t] = self.block_topics[t].unflatten(columns[t][k - f].tolist())
        return out

    def _step_joined(self, k: int, columns: dict[str, np.ndarray], spans: dict[str, tuple[int, int]]) -> None:
        """An edge step of a block: its values fed before (:attr:`pending`) and its rows, to every ``step``."""
        values = {**self.pending.pop(k, {}), **self._values_at(k, columns, spans)}
        for part in self.parts:
            part.step(k, values)

    def _park(self, end: int, columns: dict[str, np.ndarray], spans: dict[str, tuple[int, int]]) -> None:
        """The rows stamped at or after ``end`` into :attr:`pending` (their steps' other values come later)."""
        last = max((f + m for f, m in spans.values()), default=end)
        for k in range(end, last):
            values = self._values_at(k, columns, spans)
            if values:
                self.pending.setdefault(k, {}).update(values)

    # ---- result -------------------------------------------------------------------------------------
    def truth_digest(self) -> str:
        """The run's truth digest (module docstring)."""
        self.flush_truth()
        h = hashlib.sha256()
        for topic in self.truth:
            h.update(topic.encode())
            h.update(self._digests[topic].hexdigest().encode())
        return h.hexdigest()

    def summary(self, steps: int, wall_seconds: float) -> dict[str, Any]:
        """The run summary (every key, null where not applicable; never a non-finite number)."""
        self._drain(final=True)
        sc = self.scenario
        summary: dict[str, Any] = {
            'scenario': sc.name,
            'steps': steps,
            'sim_minutes': steps * sc.control_period_s / 60,
            'wall_seconds': round(wall_seconds, 3),
        }
        for part in self.parts:
            part.contribute(summary)
        for module in _summary_modules():
            module.null_keys(summary)
        self.flush_truth()
        summary['truth_messages'] = self.truth_messages
        summary['truth_digest'] = self.truth_digest()
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


def summary_json(obj: Any, indent: int | None = 2) -> tuple[str, list[str]]:
    """Strict JSON text of a summary (or a list of them) with every non-finite number written as ``null``,
    and the keys that were replaced (e.g. ``passes[0].ripple_pct``); ``indent=None``: one line."""
    replaced: list[str] = []
    text = json.dumps(_finite(obj, '', replaced), indent=indent, allow_nan=False) + '\n'
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
