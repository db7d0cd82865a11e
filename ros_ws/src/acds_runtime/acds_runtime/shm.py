"""Fast DDS shared-memory files a run leaves in /dev/shm, and removing the zombies among them.

A participant keeps its SHM segments (``fastrtps_<16 hex>``) and ports (``fastrtps_port<N>``,
semaphore ``sem.fastrtps_port<N>_mutex``) with lock files beside them (``…_el`` / ``…_sl``)
that it holds with ``flock`` while it lives. A SIGKILLed process cannot remove its files; the
kernel releases its locks, so "no lock file held" means "zombie" (what ``fastdds shm clean`` decides;
a port file without any lock file is left alone: a live participant may still use it).
:func:`clean_run` removes the
zombies among the entries that appeared while a run went (a snapshot taken at its start), so
it never touches a file another live process holds, one that was there before the run, nor one
created in the last :data:`MIN_AGE_S` seconds (a participant starting up right now).
"""

from __future__ import annotations

import fcntl
import os
import re
import time
from pathlib import Path

SHM_DIR = Path('/dev/shm')
_LOCK = re.compile(r'^(fastrtps_(?:port\d{1,5}|[0-9a-z]{16}))_(el|sl)$')


def snapshot(shm_dir: Path = SHM_DIR) -> set[str]:
    """Names of the Fast DDS entries present now."""
    try:
        return {n for n in os.listdir(shm_dir) if 'fastrtps_' in n}
    except FileNotFoundError:
        return set()


#: Where the kernel lists every file lock held now (``flock`` ones included), by device and inode.
PROC_LOCKS = Path('/proc/locks')


def _locked_inodes() -> set[int] | None:
    """Inode numbers of the files some process holds a lock on now (/proc/locks), or None when it cannot be read.

    By inode number alone: an overlay filesystem may name a file's device there otherwise than ``stat`` does, and
    an inode of another filesystem with the same number only makes a file count as held (the safe side)."""
    try:
        text = PROC_LOCKS.read_text()
    except OSError:
        return None
    return {int(tok.rsplit(':', 1)[1]) for line in text.splitlines() for tok in line.split() if tok.count(':') == 2}


def lock_held(path: Path, *, probe: bool = False) -> bool:
    """Whether a live process holds an ``flock`` on ``path``, read from /proc/locks, never by taking the lock.

    Taking it, even for a moment, makes a process that locks the file meanwhile fail: Fast DDS opening a port
    tries an exclusive lock, then a shared one, and gives the port up when both fail, and the participant then
    never receives what a writer sends to that port. Measured: the end-of-run cleaning of one run, probing the
    lock files of another run starting beside it, left that run's monitor without a message from its time owner
    (1 run in 77 of two loops of the same free-tumble ``acds run`` side by side, 0 in 80 after; once in a
    fresh-clone suite). With ``probe`` (a file only this project locks: a domain lease, a sample folder), a file
    /proc/locks does not list is also tried with LOCK_EX|LOCK_NB and released at once. A file that cannot be
    looked at counts as held."""
    try:
        inode = os.stat(path).st_ino
    except OSError:
        return True
    locked = _locked_inodes()
    if locked is not None and inode in locked:
        return True
    if not probe:
        return locked is None
    try:
        with open(path, 'ab') as fh:
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                return True
            fcntl.flock(fh, fcntl.LOCK_UN)
            return False
    except OSError:
        return True


#: A lock file younger than this may belong to a participant that is still being created (its file
#: exists before it locks it): never a zombie yet.
MIN_AGE_S = 5.0


def _young(path: Path) -> bool:
    try:
        return time.time() - path.stat().st_mtime < MIN_AGE_S
    except OSError:
        return True


def clean_run(before: set[str], shm_dir: Path = SHM_DIR) -> list[str]:
    """Remove the zombie segments and ports created since ``before``; return the names removed.

    An entry is a zombie only when none of its lock files (``_el``, ``_sl``) is held or young: a live
    participant may hold just one of them (the other run of a parallel test session, on its own
    domain, creates its entries meanwhile too, and they are in ``new``)."""
    new = snapshot(shm_dir) - before
    bases = sorted({m.group(1) for m in map(_LOCK.match, new) if m is not None})
    removed: list[str] = []
    for base in bases:
        locks = [shm_dir / f'{base}_{kind}' for kind in ('el', 'sl') if (shm_dir / f'{base}_{kind}').exists()]
        if not locks or any(_young(p) or lock_held(p) for p in locks):
            continue
        victims = [base, f'{base}_el', f'{base}_sl']
        if base.startswith('fastrtps_port'):
            victims.append(f'sem.{base}_mutex')
        for victim in victims:
            if victim in new:
                try:
                    (shm_dir / victim).unlink()
                    removed.append(victim)
                except OSError:
                    pass
    return removed
