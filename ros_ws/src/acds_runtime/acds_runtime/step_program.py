"""The direct engine's step for one graph, written out as Python and compiled once per run (issue 24).

A generic loop pays, every step, for what does not change during a run: which inputs a stage takes
from which store at which lag, which of a stage's outputs anything reads, and where each goes (its
consumers' store, the truth digest, the summaries' pending steps, their events, a bag or live view).
:func:`compile_step` writes that out for the graph at hand — one statement per input and per route
of an output — and compiles it once (as :func:`collections.namedtuple` and :mod:`dataclasses` build
their methods), so a step is a straight run of the stage calls and dictionary stores. The source is
kept (:attr:`StepProgram.source`) for a reader and for a failing test.

The errors are the generic loop's: a missing input names its producer, topic, step and consumer; a
stepper's exception names its node, stage and step; an output the node does not declare names both.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from acds_common.stepper import StepError

from .launcher import LaunchError


@dataclass(frozen=True)
class Input:
    """One input of a stage whose source runs: its key, the store of its topic, its lag, topic and source."""

    key: str
    store: dict[int, Any]
    lag: int
    topic: str
    source: str


@dataclass(frozen=True)
class Stage:
    """One stage in firing order: its node, name, bound method, the keys of inputs whose source is absent
    (always None) and the inputs whose source runs."""

    node: str
    name: str
    method: Callable[[int, float, dict[str, Any]], dict[str, Any]]
    absent: tuple[str, ...]
    inputs: tuple[Input, ...]


@dataclass(frozen=True)
class Route:
    """Where one output of a node goes: its consumers' store (or None), its stamp offset, whether it is a
    list of messages (``many``), the observer's sink of its bytes (truth) or None, whether the summaries
    read it per step, the observer's event sink or None, topic, codec."""

    store: dict[int, Any] | None
    offset: int
    many: bool
    truth: Callable[[bytes], None] | None
    per_step: bool
    event: Callable[[str, Any], None] | None
    topic: str
    codec: Any

    def read(self) -> bool:
        """Whether anything takes the value in memory (a store, the observer)."""
        return self.store is not None or self.truth is not None or self.per_step or self.event is not None


@dataclass
class StepProgram:
    """The compiled step: ``step(k)`` fires every stage of step k; ``initial(outputs)`` routes the time
    owner's ``start()`` (its values of step 0); ``source`` the Python both were compiled from."""

    step: Callable[[int], None]
    initial: Callable[[dict[str, Any]], None]
    source: str


def _missing(stage: Stage, k: int) -> LaunchError:
    """The first input of ``stage`` at step k its producer has not given (a node that produced nothing): the
    compiled step calls this on the KeyError of an input's store, so there is one."""
    inp = next(inp for inp in stage.inputs if k - inp.lag not in inp.store)
    return LaunchError(f'node {inp.source} produced no {inp.topic} for step {k - inp.lag} '
                       f'({stage.node}.{stage.name} needs it)')


def _failed(stage: Stage, k: int, exc: Exception) -> LaunchError:
    """A stepper's exception as a node process reports it: one line naming the node, stage and step."""
    if isinstance(exc, StepError):
        return LaunchError(f'node {stage.node} failed at step {k}: {exc}')
    return LaunchError(f'node {stage.node} failed: stage {stage.name} raised {type(exc).__name__} at step {k}: {exc}')


def _undeclared(node: str, outputs: dict[str, Any], declared: frozenset[str]) -> LaunchError:
    key = next(key for key in outputs if key not in declared)
    return LaunchError(f'{node}: stepper returned undeclared output {key!r}')


class _Writer:
    """Source lines and the objects they name (``ns``)."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.ns: dict[str, Any] = {'NA': object(), 'LaunchError': LaunchError, '_missing': _missing,
                                   '_failed': _failed, '_undeclared': _undeclared}
        self._names: dict[int, str] = {}

    def name(self, prefix: str, obj: Any) -> str:
        """A name for ``obj`` in the compiled code (one per object)."""
        known = self._names.get(id(obj))
        if known is None:
            known = self._names[id(obj)] = f'{prefix}{len(self._names)}'
            self.ns[known] = obj
        return known

    def add(self, indent: int, line: str) -> None:
        self.lines.append('    ' * indent + line)


def _route_lines(w: _Writer, indent: int, route: Route, value: str, step: str, publish: Callable[..., None] | None
                 ) -> None:
    """Statements handing ``value`` (an output of step ``step``) to everything that takes it."""
    if route.store is not None:
        w.add(indent, f'{w.name("S", route.store)}[{step}] = {value}')
    if publish is not None:  # a bag or live view: every message encoded, written, observed (DirectRun._publish)
        items = value if route.many else f'({value},)'
        w.add(indent, f'{w.name("PUB", publish)}({route.topic!r}, {w.name("C", route.codec)}, {step}, {items}, '
                      f'{w.name("T", route.truth) if route.truth is not None else None})')
        return
    if route.many:
        if route.event is not None:
            w.add(indent, f'for item in {value}:')
            w.add(indent + 1, f'{w.name("EV", route.event)}({route.topic!r}, item)')
        return
    if route.truth is not None:
        w.add(indent, f'{w.name("T", route.truth)}({w.name("E", route.codec.encode)}({step} * DT, {value}))')
    if route.per_step:  # RunObserver.feed_value without the call: the step goes once its values are all there
        w.add(indent, f'values = PENDING.get({step})')
        w.add(indent, 'if values is None:')
        w.add(indent + 1, f'values = PENDING[{step}] = {{}}')
        w.add(indent, f'values[{route.topic!r}] = {value}')
        w.add(indent, 'if len(values) >= COUNT:')
        w.add(indent + 1, 'DRAIN()')
    elif route.event is not None:
        w.add(indent, f'{w.name("EV", route.event)}({route.topic!r}, {value})')


def _emit_lines(w: _Writer, indent: int, node: str, routes: dict[str, Route], step_of: Callable[[Route], str],
                publish: Callable[..., None] | None) -> None:
    """Statements routing the outputs ``o`` of ``node``: each declared output it returned, to where it goes."""
    declared = frozenset(routes)
    w.add(indent, f'if not o.keys() <= {w.name("D", declared)}:')
    w.add(indent + 1, f'raise _undeclared({node!r}, o, {w.name("D", declared)})')
    for key, route in routes.items():
        if publish is None and not route.read():
            continue
        w.add(indent, f'v = o.get({key!r}, NA)')
        w.add(indent, 'if v is not NA:')
        _route_lines(w, indent + 1, route, 'v', step_of(route), publish)


def compile_step(stages: list[Stage], routes: dict[str, dict[str, Route]], owner: str, *, dt_ns: int,
                 pending: dict[int, dict[str, Any]], per_step_count: int, drain: Callable[[], None],
                 publish: Callable[..., None] | None) -> StepProgram:
    """Write out and compile the step of this graph (module docstring). ``publish``: the engine's writer of
    every message when a bag is recorded or a live view fed, else None (only what is read is routed)."""
    w = _Writer()
    w.ns.update({'DT': dt_ns, 'PENDING': pending, 'COUNT': per_step_count, 'DRAIN': drain})
    offsets = sorted({r.offset for node in routes.values() for r in node.values()})
    w.add(0, 'def step(k):')
    w.add(1, 't_s = k * DT / 1e9')
    for offset in offsets:
        if offset:
            w.add(1, f'k{offset} = k + {offset}')
    for stage in stages:
        st = w.name('STAGE', stage)
        w.add(1, f'# {stage.node}.{stage.name}')
        items = [f'{key!r}: None' for key in stage.absent]
        items += [f'{inp.key!r}: {w.name("S", inp.store)}[k{f" - {inp.lag}" if inp.lag else ""}]'
                  for inp in stage.inputs]
        w.add(1, 'try:')
        w.add(2, f'i = {{{", ".join(items)}}}')
        w.add(1, 'except KeyError:')
        w.add(2, f'raise _missing({st}, k) from None')
        w.add(1, 'try:')
        w.add(2, f'o = {w.name("M", stage.method)}(k, t_s, i)')
        w.add(1, 'except Exception as exc:')
        w.add(2, f'raise _failed({st}, k, exc) from None')
        _emit_lines(w, 1, stage.node, routes[stage.node], lambda r: f'k{r.offset}' if r.offset else 'k', publish)
    w.add(0, '')
    w.add(0, 'def initial(o):')  # the time owner's start(): its values of step 0
    _emit_lines(w, 1, owner, routes[owner], lambda _r: '0', publish)
    source = '\n'.join(w.lines) + '\n'
    exec(_compiled(source, f'<direct engine step: {len(stages)} stages>'), w.ns)  # noqa: S102 (our source)
    return StepProgram(w.ns['step'], w.ns['initial'], source)


@functools.lru_cache(maxsize=8)
def _compiled(source: str, name: str) -> Any:
    """The code of a step's source, remembered: the samples of a study write the same source (their objects are
    bound by name in each run's own namespace), and compiling it is ~2 ms a run."""
    return compile(source, name, 'exec')
