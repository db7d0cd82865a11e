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
compiler once per machine, then a ~0.1 s load per kernel; a kernel's cache entry is stamped with its own source
and the sources of the helpers it calls (:mod:`acds_common.kernel_cache`), so editing a helper recompiles it.

A model's per-step call resolves through :func:`bound`, not :func:`compiled`: numba's dispatcher types every
argument on every call (``typeof``, nested tuples walked leaf by leaf) to pick a specialization, 0.4-1.5 µs a call
at the direct engine's call sites, while a model calls its kernel with the same types every step. :func:`bound`
compiles the kernel for the ONE signature of example arguments the model gives when it is built and returns that
specialization's entry point, which only unboxes. The entry point does not check what it unboxes (numba converts,
it does not refuse: an int for a float is converted, a float for an int is truncated, an array's dtype is checked
by its item size only), so a model binds a kernel only where the argument types are fixed by construction at the
call site (each call site says why); ``ACDS_KERNEL_CHECK=1`` in the environment (the test suite sets it) makes
every bound call check its arguments' numba types against the bound signature and refuse (TypeError) any other
(a walk of the arguments' Python types, :func:`_shape`, numba's typing only when that differs: the check costs a
direct run 1.7x, not the 7x of typing every call).
"""

from __future__ import annotations

import os
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


def registered_helpers() -> tuple[Callable[..., Any], ...]:
    """The helpers marked so far (:func:`helper`)."""
    return tuple(_HELPERS)


def enable() -> None:
    """Compile kernels in this process from now on (models built afterwards use the compiled forms). The disk
    cache is stamped with the files of the helpers each kernel calls too (:mod:`acds_common.kernel_cache`),
    unless the user chose numba's cache locators (``NUMBA_CACHE_LOCATOR_CLASSES``)."""
    global _enabled
    if _enabled:
        return
    if not os.environ.get('NUMBA_CACHE_LOCATOR_CLASSES'):
        from numba.core import config

        from .kernel_cache import LOCATORS
        # The environment too: numba re-reads its configuration when its variables change.
        config.CACHE_LOCATOR_CLASSES = os.environ['NUMBA_CACHE_LOCATOR_CLASSES'] = LOCATORS
    for fn in _HELPERS:
        _register(fn)
    _enabled = True


def enabled() -> bool:
    """Whether this process compiles its kernels (:func:`enable` was called)."""
    return _enabled


def compiled(fn: F) -> F:
    """The form of kernel ``fn`` this process runs: compiled once :func:`enable` was called, else ``fn``."""
    if not _enabled:
        return fn
    out = _COMPILED.get(fn)
    if out is None:
        from numba import njit

        out = _COMPILED[fn] = njit(cache=True)(fn)
    return out  # type: ignore[return-value]


def checking() -> bool:
    """True when bound kernels check their arguments' types on every call (``ACDS_KERNEL_CHECK=1``, the tests)."""
    return os.environ.get('ACDS_KERNEL_CHECK', '') not in ('', '0')


_INT64 = (-(2 ** 63), 2 ** 63)


def _shape(value: Any) -> Any:
    """The Python-level type of a kernel argument, fine enough that two values of one shape have one numba type:
    float (float64), bool (boolean), None, an int within int64 (int64), a tuple (the shapes of its items: UniTuple
    or Tuple of their types) and an ndarray by dtype, dimensions, contiguity (numba's layout C, F or A), writability
    (readonly) and alignment; anything else (a numpy scalar, an int past int64, a subclass) is undescribed, and the
    checked call types it with numba."""
    t = type(value)
    if t is float or t is bool or value is None:
        return t
    if t is tuple:
        return tuple(_shape(v) for v in value)
    if t is int:
        return t if _INT64[0] <= value < _INT64[1] else object()
    if t.__name__ == 'ndarray' and t.__module__ == 'numpy':
        f = value.flags
        return t, value.dtype.str, value.ndim, f.c_contiguous, f.f_contiguous, f.writeable, f.aligned
    return object()  # equal to nothing else (tuples compare items by identity first): numba types the call


#: The numba types of each kernel's bound arguments by their :func:`_shape` (one shape, one numba type): a process
#: binds the same kernels to arguments of the same shapes for every sample of a study, and numba's ``typeof`` of
#: each argument is most of a binding's cost.
_SIGNATURES: dict[tuple[Any, Any], tuple[Any, ...]] = {}


def _described(shape: Any) -> bool:
    """Whether every part of a :func:`_shape` is described (an undescribed value's shape equals nothing)."""
    if type(shape) is tuple:
        return all(_described(s) for s in shape)
    return type(shape) is not object


def bound(fn: F, *example: Any) -> F:
    """Kernel ``fn`` for the one signature of the ``example`` arguments: ``fn`` itself in a plain process, else
    the entry point of its compiled specialization for the numba types of ``example`` (compiled, or loaded from
    the disk cache, now), which skips the dispatcher's per-call typing of every argument.

    Call it only with arguments of exactly the example's types (tuples of the same lengths, floats where floats,
    ints where ints, the same array dtype, dimensions and layout): the caller guarantees this by construction and
    says where. With :func:`checking` on, the returned callable checks each call's types against the signature
    and raises ``TypeError`` on any other (it never runs a specialization on arguments of another type).
    """
    if not _enabled:
        return fn
    from numba import typeof

    dispatcher: Any = compiled(fn)
    shape = _shape(example)
    signature = _SIGNATURES.get((fn, shape)) if _described(shape) else None
    if signature is None:
        signature = tuple(typeof(a) for a in example)
        if _described(shape):
            _SIGNATURES[(fn, shape)] = signature
    overload = dispatcher.overloads.get(signature)
    if overload is None:
        dispatcher.compile(signature)
        overload = dispatcher.overloads[signature]
    entry = overload.entry_point
    if not checking():
        return entry  # type: ignore[no-any-return]

    def checked(*args: Any) -> Any:
        if _shape(args) != shape:  # else the same numba types (_shape); numba's own typing otherwise
            got = tuple(typeof(a) for a in args)
            if got != signature:
                wrong = [f'argument {i}: {g} (bound: {w})'
                         for i, (g, w) in enumerate(zip(got, signature, strict=False)) if g != w]
                raise TypeError(f'{fn.__name__} is bound to {len(signature)} arguments of fixed types, called with '
                                f'{len(got)}: {"; ".join(wrong) or "another count"}')
        return entry(*args)

    checked.signature = signature  # type: ignore[attr-defined]
    checked.py_func = fn  # type: ignore[attr-defined]
    return checked  # type: ignore[return-value]
