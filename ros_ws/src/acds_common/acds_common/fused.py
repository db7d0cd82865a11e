"""A stage's fused form: the declaration a stepper gives for the direct engine's fused loop (spec §2).

The direct engine can run the quiet steps of a run — no transition, event, fault, command, refused
input or telemetry — inside one compiled loop (:mod:`acds_runtime.fused_step` composes it). A stepper
takes part by answering ``fused(stage, held)`` for each of its stages with a :class:`FusedStage`, or
``None`` when it cannot run fused from its present state (a variant or feature the kernel does not cover,
a fault or command pending, telemetry wanted, noise drawn in Python…): the engine then runs the step
through the stepper's Python method as always.

The kernel is a plain function written as :mod:`acds_common.kernels` asks (floats, ints, bools, tuples,
float64 arrays; a :func:`~acds_common.kernels.helper`: the composed loop calls it compiled, without
``fastmath``)::

    kernel(params, state, k, t_s, *inputs) -> (quiet, state, *outputs)

``inputs`` are the values of the declared input keys at step k as nested float tuples (:func:`nested`:
an output's value flattened by its :data:`Shape`), ``outputs`` the declared outputs in the same form.
``quiet`` True promises that the outputs and the new state are exactly what the Python stage returns and
leaves at this step; False says the step is not quiet (a transition, an event, a rejected input, a
refusal, the run's end): the loop then stops before step k, every stage's state is the one at the start
of step k (a kernel never changes its ``state`` argument in place in a step it calls not quiet), and the
engine runs step k through the Python steppers, which make the events, logs and errors as ever.
``restore(state)`` writes a kernel state back into the stepper (after every block of fused steps).

Inputs the kernel does not take (``held``: the mode report, a tuple of ``Status``) stay Python values:
``fused`` is given the value each will have at every step of the block (the producer returns the same
object at every quiet step, :attr:`FusedStage.held`), and answers ``None`` when that value asks for work
(a forwarded command). Inputs from a source absent from the graph are not passed: the stepper knows
them (its Python method reads them as None).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

#: How an output's value is laid out as floats: an int n is a tuple of n floats, a tuple of shapes a tuple
#: of their values (``(3, 9)``: a vector and a 3×3 covariance; ``3``: a vector).
Shape = int | tuple['Shape', ...]


@dataclass(frozen=True)
class Output:
    """A kernel output: its key, its :data:`Shape`, and ``make`` the stage's value from the nested tuple
    (None: the nested tuple is the value)."""

    key: str
    shape: Shape
    make: Callable[[tuple], Any] | None = None

    def value(self, nested_value: tuple) -> Any:
        """The value the Python stage returns, from the kernel's nested tuple."""
        return nested_value if self.make is None else self.make(nested_value)


@dataclass(frozen=True)
class FusedStage:
    """One stage's fused form (module docstring): ``kernel`` (a plain function, :mod:`acds_common.kernels`),
    its ``params`` and ``state`` (tuples; float64 arrays allowed), the input keys it takes in order, its
    :class:`Output` s in order, ``restore`` (a kernel state → the stepper), and ``held``: the outputs returned
    as the same Python object at every quiet step."""

    kernel: Callable[..., tuple]
    params: tuple
    state: tuple
    inputs: tuple[str, ...]
    outputs: tuple[Output, ...]
    restore: Callable[[Any], None]
    held: Mapping[str, Any] = field(default_factory=dict)


def width(shape: Shape) -> int:
    """How many floats a value of ``shape`` holds."""
    return shape if isinstance(shape, int) else sum(width(s) for s in shape)


def leaves(shape: Shape, prefix: str = '') -> list[str]:
    """The index paths (``[0][2]``…) of a value of ``shape``'s floats, in row order (depth first)."""
    if isinstance(shape, int):
        return [f'{prefix}[{i}]' for i in range(shape)]
    return [p for i, s in enumerate(shape) for p in leaves(s, f'{prefix}[{i}]')]


def nested(value: Any, shape: Shape) -> tuple:
    """``value`` (a stage's output: tuples, named tuples, floats) as plain nested tuples of floats by ``shape``."""
    if isinstance(shape, int):
        return tuple(float(x) for x in value)
    return tuple(nested(v, s) for v, s in zip(value, shape, strict=True))
