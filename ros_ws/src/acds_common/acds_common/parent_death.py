"""A child process that dies with the process that started it (Linux ``prctl(PR_SET_PDEATHSIG, SIGKILL)``).

The kernel SIGKILLs the child the moment the thread that started it ends: it acts even on a child that is stopped,
hung or holding the interpreter lock, so a killed launcher, study or Dask worker leaves no orphan behind (node
processes, a user's flight software, a study's drawing processes). One definition for all of them.
"""

from __future__ import annotations

import ctypes
import functools
import os
import signal
from collections.abc import Callable

#: ``prctl`` option: the signal a process gets when its parent dies.
PR_SET_PDEATHSIG = 1


def kill_on_parent_death() -> Callable[[], int]:
    """The call that asks the kernel to SIGKILL the calling process when its parent dies, resolved now: safe to run
    in a child between fork and exec (``subprocess.Popen(preexec_fn=...)``), where looking up libc is not."""
    return functools.partial(ctypes.CDLL(None, use_errno=True).prctl, PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)


def die_with(parent_pid: int) -> bool:
    """Ask to be SIGKILLed when the parent dies; False when parent ``parent_pid`` is gone already (checked after
    the call, which covers a parent that died before it)."""
    kill_on_parent_death()()
    return os.getppid() == parent_pid
