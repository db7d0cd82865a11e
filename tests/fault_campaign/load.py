"""Induced load for the fault campaign (issue 18): starve a process of CPU as a busy machine does.

``starved(pid)`` renices every thread of ``pid`` to 19 (threads it starts later inherit it from their creator)
and runs busy loops, one more than there are cores, until the block ends: the process then gets a sliver of
the CPU while everything else runs — the launcher's run monitor falls behind the graph it watches.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path


def renice_threads(pid: int, niceness: int = 19) -> int:
    """Set the niceness of every thread of ``pid`` (Linux schedules threads, so ``renice -p`` alone misses them)."""
    count = 0
    for task in Path(f'/proc/{pid}/task').iterdir():
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.setpriority(os.PRIO_PROCESS, int(task.name), niceness)
            count += 1
    return count


@contextlib.contextmanager
def busy_loops(n: int | None = None) -> Iterator[list[subprocess.Popen[bytes]]]:
    """``n`` processes spinning at full speed (default: cores + 1) for the duration of the block."""
    n = (os.cpu_count() or 2) + 1 if n is None else n
    procs = [subprocess.Popen([sys.executable, '-c', 'while True: pass'], stdin=subprocess.DEVNULL)
             for _ in range(n)]
    try:
        yield procs
    finally:
        for p in procs:
            p.kill()
        for p in procs:
            p.wait()


@contextlib.contextmanager
def starved(pid: int, loops: int | None = None) -> Iterator[None]:
    """Renice ``pid``'s threads to 19 and spin ``loops`` busy processes while the block runs."""
    renice_threads(pid)
    with busy_loops(loops):
        yield
