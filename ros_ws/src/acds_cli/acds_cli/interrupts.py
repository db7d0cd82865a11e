"""A stop signal that arrived inside a C extension: find it under the error the extension wrapped it in.

Python runs a signal handler between bytecodes, so the handler's exception (Ctrl-C's KeyboardInterrupt, the
CLI's SIGTERM/SIGHUP stop) can be raised inside Python code that a C extension called back into. numba
loading a compiled kernel from its cache is such a case: its unpickler's exception comes out as
``SystemError: ... returned a result with an exception set``, the stop as its ``__cause__`` (seen by CI: a
study sent SIGHUP while its first fused block loaded exited 1 with a traceback instead of 129).
"""

from __future__ import annotations


def interruption(exc: BaseException, kinds: tuple[type[BaseException], ...] = (KeyboardInterrupt,)) -> BaseException | None:
    """The first exception of ``kinds`` in ``exc``'s chain (``exc`` itself, then its causes and contexts), else None."""
    seen: set[int] = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, kinds):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None
