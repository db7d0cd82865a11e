"""The run observer fed blocks of steps gives the summary and truth digest it gives fed step by step, exactly
(acds_runtime.summary ``RunObserver.feed_block``, ``Accumulator.step_block``; spec §2 "the same data bit for bit").

One direct-engine run of heao_b_acquisition is recorded (every per-step value the summaries read and every truth
message), then replayed into fresh observers: step by step, and by blocks of several sizes between the steps
that change the mode (which the engine runs in Python and feeds one by one), with and without extra
one-by-one steps in between, and with summary modules that have no ``step_block`` (the observer unflattens).
"""

from __future__ import annotations

import math
import random
from typing import Any, NamedTuple

import numpy as np
import pytest
from acds_common import topics
from acds_common.cdr import Codec
from acds_common.graph import build_graph
from acds_common.parameters import node_parameters
from acds_common.scenario import load_scenario
from acds_common.step_blocks import first, nonzero, norms, running_max, running_min
from acds_common.vec3 import norm
from acds_runtime.direct import DirectRun
from acds_runtime.summary import (
    B_BODY,
    ODOMETRY,
    TORQUE_GG,
    TORQUE_MAG,
    WHEEL_H,
    WHEEL_HDOT,
    DynamicsSummary,
    RunObserver,
    summary_json,
)


class Recording(NamedTuple):
    """One run's data: its scenario and graph, step count (0 … steps − 1 fed), each step's values the summaries
    read, each truth topic's messages, the rows of every block topic over the whole run, the run's summary."""

    scenario: Any
    graph: Any
    steps: int
    values: list[dict]
    truth: dict[str, list[bytes]]
    rows: dict[str, np.ndarray]
    summary: dict
    #: Each topic's stamp offset: loop step k gives its value of step k + offset (the time owner's truth: 1).
    offsets: dict[str, int]


class _Recorder:
    """A summary part that keeps each step's values (what the summaries read)."""

    topics = ()

    def __init__(self) -> None:
        self.values: list[dict] = []

    def step(self, k, values):
        assert k == len(self.values)
        self.values.append(dict(values))

    def contribute(self, summary):
        pass


def _record(sc, steps: int | None = None) -> Recording:
    """Run ``sc`` on the direct engine, keeping every value the summaries read and every truth message."""
    run = DirectRun(sc, steps=steps, fused=False)  # every value fed one by one, as the recorder keeps them
    recorder = _Recorder()
    run.observer.parts.append(recorder)
    # The engine's routes append each truth message to the observer's buffer of its topic (truth_sink), which
    # flush_truth hashes and empties: keep what each flush finds.
    buffers = {t: run.observer.truth_sink(t).__self__ for t in run.observer.truth}
    truth: dict[str, list[bytes]] = {t: [] for t in buffers}
    flush = run.observer.flush_truth

    def keep_and_flush():
        for t, buffer in buffers.items():
            truth[t] += buffer
        flush()
    run.observer.flush_truth = keep_and_flush
    result = run.run()
    n = result.steps + 1
    assert len(recorder.values) == n and all(len(messages) == n for messages in truth.values())
    rows = {}
    for topic, layout in RunObserver(sc, run.graph).block_topics.items():
        if topic in truth:
            decode = Codec(topics.type_of(topic)).decode
            flat = [layout.flatten(decode(m)[1]) for m in truth[topic]]
        else:
            flat = [layout.flatten(v[topic]) for v in recorder.values]
        rows[topic] = np.array(flat, dtype=np.float64).reshape(n, layout.width)
    offsets = {spec.topic(out.topic): out.stamp_offset for spec, out in run.graph.outputs()}
    topics_fed = {*truth, *(t for v in recorder.values for t in v)}
    return Recording(sc, run.graph, n, recorder.values, truth, rows, result.summary,
                     {t: offsets[t] for t in topics_fed})


@pytest.fixture(scope='module')
def acquisition() -> Recording:
    """heao_b_acquisition to capture (the owner ends the run there): Mode 1A, Mode 1B, capture."""
    return _record(load_scenario('heao_b_acquisition'))


@pytest.fixture(scope='module')
def torque_free(tmp_path_factory) -> Recording:
    """HEAO-B tumbling without gravity gradient or actuators: the drifts of H and E are kept every step."""
    path = tmp_path_factory.mktemp('torque_free') / 'torque_free.yaml'
    path.write_text('extends: free_tumble_heao_b\nname: torque_free_heao_b\nnodes: [rigid_body]\n'
                    'dynamics:\n  gravity_gradient: false\n')
    return _record(load_scenario(str(path)), steps=3000)


def _text(summary: dict) -> str:
    return summary_json({**summary, 'wall_seconds': 0.0})[0]


def _feed_topic(observer: RunObserver, topic: str, k: int, rec: Recording) -> None:
    """``topic``'s value of step k as the direct engine feeds it today: a truth message to its sink, a value the
    summaries read to the observer."""
    if topic in rec.truth:
        observer.truth_sink(topic)(rec.truth[topic][k])
    if topic in rec.values[k]:
        observer.feed_value(topic, k, rec.values[k][topic])


def _feed_step(observer: RunObserver, k: int, rec: Recording, loop: bool) -> None:
    """Step k fed one by one: its values (``loop=False``), or as loop step k of the engine gives them: each
    topic's value of step k + its stamp offset (``loop=True``; the values of step 0 of an offset come first)."""
    if loop and k == 0:
        for topic in (t for t, offset in rec.offsets.items() if offset):
            _feed_topic(observer, topic, 0, rec)
    for topic, offset in rec.offsets.items():
        if k + offset * loop < rec.steps:
            _feed_topic(observer, topic, k + offset * loop, rec)


def _block(rec: Recording, k0: int, n: int, loop: bool) -> tuple[dict, dict]:
    """The rows and first steps of loop steps k0 … k0 + n − 1 (``loop``: each topic's shifted by its stamp offset),
    or of steps k0 … k0 + n − 1."""
    first = {t: k0 + rec.offsets[t] * loop for t in rec.rows}
    return {t: r[first[t]:first[t] + n] for t, r in rec.rows.items()}, first


def _mode_changes(values: list[dict]) -> set[int]:
    """The steps whose mode value differs from the step before (the ones the engine runs in Python)."""
    modes = [v.get('/acds/mode') for v in values]
    return {k for k, m in enumerate(modes) if k == 0 or m != modes[k - 1]}


#: Small blocks are fed within this many steps of a step fed singly, blocks of :data:`FAR` steps farther away.
NEAR, FAR = 300, 4096


def _plan(steps: int, size: int, one_by_one: set[int]) -> list[tuple[int, int]]:
    """(k0, n) of each block of at most ``size`` steps near the steps ``one_by_one`` (:data:`NEAR`; :data:`FAR`
    steps farther), n = 0 for a step of ``one_by_one`` fed singly."""
    near = {k for s in one_by_one for k in range(s - NEAR, s + NEAR)}
    plan, k = [], 0
    while k < steps:
        if k in one_by_one:
            plan.append((k, 0))
            k += 1
            continue
        limit = size if k in near else FAR
        n = 1
        while n < limit and k + n < steps and k + n not in one_by_one:
            n += 1
        plan.append((k, n))
        k += n
    return plan


def _replay_blocks(rec: Recording, size: int, one_by_one: set[int], rows_only: bool = False, loop: bool = True
                   ) -> dict:
    """The summary of a fresh observer fed blocks of at most ``size`` (loop) steps, the steps ``one_by_one`` singly
    (as the engine's Python steps feed them, :func:`_feed_step`)."""
    observer = RunObserver(rec.scenario, rec.graph)
    if rows_only:  # as if no summary module had step_block: each step's values unflattened
        observer._row_parts, observer._block_parts = observer.parts, []
    blocks = [(k0, n, *_block(rec, k0, n, loop)) for k0, n in _plan(rec.steps, size, one_by_one)]
    for k0, n, columns, firsts in blocks:
        if not n:
            _feed_step(observer, k0, rec, loop)
            continue
        if loop and k0 == 0:  # the engine's initial(): the values of step 0 of an offset, one by one
            for topic in (t for t, offset in rec.offsets.items() if offset):
                _feed_topic(observer, topic, 0, rec)
        observer.feed_block(k0, n, columns, firsts)
    return observer.summary(rec.steps - 1, 0.0)


def _replay_steps(rec: Recording, loop: bool = True) -> dict:
    """The summary of a fresh observer fed every step one by one (:func:`_feed_step`)."""
    observer = RunObserver(rec.scenario, rec.graph)
    for k in range(rec.steps):
        _feed_step(observer, k, rec, loop)
    return observer.summary(rec.steps - 1, 0.0)


def test_the_recording_replays_the_run(acquisition, torque_free):
    """Step by step, the recorded values give the run's own summary and digest (the replay is faithful)."""
    for rec in (acquisition, torque_free):
        assert _text(_replay_steps(rec)) == _text(rec.summary)
        assert _text(_replay_steps(rec, loop=False)) == _text(rec.summary)
    assert {acquisition.offsets[t] for t in acquisition.truth} == {1}  # the time owner's: loop step k gives k + 1
    assert acquisition.summary['acquisition_time_min'] is not None  # the run reaches Mode 1B and capture
    assert torque_free.summary['torque_free'] and torque_free.summary['momentum_drift_rel'] > 0.0


@pytest.mark.parametrize('loop', (True, False), ids=('loop_steps', 'stamped_steps'))
@pytest.mark.parametrize('size', (1, 7, 4096, 100_000))
def test_blocks_give_the_same_summary_and_digest(acquisition, size, loop):
    """Blocks between the steps that change the mode (Mode 1B, capture: the last step; ``size`` near them), the rows
    of a block of loop steps each shifted by its topic's stamp offset (the time owner's truth one step ahead) or all
    stamped alike."""
    changes = _mode_changes(acquisition.values)
    assert len(changes) >= 3  # the start, Mode 1B, capture (the last step)
    assert _text(_replay_blocks(acquisition, size, changes, loop=loop)) == _text(acquisition.summary)


@pytest.mark.parametrize('loop', (True, False), ids=('loop_steps', 'stamped_steps'))
def test_blocks_between_steps_fed_one_by_one(acquisition, loop):
    """Blocks with steps fed singly in between (the truth kept by the sinks hashed first, the values of a step
    fed singly before its block joined with its rows)."""
    rng = random.Random(36)
    singles = _mode_changes(acquisition.values) | {rng.randrange(acquisition.steps) for _ in range(200)}
    assert _text(_replay_blocks(acquisition, 613, singles, loop=loop)) == _text(acquisition.summary)


@pytest.mark.parametrize(('size', 'singles'), ((7, {0}), (4096, set()), (4096, {0, 1, 2500})))
def test_blocks_of_a_torque_free_run(torque_free, size, singles):
    """Every row of every block counts in the drifts of H and E; every topic is the time owner's (one step ahead of
    its loop step), so a block's first step was fed with the step before it."""
    assert _text(_replay_blocks(torque_free, size, singles)) == _text(torque_free.summary)


def test_a_module_without_step_block_takes_each_step(acquisition):
    summary = _replay_blocks(acquisition, 4096, _mode_changes(acquisition.values), rows_only=True)
    assert _text(summary) == _text(acquisition.summary)


def test_a_block_out_of_order_or_without_a_truth_topic_is_refused(acquisition):
    observer = RunObserver(acquisition.scenario, acquisition.graph)
    columns = {t: r[:4] for t, r in acquisition.rows.items()}
    with pytest.raises(ValueError, match='fed once each, in order'):
        observer.feed_block(1, 3, {t: c[1:] for t, c in columns.items()})
    topic = sorted(observer.truth)[0]
    with pytest.raises(ValueError, match=f'lacks the truth topic.*{topic}'):
        observer.feed_block(0, 4, {t: c for t, c in columns.items() if t != topic})
    observer.feed_block(0, 4, columns)
    with pytest.raises(ValueError, match='fed once each, in order'):
        observer.feed_block(0, 4, columns)
    with pytest.raises(ValueError, match=f'rows of steps fed already: {topic}'):
        observer.feed_block(4, 4, {t: r[3:7] for t, r in acquisition.rows.items()}, {topic: 3})


def test_a_module_that_reads_the_mode_every_step_refuses_blocks():
    """The SSS summary reads the pass mode every step and has no step_block: a block (no mode) would lose it."""
    sc = load_scenario('sss_a_attitude')
    observer = RunObserver(sc, build_graph(node_parameters(sc, 10, 0.0)))
    assert observer.without_blocks == {'ascs_mode_manager.sss_summary': [topics.resolve(topics.MODE)]}
    columns = {t: np.zeros((2, layout.width)) for t, layout in observer.block_topics.items()}
    with pytest.raises(ValueError, match=r'ascs_mode_manager.sss_summary reads every step \(/acds/mode\)'):
        observer.feed_block(0, 2, columns)


# ---- the block reductions against their per-step loops, on rows with NaN, ±inf, −0.0 ----------------------------
SPECIAL = (math.nan, math.inf, -math.inf, -0.0, 0.0)


def _rows(rng: np.random.Generator, n: int, width: int, scale: float) -> np.ndarray:
    rows = rng.normal(size=(n, width)) * scale
    at = rng.random(size=rows.shape) < 0.01
    rows[at] = rng.choice(SPECIAL, size=int(at.sum()))
    return rows


@pytest.mark.parametrize('seed', range(4))
def test_the_reductions_are_the_per_step_loops(seed):
    rng = np.random.default_rng(seed)
    rows = _rows(rng, 300, 3, 10.0)
    assert norms(rows).tobytes() == np.array([norm(r) for r in rows.tolist()]).tobytes()
    values = np.abs(rows[:, 0])
    top, low = 0.0, math.inf
    for v in values.tolist():
        top, low = v if v > top else top, v if v < low else low
    assert (running_max(0.0, values), running_min(math.inf, values)) == (top, low)
    mask = values > 15.0
    assert first(mask) == next((i for i, m in enumerate(mask) if m), None)
    assert nonzero(rows).tolist() == [any(r) for r in rows.tolist()]


@pytest.mark.parametrize('seed', range(6))
def test_step_block_is_step_row_by_row(seed):
    """DynamicsSummary and the HEAO summary fed random blocks of random rows (torques from a random step on, wheel
    momenta past capacity now and then, special values) end as fed the rows one by one."""
    from heao_mission.heao_summary import Accumulator

    rng = np.random.default_rng(seed)
    sc = load_scenario('heao_b_acquisition')
    n = 400
    capacity = float(np.min(Accumulator(sc).capacity))
    columns = {ODOMETRY: _rows(rng, n, 13, 0.05), B_BODY: _rows(rng, n, 12, 3e-5),
               WHEEL_H: _rows(rng, n, 3, capacity * 0.4), topics.resolve(topics.MOMENT_COMMAND): _rows(rng, n, 3, 900.0)}
    start = int(rng.integers(0, n + 1))  # the first step with a torque (n: none)
    for topic in (WHEEL_HDOT, TORQUE_MAG, TORQUE_GG):
        rows = _rows(rng, n, 3, 1e-3)
        rows[:start] = rng.choice((0.0, -0.0), size=(start, 3))
        columns[topic] = rows
    layouts = {t: Codec(topics.type_of(t)).layout for t in columns}
    one, block = [(DynamicsSummary(sc), Accumulator(sc)) for _ in range(2)]
    for k in range(n):
        values = {t: layouts[t].unflatten(rows[k].tolist()) for t, rows in columns.items()}
        for part in one:
            part.step(k, values)
    k0 = 0
    while k0 < n:
        size = int(rng.integers(1, 60))
        for part in block:
            part.step_block(k0, {t: rows[k0:k0 + size] for t, rows in columns.items()})
        k0 += size
    for a, b in zip(one, block, strict=True):
        sa, sb = {}, {}
        a.contribute(sa)
        b.contribute(sb)
        assert summary_json(sa)[0] == summary_json(sb)[0]
