"""Where a graph run's time goes: cProfile of each node process and of the run monitor's thread, on request.

With :data:`PROFILE_ENV` set to a folder, every node process (:func:`acds_common.lockstep.run_node`) and the
launcher's run monitor (:class:`acds_runtime.monitor.RunMonitor`) profile their spinning loop and write
``<folder>/<name>.prof`` (``pstats`` format) as they leave; unset (the default), nothing is profiled. The clock is the
profiled thread's CPU time (``time.thread_time``): waiting costs nothing, and the middleware's own threads (its
transport's receive threads) are the process's CPU time less the profile's total.
``docs/measurements.md`` gives the figures measured this way.
"""

from __future__ import annotations

import cProfile
import os
import re
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

#: Environment variable naming the folder the profiles go to (unset: no profiling).
PROFILE_ENV = 'ACDS_PROFILE_DIR'


@contextmanager
def profiled(name: str) -> Iterator[None]:
    """Profile the body (this thread only) into ``<$ACDS_PROFILE_DIR>/<name>.prof``; nothing when it is unset."""
    folder = os.environ.get(PROFILE_ENV)
    if not folder:
        yield
        return
    profile = cProfile.Profile(time.thread_time)
    profile.enable()
    try:
        yield
    finally:
        profile.disable()
        Path(folder).mkdir(parents=True, exist_ok=True)
        profile.dump_stats(Path(folder) / f'{re.sub(r"[^A-Za-z0-9_.-]", "_", name)}.prof')


def profiling(name: str, body: Callable[[], None]) -> Callable[[], None]:
    """``body`` run under :func:`profiled` (a thread's target)."""
    def run() -> None:
        with profiled(name):
            body()
    return run
