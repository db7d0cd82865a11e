"""The "being recorded" marker of a bag folder: a lock file its writer holds with ``flock`` for the recording's life.

:class:`RecordingLock` is taken by the writer right after it creates the bag
folder, before the storage file exists, and released (the file removed) after
``metadata.yaml`` and the sidecar are written. The kernel drops an ``flock``
when its holder dies, so a killed recorder leaves at most a stale file, and the
test is whether the lock is *held*, never whether the file exists:

- no ``metadata.yaml`` and the lock held: the bag is being recorded;
- no ``metadata.yaml`` and the lock free (or no lock file): the bag is unclosed
  (its recorder died), readable up to what reached the disk.

The lock's descriptor is not inherited by child processes (PEP 446), so a node
process started by the recording launcher never keeps a dead launcher's bag
"being recorded". Readers only open the file read-only and try a shared lock
without blocking: they never create, change or remove anything.
"""

from __future__ import annotations

import fcntl
import os
import time
from pathlib import Path

#: The lock file in a bag folder while its writer is alive.
LOCK_FILE = 'acds_recording.lock'


class RecordingLock:
    """An exclusive ``flock`` on ``FOLDER/acds_recording.lock``, held until :meth:`release`."""

    def __init__(self, folder: Path) -> None:
        """Create the lock file in ``folder`` (which must not hold one) and lock it; raise OSError otherwise."""
        self.path = Path(folder) / LOCK_FILE
        self._fd: int | None = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        try:
            fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            os.write(self._fd, f'pid {os.getpid()} recording since {time.strftime("%Y-%m-%d %H:%M:%S")}\n'.encode())
        except OSError:
            self.release()
            raise

    def release(self) -> None:
        """Remove the lock file and drop the lock (idempotent)."""
        if self._fd is None:
            return
        try:
            self.path.unlink(missing_ok=True)
        finally:
            os.close(self._fd)
            self._fd = None


def being_recorded(folder: Path) -> bool:
    """Whether a live writer holds the recording lock of bag folder ``folder`` (read-only test)."""
    try:
        fd = os.open(Path(folder) / LOCK_FILE, os.O_RDONLY)
    except OSError:  # no lock file (closed, or never locked), or not readable: nobody to wait for
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)  # closing drops the shared lock this test may have taken
    return False
