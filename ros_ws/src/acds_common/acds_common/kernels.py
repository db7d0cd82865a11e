"""Compiled model kernels for the direct engine: the same Python source, the same bits (issue 24).

A model's innermost loop (the attitude RK4 step, a coil's event-driven period) is written once, as
a plain function of floats; a helper it calls is marked :func:`helper`.
A model resolves its kernels once, when it is built, through :func:`compiled`: the plain function in
a node process (the per-process graph starts its six processes without a compiler), the function
compiled by numba's ``njit`` in a process that called :func:`enable` first (the direct engine, hence
every Monte Carlo worker). The compiled kernel keeps IEEE double semantics: numba compiles without
``fastmath`` (no reassociation, no fused multiply-add contraction), ``math.exp``/``log``/``sqrt`` call
the same C library the interpreter calls, so the same operations in the same order give the same bits.
That is checked, not assumed: ``tests/test_kernels.py`` compares every kernel compiled against plain on
random and edge inputs bit for bit, the engines test compares the direct engine (compiled) with the
per-process graph (plain) message for message, and every shipped scenario keeps its recorded truth
digest on the direct engine.

Write a kernel on floats, tuples of floats, ints and bools only; a debugging hook or recorder may be
an argument that is ``None`` on the compiled path (numba prunes the ``is not None`` branches) and is
set only when the caller runs the plain function.
Compiled code is cached on disk next to the source (numba ``cache=True``), so a process pays the
compiler once per machine, then a ~0.1 s load per kernel.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

F = TypeVar('F', bound=Callable[..., Any])

#: Helpers compiled kernels call (registered with numba when compilation is enabled).
_HELPERS: list[Callable[..., Any]] = []
#: Compiled form of each kernel, once compilation is enabled.
_COMPILED: dict[Callable[..., Any], Callable[..., Any]] = {}
_enabled = False


def helper(fn: F) -> F:
    """Mark a plain function a compiled kernel may call (it stays a plain function for Python callers)."""
    _HELPERS.append(fn)
    if _enabled:
        _register(fn)
    return fn


def _register(fn: Callable[..., Any]) -> None:
    from numba.extending import register_jitable

    register_jitable(fn)


def enable() -> None:
    """Compile kernels in this process from now on (models built afterwards use the compiled forms)."""
    global _enabled
    if _enabled:
        return
    for fn in _HELPERS:
        _register(fn)
    _enabled = True


def compiled(fn: F) -> F:
    """The form of kernel ``fn`` this process runs: compiled once :func:`enable` was called, else ``fn``."""
    if not _enabled:
        return fn
    out = _COMPILED.get(fn)
    if out is None:
        from numba import njit

        out = _COMPILED[fn] = njit(cache=True)(fn)
    return out  # type: ignore[return-value]
