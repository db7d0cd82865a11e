"""The direct engine: every node's stepper in one process, no DDS, the same data bit for bit (spec §2).

Built from the same declaration as the per-process graph (:mod:`acds_common.graph`) and the
same parameters the launcher writes to ``params.yaml`` (:func:`~acds_common.parameters.node_parameters`):
the steppers are constructed exactly as the node processes construct them, and step k fires
every stage in :meth:`~acds_common.graph.Graph.firing_order` (each lag-0 input produced
before its consumer fires; the time owner closes the step), handing each stage the values its
inputs carry for step k − lag. Values never leave memory unless a bag is recorded; then each
message is encoded with the same codec the nodes publish with, so the bag holds the same bytes.
Without a bag or a live view, a node's periodic telemetry that no input and no summary reads is not
built at all (:attr:`~acds_common.stepper.Stepper.telemetry_wanted`).
The run summary is the same streaming :class:`~acds_runtime.summary.RunObserver` the run monitor
feeds, given values instead of bytes (and the bytes of the truth topics, for the digest).

Without a bag or a live view, when every stage of the graph declares a fused form (:mod:`acds_common.fused`), the
quiet steps run in blocks inside one compiled loop composed from those declarations
(:mod:`acds_runtime.fused_step`); every step that is not quiet (a transition, an event, a fault, a command, a
refused input, the run's end) runs through the step program above, so the data are the same bits either way.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from acds_common import kernels, topics
from acds_common.cdr import Codec
from acds_common.graph import Graph, build_graph
from acds_common.parameters import node_parameters, normalize
from acds_common.scenario import Scenario
from acds_common.stepper import Stepper, load_stepper

from .fused_step import BLOCK_STEPS, FusedLoop, stage_costs
from .launcher import LaunchError, RunResult
from .step_program import Input, Route, Stage, StepProgram, compile_step
from .summary import RunObserver


def build_steppers(graph: Graph, params: dict[str, dict[str, Any]],
                   log: Callable[[str, str, str], None] | None = None) -> dict[str, Stepper]:
    """Every node's stepper, constructed from its normalized parameters as its node process does."""
    out = {}
    for inst, spec in graph.nodes.items():
        node_log = None if log is None else (lambda level, text, n=inst: log(n, level, text))
        out[inst] = load_stepper(spec.stepper)(normalize(spec.name, params[inst]), log=node_log)
    return out


#: Steps between two prunings of the values no input reads any more (memory stays bounded either way).
PRUNE_EVERY = 64
#: After a step from which no block of fused steps could start, the engine tries again after 1, 2, 4, … steps,
#: at most this many (a run whose stages cannot fuse for a while pays little for asking).
FUSED_RETRY_MAX = 256


class DirectRun:
    """Run a scenario's graph in this process (the ``--engine direct`` of ``acds run``)."""

    def __init__(self, scenario: Scenario, *, steps: int | None = None, echo: Callable[[str], None] | None = None,
                 progress: Callable[[int, int, float], None] | None = None, record: Path | None = None,
                 record_storage: str = 'mcap', record_compression: str | None = None,
                 overrides: dict[str, dict[str, Any]] | None = None,
                 live: Callable[[dict[str, dict[str, Any]]], Any] | None = None, run_id: str | None = None,
                 fused: bool = True) -> None:
        self.scenario = scenario
        #: Whether the quiet steps may run in the fused loop (module docstring; False: every step in Python).
        self.fused = fused
        #: The fused loop of this run, once it runs (None: not used).
        self.fused_loop: FusedLoop | None = None
        #: The run folder's name, stored with the bag for the plots' titles (as the graph's launcher stores it).
        self.run_id = run_id
        self.steps = steps if steps is not None else scenario.total_steps()
        self.echo = echo or (lambda line: None)
        self.progress = progress
        self.record = Path(record) if record is not None else None
        self.record_storage = record_storage
        self.record_compression = record_compression
        if scenario.get('', 'external'):
            raise LaunchError(f'scenario {scenario.name} leaves {", ".join(scenario.get("", "external"))} to the user '
                              '(key external): an external node joins the process graph (acds run --engine graph)')
        self.params = node_parameters(scenario, self.steps, 0.0, overrides)
        self.graph = build_graph(self.params)
        self.observer = RunObserver(scenario, self.graph)
        self.dt_ns = round(scenario.control_period_s * 1e9)
        kernels.enable()  # the models' kernels compiled (acds_common.kernels: the same bits as the graph's)
        self.steppers = build_steppers(self.graph, self.params,
                                       lambda node, level, text: self.echo(f'[{node}] [{level.upper()}] {text}'))
        self._codecs = {(spec.instance, out.key): (spec.topic(out.topic), Codec(out.msg_type, out.frame_id,
                                                                                  out.child_frame_id), out)
                        for spec, out in self.graph.outputs()}
        self._clock = Codec(topics.TYPES[topics.CLOCK])
        # A store per per-step topic an input of the graph reads (the values its consumers take).
        read = {spec.topic(i.topic) for spec in self.graph.nodes.values() for st in spec.stages for i in st.inputs}
        self._store: dict[str, dict[int, Any]] = {topic: {} for topic, _codec, out in self._codecs.values()
                                                  if out.every_step and topic in read}
        # Per node and output key, where its values go (step_program.Route).
        self._routes: dict[str, dict[str, Route]] = {name: {} for name in self.graph.nodes}
        for (node, key), (topic, codec, out) in self._codecs.items():
            self._routes[node][key] = Route(self._store.get(topic), out.stamp_offset, out.many,
                                            self.observer.truth_sink(topic), self.observer.reads_per_step(topic),
                                            self.observer.event_sink(topic), topic, codec)
        self._max_lag = max((i.lag for spec in self.graph.nodes.values() for st in spec.stages for i in st.inputs),
                            default=0)
        self._writer: Any = None
        #: Every message is encoded (a bag is recorded or a live view fed): set when the run starts.
        self._bytes_out = False
        #: Live view (as for :class:`~acds_runtime.launcher.GraphRun`): fed (topic, CDR, value), closed after the run.
        self.live_sink = live(self.params) if live is not None else None

    def _publish(self, topic: str, codec: Codec, step: int, items: Any, truth: Any) -> None:
        """Recording or a live view: every message encoded, written, shown and observed."""
        live = self.live_sink
        t_ns = step * self.dt_ns
        for item in items:
            data = codec.encode(t_ns, item)
            if self._writer is not None:
                self._writer.write(topic, data)
            if live is not None:
                live(topic, data, item)
            if truth is not None:
                truth(data)
            self.observer.feed_value(topic, step, item)

    def _read(self, key: str, node: str) -> bool:
        """Whether anything takes ``node``'s output ``key`` in memory (an input's store, the run observer)."""
        route = self._routes[node].get(key)
        return route is not None and route.read()

    def _clock_tick(self, k: int) -> None:
        if self._writer is not None or self.live_sink is not None:
            data = self._clock.encode(k * self.dt_ns)
            if self._writer is not None:
                self._writer.write(topics.CLOCK, data)
            if self.live_sink is not None:
                self.live_sink(topics.CLOCK, data)

    def run(self) -> RunResult:
        """Run to completion (the time owner finishes); a stepper's StepError fails the run naming the node."""
        if self.record is not None:
            from .bag.writer import BagError, BagWriter, run_info
            try:
                self._writer = BagWriter(self.record, self.record_storage, run_info(self.scenario, self.steps,
                                                                                    self.params, run_id=self.run_id),
                                         compression=self.record_compression)
            except BagError as exc:
                raise LaunchError(str(exc)) from None
        self._bytes_out = self._writer is not None or self.live_sink is not None
        for name, stepper in self.steppers.items():  # periodic telemetry nobody reads is not built
            stepper.telemetry_wanted = self._bytes_out or self._read('diagnostics', name)
        t0 = time.monotonic()
        try:
            final = self._loop(t0)
        finally:
            for stepper in self.steppers.values():
                stepper.close()
            if self.live_sink is not None:
                self.live_sink.close()
            if self._writer is not None:
                for topic in sorted({t for t, _c, _o in self._codecs.values()}):
                    self._writer.note_publishers(topic, self.graph.publisher_of(topic))
                self._writer.close()
        wall = time.monotonic() - t0
        if self._writer is not None and self._writer.error:
            raise LaunchError(self._writer.error)
        return RunResult(self.scenario, final, wall, self.observer.summary(final, wall), bag=self.record)

    def _program(self) -> StepProgram:
        """The step of this graph written out (:mod:`~acds_runtime.step_program`): stages in firing order, each
        lag-0 input produced before its consumer fires, each lagged input None before its first step (each
        store holds None at the steps before 0 its readers look back to)."""
        present = set(self.graph.nodes)
        stages = []
        for name, stage in self.graph.firing_order():
            spec = self.graph.nodes[name]
            inputs = tuple(Input(inp.key, self._store.get(spec.topic(inp.topic), {}), inp.lag, spec.topic(inp.topic),
                                 inp.source) for inp in stage.inputs if inp.source in present)
            for inp in inputs:
                inp.store.update(dict.fromkeys(range(-inp.lag, 0)))
            stages.append(Stage(name, stage.name, getattr(self.steppers[name], stage.name),
                                tuple(inp.key for inp in stage.inputs if inp.source not in present), inputs))
        return compile_step(stages, self._routes, self.graph.time_owner, dt_ns=self.dt_ns,
                            pending=self.observer.pending, per_step_count=self.observer.per_step_count,
                            drain=self.observer.drain, publish=self._publish if self._bytes_out else None)

    def fused_stage_costs(self, at_step: int, repeats: int) -> dict[str, float]:
        """µs per step of each node's fused kernel (:func:`~acds_runtime.fused_step.stage_costs`) at step
        ``at_step`` of this run, reached through the step program (no bag, no live view); empty when the graph has
        no fused loop or no block could start there. For ``acds bench``."""
        for name, stepper in self.steppers.items():
            stepper.telemetry_wanted = self._read('diagnostics', name)
        loop = self._fused_loop()
        if loop is None:
            return {}
        program = self._program()
        program.initial(self.steppers[self.graph.time_owner].start())
        for k in range(at_step):
            program.step(k)
        try:
            return stage_costs(loop, at_step, program.step, repeats)
        finally:
            for stepper in self.steppers.values():
                stepper.close()

    def _fused_loop(self) -> FusedLoop | None:
        """The fused loop when this run may use it (no bag, no live view, every stage with a fused form)."""
        if not self.fused or self._bytes_out:
            return None
        loop = FusedLoop(self.graph, self.steppers, self._routes, self._store, self.observer, self.dt_ns,
                         self._max_lag)
        return loop if loop.possible else None

    def _loop(self, t0: float) -> int:
        owner = self.steppers[self.graph.time_owner]
        program = self._program()
        step, progress, steps, bytes_out = program.step, self.progress, self.steps, self._bytes_out
        buffers = list(self._store.values())
        flush_truth = self.observer.flush_truth
        fused = self.fused_loop = self._fused_loop()
        self._clock_tick(0)
        program.initial(owner.start())
        k = 0
        prune_at = PRUNE_EVERY
        retry_at, retry_wait = self._max_lag + 1, 1  # a block starts once every lagged input has a value
        while True:
            n = 0
            if fused is not None and k >= retry_at:
                n = fused.block(k)
                if n:
                    k += n
                    retry_at, retry_wait = k, 1
                else:
                    retry_at, retry_wait = k + retry_wait, min(2 * retry_wait, FUSED_RETRY_MAX)
            if n != BLOCK_STEPS:  # a full block goes on with the next one; else step k is the step program's
                step(k)
                if owner.finished:
                    return k
                k += 1
                if bytes_out:
                    self._clock_tick(k)
            if progress is not None:
                progress(k, steps, time.monotonic() - t0)
            if k >= prune_at:  # values no input can still read; the truth kept for the digest hashed
                prune_at = k + PRUNE_EVERY
                flush_truth()
                oldest = k - self._max_lag
                for buf in buffers:
                    for old in [s for s in buf if s < oldest]:
                        del buf[old]
