"""The direct engine's fused loop: the quiet steps of a run in one compiled loop, composed from the stages' declarations.

Every stage of the graph may declare a fused form (:mod:`acds_common.fused`: a kernel on floats, its parameters
and state, the inputs it takes and the outputs it gives). When all of them do, :class:`FusedLoop` writes out
(as :mod:`~acds_runtime.step_program` writes the Python step) the source of one function that runs steps k0,
k0 + 1, … of the graph: the stages in :meth:`~acds_common.graph.Graph.firing_order`, each kernel handed its
inputs of step k − lag through local variables (a lag-0 input the value its producer gave earlier in the same
step; a producer's stamp offset counted, so the time owner's truth of step k is its stage's output of step
k − 1), every output that something outside the loop reads (an input's store, the truth digest, the per-step
summaries) written into a float64 row of a preallocated buffer. It compiles that function with numba
(:mod:`acds_common.kernels`: no ``fastmath``, the same operations in the same order give the same bits as each
kernel's plain form and the Python stage it replaces). The loop ends when a stage says its step is not quiet
(a transition, an event, a refused input, the run's end: the stages' states are then those at the start of that
step, which runs through the Python step program as always) or the buffers are full.

After a block, each stage's state goes back into its stepper (``restore``), and the rows become the values the
Python path would have routed: the inputs' stores (the steps later steps read), the truth topics' messages for
the digest and the summaries' per-step values, step by step and topic by topic as the step program routes them,
so the data, the digest and the summaries are the same bits with or without the loop.

Which inputs a stage's kernel does not take (the mode report: a Python object) are *held*: the producer's
declaration names the object it returns at every quiet step, the consumer is asked for its form knowing that
object, and the block starts only when every step it reads before the block gave that very object.
The loop runs only without a bag and a live view (:class:`~acds_runtime.direct.DirectRun` decides, and after a
step from which no block could start asks again after 1, 2, 4 … steps).

The composed module is written once per structure under ``acds_runtime/__pycache__/fused_loops/`` (named by the
hash of its source: it imports the kernels by name, and the step period is an argument), so numba keeps its machine
code on disk beside it, stamped with the kernels' and their helpers' sources (:mod:`acds_common.kernel_cache`):
one compile per machine (``acds_runtime.warm_kernels`` at set-up), one load per process.
:func:`stage_costs` times each stage's kernel alone, for ``acds bench``.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
from acds_common import kernels
from acds_common.fused import FusedStage, Output, leaves, nested, width
from acds_common.graph import Graph
from acds_common.stepper import Stepper

from .step_program import Route

#: Steps of one block at most (the rows of each buffer).
BLOCK_STEPS = 2048
#: The block functions compiled in this process, by structure (:attr:`_Plan.key`): (function, source).
_COMPILED: dict[Any, tuple[Any, str]] = {}


@dataclass(frozen=True)
class _Read:
    """One input of a stage whose source runs: its key, topic, producer node and output key, lag."""

    key: str
    topic: str
    source: str
    output: str
    lag: int


@dataclass(frozen=True)
class _Produced:
    """An output a fused stage gives: the stage's index, the output's index in the kernel's outputs, its declaration,
    the producer's stamp offset and where it goes outside the loop."""

    stage: int
    index: int
    output: Output
    offset: int
    route: Route | None


class FusedLoop:
    """The fused loop of one direct run (module docstring): :meth:`block` runs a block of quiet steps from step k0."""

    def __init__(self, graph: Graph, steppers: dict[str, Stepper], routes: dict[str, dict[str, Route]],
                 stores: dict[str, dict[int, Any]], observer: Any, dt_ns: int, max_lag: int) -> None:
        self.graph = graph
        self.steppers = steppers
        self.routes = routes
        self.dt_ns = dt_ns
        self.max_lag = max_lag
        #: The run observer, its steps waiting for values (step → {topic: value}) and its drain.
        self._observer, self._pending, self._drain = observer, observer.pending, observer.drain
        #: Per block structure, where the observer's rows come from (:meth:`_block_plan`).
        self._block_sources: dict[Any, dict[str, tuple[int, int]]] = {}
        self.stages: list[tuple[str, str]] = [(name, stage.name) for name, stage in graph.firing_order()]
        present = set(graph.nodes)
        self._reads: list[tuple[_Read, ...]] = []
        for name, stage in graph.firing_order():
            spec = graph.nodes[name]
            reads = []
            for inp in stage.inputs:
                if inp.source not in present:
                    continue
                topic = spec.topic(inp.topic)
                producer = graph.nodes[inp.source]
                key = next(out.key for out in producer.outputs if producer.topic(out.topic) == topic)
                reads.append(_Read(inp.key, topic, inp.source, key, inp.lag))
            self._reads.append(tuple(reads))
        self._offsets = {(spec.instance, out.key): out.stamp_offset for spec, out in graph.outputs()}
        #: Per node, the keys of its per-step outputs something reads (a store, the digest, a summary).
        self._per_step_read = {name: [out.key for out in graph.nodes[name].outputs
                                      if out.every_step and (r := routes[name].get(out.key)) is not None and r.read()]
                               for name, _stage in self.stages}
        self._stores = stores
        self._buffers: dict[Any, list[np.ndarray]] = {}
        #: The plans worked out so far, by the stages' declared kernels, inputs and outputs (:meth:`_plan`).
        self._plans: dict[Any, _Plan] = {}
        self._possible = all(hasattr(steppers[name], 'fused') for name, _stage in self.stages)
        #: Steps run fused so far, blocks, and the wall seconds spent in the compiled loop (for ``acds bench``).
        self.fused_steps = 0
        self.blocks = 0
        self.compiled_s = 0.0

    @property
    def possible(self) -> bool:
        """Whether every stepper of the graph has a fused form at all."""
        return self._possible

    # ---- one block ---------------------------------------------------------------------------------
    def _value_at(self, topic: str, index: int) -> Any:
        return self._stores[topic][index]

    def _declare(self, k0: int) -> list[FusedStage] | None:
        """Every stage's fused form for a block from step k0, or None when one has none or a held input moves."""
        declared: list[FusedStage] = []
        for (name, stage), reads in zip(self.stages, self._reads, strict=True):
            held = {}
            for r in reads:
                last = k0 - 1 + self._offsets[(r.source, r.output)]  # the last index its producer wrote
                index = min(k0 - r.lag, last)
                store = self._stores.get(r.topic)
                if store is None or index not in store:
                    return None
                held[r.key] = store[index]
            fs = self.steppers[name].fused(stage, held)  # type: ignore[attr-defined]
            if fs is None:
                return None
            declared.append(fs)
        by_node = dict(zip((name for name, _stage in self.stages), declared, strict=True))
        for name, fs in by_node.items():  # every per-step output something reads: given by the kernel or held
            given = {o.key for o in fs.outputs} | set(fs.held)
            if any(key not in given for key in self._per_step_read[name]):
                return None
        for fs, reads in zip(declared, self._reads, strict=True):
            for r in reads:
                producer = by_node[r.source]
                if r.key in fs.inputs:
                    if not any(o.key == r.output for o in producer.outputs):
                        return None
                    continue
                if r.output not in producer.held:
                    return None
                obj = producer.held[r.output]
                offset = self._offsets[(r.source, r.output)]
                store = self._stores[r.topic]
                if any(store.get(i, obj) is not obj for i in range(min(k0 - r.lag, k0 - 1 + offset), k0 + offset)):
                    return None
        return declared

    def block(self, k0: int) -> int:
        """Run the quiet steps from k0 in the compiled loop; return how many ran (0: none could)."""
        declared = self._declare(k0)
        if declared is None:
            return 0
        plan = self._plan(declared)
        fn, buffers = self._function(plan)
        args: list[Any] = [k0, BLOCK_STEPS, self.dt_ns]
        for fs in declared:
            args += [fs.params, fs.state]
        for topic, (shape, depth, offset) in plan.registers.items():
            args += [nested(self._value_at(topic, k0 + offset - 1 - j), shape) for j in range(depth)]
        args += buffers
        t0 = time.perf_counter()
        result = fn(*args)
        self.compiled_s += time.perf_counter() - t0
        n = result[0]
        for fs, state in zip(declared, result[1:], strict=True):
            fs.restore(state)
        if n:
            self._route(plan, declared, buffers, k0, n)
            self.fused_steps += n
            self.blocks += 1
        return n

    # ---- composition -------------------------------------------------------------------------------
    def _plan(self, declared: list[FusedStage]) -> _Plan:
        """The structure of the loop for these declarations (what the compiled function depends on), worked out
        once per run for each set of kernels, input keys and outputs the stages declare (a block after a step that
        was not quiet mostly has the structure of the block before)."""
        key = tuple((fs.kernel, fs.inputs, fs.outputs) for fs in declared)
        plan = self._plans.get(key)
        if plan is None:
            plan = self._plans[key] = self._structure(declared)
        return plan

    def _structure(self, declared: list[FusedStage]) -> _Plan:
        """:meth:`_plan` worked out."""
        names = [name for name, _stage in self.stages]
        produced: dict[tuple[str, str], _Produced] = {}
        for i, (name, fs) in enumerate(zip(names, declared, strict=True)):
            for j, out in enumerate(fs.outputs):
                produced[(name, out.key)] = _Produced(i, j, out, self._offsets[(name, out.key)],
                                                      self.routes[name].get(out.key))
        position = {name: i for i, name in enumerate(names)}
        registers: dict[str, tuple[Any, int, int]] = {}
        args: list[list[tuple[str, Any]]] = []  # per stage: (how, what) of each kernel input
        for i, (fs, reads) in enumerate(zip(declared, self._reads, strict=True)):
            by_key = {r.key: r for r in reads}
            stage_args = []
            for key in fs.inputs:
                r = by_key[key]
                p = produced[(r.source, r.output)]
                back = p.offset + r.lag - 1
                if back < 0:  # lag 0, no offset: the producer's output earlier in this step
                    if position[r.source] >= i:
                        raise ValueError(f'{names[i]} reads {r.topic} of this step before {r.source} fires')
                    stage_args.append(('new', (p.stage, p.index)))
                    continue
                shape, depth, _offset = registers.get(r.topic, (p.output.shape, 0, p.offset))
                registers[r.topic] = (shape, max(depth, back + 1), p.offset)
                stage_args.append(('reg', (r.topic, back)))
            args.append(stage_args)
        topics_of = {p.route.topic: key for key, p in produced.items() if p.route is not None}
        written = tuple(key for key, p in produced.items() if p.route is not None and p.route.read())
        register_producers = {topic: (produced[topics_of[topic]].stage, produced[topics_of[topic]].index)
                              for topic in registers}
        kernels_ = tuple(fs.kernel for fs in declared)
        return _Plan(names, kernels_, args, registers, register_producers, written, produced,
                     tuple(tuple(o.key for o in fs.outputs) for fs in declared))

    def _function(self, plan: _Plan) -> tuple[Any, list[np.ndarray]]:
        """The compiled block function of ``plan`` (composed once per structure and process) and its row buffers."""
        key = plan.key
        known = _COMPILED.get(key)
        if known is None:
            if not kernels.enabled():
                raise RuntimeError('the fused loop runs compiled only (acds_common.kernels.enable)')
            source = compose(plan)
            known = _COMPILED[key] = (_load(source), source)
        buffers = self._buffers.get(key)
        if buffers is None:
            buffers = self._buffers[key] = [np.zeros((BLOCK_STEPS, width(plan.produced[w].output.shape)))
                                            for w in plan.written]
        return known[0], buffers

    def source(self) -> list[str]:
        """The sources of the block functions this loop ran (for a reader and a failing test)."""
        return [_COMPILED[key][1] for key in self._buffers]

    # ---- after a block ------------------------------------------------------------------------------
    def _route(self, plan: _Plan, declared: list[FusedStage], buffers: list[np.ndarray], k0: int, n: int) -> None:
        """The n steps' outputs where the Python step program routes them (module docstring): the stores (the steps
        a later step reads), then the run observer: the steps stamped k0 + 1 … k0 + n − 1, which the block alone
        gives, as one block of rows (:meth:`~acds_runtime.summary.RunObserver.feed_block`: truth messages encoded
        from the rows, the summaries' block forms), and the values stamped k0 and k0 + n (the time owner's truth of
        step k0 came from the step before, its last one goes to the step after) one by one, as the step program
        feeds them. Without a block form (a topic the observer takes as rows that the loop does not give as the
        observer lays it out) every value goes one by one."""
        keep_from = max(0, n - self.max_lag - 1)
        columns = self._columns(plan, buffers, k0, n)
        lo, hi = (k0 + 1, k0 + n) if columns is not None else (k0, k0)  # stamps the block feeds: [lo, hi)
        edges: list[tuple[Route, int, Any]] = []  # (route, stamp, value) of the values fed one by one
        for key, buf in zip(plan.written, buffers, strict=True):
            p = plan.produced[key]
            route = p.route
            assert route is not None
            first = k0 + p.offset
            from_row = _from_row(p.output)
            if route.store is not None:
                for i in range(keep_from, n):
                    route.store[first + i] = from_row(buf[i].tolist())
            if route.per_step or route.truth is not None:
                rows = _outside(first, n, lo, hi)
                edges += [(route, first + i, from_row(row)) for i, row in zip(rows, buf[rows].tolist(), strict=True)]
        for name, fs in zip(plan.names, declared, strict=True):
            for key, obj in fs.held.items():
                route = self.routes[name].get(key)
                if route is None:
                    continue
                first = k0 + self._offsets[(name, key)]
                if route.store is not None:
                    for i in range(keep_from, n):
                        route.store[first + i] = obj
                edges += [(route, first + i, obj) for i in _outside(first, n, lo, hi)]
        # The truth digest takes each topic's messages in stamp order: the values before the block, the block, after.
        self._one_by_one([e for e in edges if e[1] < lo])
        if columns is not None:
            self._drain()
            if self._observer.next_step != lo:
                raise RuntimeError(f'the fused loop left step {self._observer.next_step} incomplete before its block')
            self._observer.feed_block(lo, hi - lo, columns)
        self._one_by_one([e for e in edges if e[1] >= hi])  # without a block (lo = hi = k0): every value from k0 on
        self._drain()

    def _one_by_one(self, edges: list[tuple[Route, int, Any]]) -> None:
        """Values (route, stamp, value) to the truth digest and the summaries' steps, as the step program feeds them."""
        dt, pending = self.dt_ns, self._pending
        for route, stamp, value in edges:
            if route.truth is not None:
                route.truth(route.codec.encode(stamp * dt, value))
            if route.per_step:
                step = pending.get(stamp)
                if step is None:
                    step = pending[stamp] = {}
                step[route.topic] = value

    def _columns(self, plan: _Plan, buffers: list[np.ndarray], k0: int, n: int) -> dict[str, np.ndarray] | None:
        """The rows of the steps stamped k0 + 1 … k0 + n − 1 per topic the observer takes as rows, or None when the
        block cannot be fed so (fewer than two steps, a topic missing, another layout or a stamp offset past 1)."""
        if n < 2:
            return None
        sources = self._block_sources.get(plan.key)
        if sources is None:
            sources = self._block_sources[plan.key] = self._block_plan(plan)
        if not sources:
            return None
        return {topic: buffers[b][1 - offset:n - offset] for topic, (b, offset) in sources.items()}

    def _block_plan(self, plan: _Plan) -> dict[str, tuple[int, int]]:
        """Per topic the observer takes as rows, (buffer index, stamp offset) of the output giving it; empty when
        one is not given so (module docstring)."""
        if self._observer.without_blocks:  # a summary module reads every step what a block does not carry
            return {}
        written = {plan.produced[key].route.topic: b for b, key in enumerate(plan.written)}  # type: ignore[union-attr]
        sources = {}
        for topic, layout in self._observer.block_topics.items():
            b = written.get(topic)
            if b is None:
                return {}
            p = plan.produced[plan.written[b]]
            if p.offset not in (0, 1) or not _same_rows(layout, p.output):
                return {}
            sources[topic] = (b, p.offset)
        return sources


def _outside(first: int, n: int, lo: int, hi: int) -> list[int]:
    """The rows i < n of values stamped ``first`` + i outside the stamps [lo, hi) a block feeds (its edges)."""
    return [*range(min(n, max(0, lo - first))), *range(max(0, hi - first), n)]


def _from_row(out: Output) -> Callable[[list[float]], Any]:
    """The stage's value of ``out`` from its row (a list of floats):  the floats in :func:`~acds_common.fused.leaves` order
    nested by the shape, then ``make``, written out once per output (this runs for every step of a block)."""
    fn = _FROM_ROW.get(out)
    if fn is None:
        counter = iter(range(width(out.shape)))

        def text(shape: Any) -> str:
            if isinstance(shape, int):
                return '(' + ''.join(f'r[{next(counter)}], ' for _ in range(shape)) + ')'
            return '(' + ''.join(text(s) + ', ' for s in shape) + ')'
        body = text(out.shape)
        fn = _FROM_ROW[out] = eval(f'lambda r: {body}' if out.make is None else f'lambda r: make({body})',  # noqa: S307
                                   {'make': out.make})
    return fn


#: :func:`_from_row` of each output declared so far.
_FROM_ROW: dict[Output, Callable[[list[float]], Any]] = {}


def _same_rows(layout: Any, out: Output) -> bool:
    """Whether the row ``layout`` of a topic (:class:`acds_common.cdr.RowLayout`) lays a value of ``out`` out as the
    kernel's row does (:func:`~acds_common.fused.leaves`): then its rows are the observer's.

    Known by what the answer depends on, the layout's width and ``flatten`` (one per message type, kept for the
    process) and ``out``: every codec has a layout object of its own, so a key by the object's ``id`` grew by ~20
    entries with every sample of a study and could meet a dead layout's ``id`` again."""
    key = (layout.width, layout.flatten, out)
    known = _SAME_ROWS.get(key)
    if known is None:
        n = width(out.shape)
        row = [float(i + 1) for i in range(n)]
        known = _SAME_ROWS[key] = layout.width == n and list(layout.flatten(_from_row(out)(row))) == row
    return known


#: :func:`_same_rows` by (layout width, layout flatten, output).
_SAME_ROWS: dict[tuple[int, Callable[[Any], tuple[float, ...]], Output], bool] = {}


@dataclass(frozen=True)
class _Plan:
    """A block function's structure: stage names and kernels, each kernel input's source (``args``: a register
    ``('reg', (topic, back))`` or an output of this step ``('new', (stage, index))``), the registers (topic →
    (shape, depth, producer's offset)) and their producers, the outputs written to buffers, every output produced,
    and each stage's output keys."""

    names: list[str]
    kernels: tuple[Callable[..., Any], ...]
    args: list[list[tuple[str, Any]]]
    registers: dict[str, tuple[Any, int, int]]
    register_producers: dict[str, tuple[int, int]]
    written: tuple[tuple[str, str], ...]
    produced: dict[tuple[str, str], _Produced]
    outputs: tuple[tuple[str, ...], ...]

    @cached_property
    def key(self) -> Any:
        """What the compiled function depends on (worked out once per plan)."""
        return (tuple(self.names), self.kernels, tuple(tuple(a) for a in self.args),
                tuple(sorted((t, repr(s), d, o) for t, (s, d, o) in self.registers.items())), self.written,
                self.outputs)


def compose(plan: _Plan) -> str:
    """The source of a module defining ``fused_block(k0, n_max, dt_ns, params0, state0, …, registers…, buffers…)``: steps
    k0, k0 + 1, … until a stage is not quiet or n_max steps ran; it returns (steps run, every stage's state). The
    kernels are imported by name (their modules' own, so numba's disk cache follows their sources,
    :mod:`acds_common.kernel_cache`)."""
    lines = ['"""The direct engine\'s fused loop for one graph (written by acds_runtime.fused_step.compose)."""', '']
    for i, kernel in enumerate(plan.kernels):
        lines.append(f'from {kernel.__module__} import {kernel.__qualname__} as K{i}')
    lines += ['', '']
    reg_names = {topic: [f'R{t}_{j}' for j in range(depth)] for t, (topic, (_s, depth, _o)) in
                 enumerate(plan.registers.items())}
    params = [f'P{i}' for i in range(len(plan.names))]
    states = [f'S{i}' for i in range(len(plan.names))]
    signature = ['k0', 'n_max', 'dt_ns'] + [x for pair in zip(params, states, strict=True) for x in pair]
    signature += [r for names in reg_names.values() for r in names]
    buffers = [f'B{i}' for i in range(len(plan.written))]
    signature += buffers
    lines += [f'def fused_block({", ".join(signature)}):', '    i = 0', '    while i < n_max:',
              '        k = k0 + i', '        t_s = k * dt_ns / 1e9']
    for i, name in enumerate(plan.names):
        inputs = []
        for how, what in plan.args[i]:
            if how == 'new':
                stage, index = what
                inputs.append(f'o{stage}[{2 + index}]')
            else:
                topic, back = what
                inputs.append(reg_names[topic][back])
        lines.append(f'        # {name}')
        lines.append(f'        o{i} = K{i}(P{i}, S{i}, k, t_s{"".join(", " + a for a in inputs)})')
        lines.append(f'        if not o{i}[0]:')
        lines.append('            break')
    lines.append('        # every stage quiet: step k is committed')
    for i in range(len(plan.names)):
        lines.append(f'        S{i} = o{i}[1]')
    for topic, names in reg_names.items():
        stage, index = plan.register_producers[topic]
        for j in range(len(names) - 1, 0, -1):
            lines.append(f'        {names[j]} = {names[j - 1]}')
        lines.append(f'        {names[0]} = o{stage}[{2 + index}]')
    for b, key in zip(buffers, plan.written, strict=True):
        p = plan.produced[key]
        for c, path in enumerate(leaves(p.output.shape)):
            lines.append(f'        {b}[i, {c}] = o{p.stage}[{2 + p.index}]{path}')
    lines.append('        i += 1')
    lines.append(f'    return i, {", ".join(states)}')
    return '\n'.join(lines) + '\n'


#: Where the composed modules are written (one file per source, named by its hash), so that numba caches their
#: machine code on disk as it caches the kernels': beside the source.
LOOP_DIR = Path(__file__).resolve().parent / '__pycache__' / 'fused_loops'


def _load(source: str, function: str = 'fused_block') -> Any:
    """``function`` of ``source`` compiled: from a module file written once per source (numba's disk cache then
    keeps its machine code across processes), or, where that folder cannot be written, from the source in memory
    (compiled in every process)."""
    from numba import njit

    name = 'fused_' + hashlib.sha256(source.encode()).hexdigest()[:24]
    path = LOOP_DIR / f'{name}.py'
    try:
        if not path.exists() or path.read_text() != source:
            LOOP_DIR.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(f'.{os.getpid()}.tmp')
            tmp.write_text(source)
            os.replace(tmp, path)
    except OSError:
        ns: dict[str, Any] = {}
        exec(compile(source, '<fused loop>', 'exec'), ns)  # noqa: S102 (our source)
        return njit(ns[function])
    module = sys.modules.get(name)
    if module is None:  # registered before it runs: numba's cached code names its module
        spec = importlib.util.spec_from_file_location(name, path)
        assert spec is not None and spec.loader is not None
        module = sys.modules[name] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    return njit(cache=True)(getattr(module, function))


def stage_costs(loop: FusedLoop, k: int, step: Callable[[int], None], repeats: int) -> dict[str, float]:
    """µs per call of each stage's compiled kernel, called ``repeats`` times in a compiled loop from its state at the
    start of step k with the inputs of step k (``step(k)`` runs step k through the step program, which gives them;
    each call takes the state the last quiet one left): the fused step's cost per model, for ``acds bench``.
    Empty when no block could start at step k."""
    declared = loop._declare(k)
    if declared is None:
        return {}
    plan = loop._plan(declared)
    step(k)
    costs = {}
    for i, (name, fs) in enumerate(zip(plan.names, declared, strict=True)):
        inputs = []
        for r in (r for key in fs.inputs for r in loop._reads[i] if r.key == key):
            shape = plan.produced[(r.source, r.output)].output.shape
            inputs.append(nested(loop._stores[r.topic][k - r.lag], shape))
        kernel = fs.kernel
        names = ''.join(f', I{j}' for j in range(len(inputs)))
        source = (f'from {kernel.__module__} import {kernel.__qualname__} as K\n\n\n'
                  f'def time_stage(P, S, k, t_s, n{names}):\n'
                  '    quiet = 0\n'
                  '    for _ in range(n):\n'
                  f'        o = K(P, S, k, t_s{names})\n'
                  '        if o[0]:\n'
                  '            S = o[1]\n'
                  '            quiet += 1\n'
                  '    return quiet, S\n')
        fn = _load(source, 'time_stage')
        t_s = k * loop.dt_ns / 1e9
        fn(fs.params, fs.state, k, t_s, 1, *inputs)
        t0 = time.perf_counter()
        fn(fs.params, fs.state, k, t_s, repeats, *inputs)
        costs[name] = (time.perf_counter() - t0) / repeats * 1e6
    return costs
