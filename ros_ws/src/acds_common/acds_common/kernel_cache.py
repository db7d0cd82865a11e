"""numba's disk cache of the compiled kernels, kept fresh when a helper they call changes (issue 24).

numba's ``cache=True`` stamps a compiled kernel with the content of the kernel's own source file only. A kernel
that calls a :func:`~acds_common.kernels.helper` defined in another file (``vec3.mv``, the magnetic laws, the
environment's orbit) kept its cached machine code after that helper's file changed: the direct engine then ran
the old helper while the per-process graph ran the new one, and the truth digests could pass on stale code (seen:
a reordered ``bxh_moment_xyz`` left the recorded digest unchanged until the cache was deleted).

The locators here stamp a kernel with its own file AND the files of every helper it reaches (its code's global
and attribute names that resolve to registered helpers, then theirs, transitively): a changed helper file misses
the cache and the kernel is compiled again. The set is the kernel's own, so processes that imported different
modules agree on it (a process-wide set would rewrite the cache back and forth). :func:`acds_common.kernels.enable`
installs them through numba's ``NUMBA_CACHE_LOCATOR_CLASSES`` (unless the user set that variable); this module
imports numba and is imported by numba only in a process that compiles.
"""

from __future__ import annotations

import functools
import hashlib
import os
from collections.abc import Callable, Iterator
from types import CodeType, ModuleType
from typing import Any

from numba.core.caching import InTreeCacheLocator, UserProvidedCacheLocator

from . import kernels

#: What :func:`acds_common.kernels.enable` puts in ``NUMBA_CACHE_LOCATOR_CLASSES``: a user-provided cache
#: directory (``NUMBA_CACHE_DIR``) first, as numba orders them, then ``__pycache__`` beside the source, then
#: numba's own fall-back for a read-only tree.
LOCATORS = f'{__name__}.UserDirLocator,{__name__}.InTreeLocator,UserWideCacheLocator'


@functools.cache
def _content_hash(path: str, _mtime_ns: int, _size: int) -> str:
    """SHA-256 of a file's bytes (memoized per path, modification time and size, as numba memoizes its own)."""
    with open(path, 'rb') as fh:
        return hashlib.file_digest(fh, 'sha256').hexdigest()


def _codes(code: CodeType) -> Iterator[CodeType]:
    """A code object and the ones nested in it (comprehensions, inner functions)."""
    yield code
    for const in code.co_consts:
        if isinstance(const, CodeType):
            yield from _codes(const)


def reached_helpers(fn: Callable[..., Any]) -> list[Callable[..., Any]]:
    """The registered helpers ``fn`` calls, directly or through other helpers: each global name of its code that
    is a helper, and each attribute name of its code that is a helper of a module it names (``vec3.mv``)."""
    helpers = {id(h) for h in kernels.registered_helpers()}  # by identity: a global may be unhashable
    seen: dict[int, Callable[..., Any]] = {}
    stack = [fn]
    while stack:
        f = stack.pop()
        names = {name for code in _codes(f.__code__) for name in code.co_names}
        modules = [obj for name in names if isinstance(obj := f.__globals__.get(name), ModuleType)]
        candidates = [f.__globals__.get(name) for name in names]
        candidates += [getattr(m, name, None) for m in modules for name in names]
        for c in candidates:
            if id(c) in helpers and id(c) not in seen:
                seen[id(c)] = c
                stack.append(c)
    return list(seen.values())


class _HelperStamped:
    """A numba source-file locator whose stamp also covers the files of the helpers the kernel reaches."""

    def __init__(self, py_func: Callable[..., Any], py_file: str) -> None:
        super().__init__(py_func, py_file)  # type: ignore[call-arg]
        self._helper_files = sorted({os.path.abspath(h.__code__.co_filename) for h in reached_helpers(py_func)}
                                    - {os.path.abspath(py_file)})

    def get_source_stamp(self) -> Any:
        stamps = []
        for path in self._helper_files:
            st = os.stat(path)
            stamps.append((path, _content_hash(path, st.st_mtime_ns, st.st_size)))
        return super().get_source_stamp(), tuple(stamps)  # type: ignore[misc]


class UserDirLocator(_HelperStamped, UserProvidedCacheLocator):
    """numba's ``NUMBA_CACHE_DIR`` locator, stamped with the helpers' files too."""


class InTreeLocator(_HelperStamped, InTreeCacheLocator):
    """numba's ``__pycache__`` locator, stamped with the helpers' files too."""
