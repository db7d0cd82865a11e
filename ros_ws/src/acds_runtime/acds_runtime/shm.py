"""Fast DDS shared-memory files a run leaves in /dev/shm, and removing the zombies among them.

A participant keeps its SHM segments (``fastrtps_<16 hex>``) and ports (``fastrtps_port<N>``,
semaphore ``sem.fastrtps_port<N>_mutex``) with lock files beside them (``…_el`` / ``…_sl``)
that it holds with ``flock`` while it lives. A SIGKILLed process cannot remove its files; the
kernel releases its locks, so "no lock file held" means "zombie" (what ``fastdds shm clean`` decides).
A port must never lose its lock files and stay: Fast DDS takes an existing port whose lock files exist but are not
held for the zombie it is and makes it anew, but one with no lock file left it reuses as it finds it, and a
participant killed while it read from the port left it marked healthy with a listener that is gone (measured below).

:func:`clean_run` removes the zombies among the entries whose lock files appeared while a run went (a snapshot taken
at its start), the port with its lock files even if the port was there before (a participant of the run made it its
own), so it never touches a file another live process holds, an entry no participant of the run used, nor one
created in the last :data:`MIN_AGE_S` seconds (a participant starting up right now). :func:`clean_domain` removes,
as a run leases its domain, every port of that domain no process holds, with lock files or without, wherever it
came from.
"""

from __future__ import annotations

import fcntl
import os
import re
import time
from pathlib import Path

SHM_DIR = Path('/dev/shm')
_LOCK = re.compile(r'^(fastrtps_(?:port\d{1,5}|[0-9a-z]{16}))_(el|sl)$')
#: A port's entries: the port itself, its lock files and its mutex, by port number.
_PORT_ENTRY = re.compile(r'^(?:sem\.)?fastrtps_port(\d{1,5})(?:_el|_sl|_mutex)?$')
#: The RTPS well-known ports (port base PB, domain gain DG; DDSI-RTPS 2.2 §9.6.1.1, Fast DDS's defaults): every port a
#: participant on domain d opens, discovery and user data, multicast and unicast, lies in [PB + DG·d, PB + DG·(d + 1)).
PORT_BASE, DOMAIN_GAIN = 7400, 250


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
    """Remove the zombie segments and ports whose lock files were created since ``before``; return the names removed.

    An entry is a zombie only when none of its lock files (``_el``, ``_sl``) is held or young: a live
    participant may hold just one of them (the other run of a parallel test session, on its own
    domain, creates its entries meanwhile too, and they are in ``new``). The entry goes whole: removing only the
    new lock files of a port that was there before left a port Fast DDS reuses as it is (the module's docstring)."""
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
        removed += _remove(shm_dir, [v for v in victims if (shm_dir / v).exists()])
    return removed


def _remove(shm_dir: Path, names: list[str]) -> list[str]:
    """Unlink ``names`` in ``shm_dir``; return those removed (one gone meanwhile, or not ours to remove, is skipped)."""
    removed = []
    for name in names:
        try:
            (shm_dir / name).unlink()
            removed.append(name)
        except OSError:
            pass
    return removed


def clean_domain(domain_id: int, shm_dir: Path = SHM_DIR) -> list[str]:
    """Remove the zombie ports of ``domain_id`` (see :data:`PORT_BASE`) before a run on it starts; return the names.

    For a domain just leased (:class:`acds_runtime.launcher.DomainLease`): no run of this project is on it, so a port of
    it whose lock files no process holds (or that has none left) has no reader; the entries of a port are removed
    together, unless any of them is young (a participant being created right now: someone else's, on a domain they
    chose). Measured: one port without lock files (``fastrtps_port26161`` and its mutex: marked healthy, one listener,
    that of a killed participant) made every run on its domain, 75, fail: every participant discovered the others,
    none received a sample from another (4 of 4 two-node runs under load, 1 of 1 quiet: "graph never became ready" or
    a node waiting 30 s for /clock step 0); with the entries removed, or with the port's listener count or its health
    flag zeroed, or with an unheld ``_el`` file beside it, the same run passed.
    """
    low = PORT_BASE + DOMAIN_GAIN * domain_id
    ports: dict[int, list[str]] = {}
    for name in snapshot(shm_dir):
        m = _PORT_ENTRY.match(name)
        if m is not None and low <= int(m.group(1)) < low + DOMAIN_GAIN:
            ports.setdefault(int(m.group(1)), []).append(name)
    removed: list[str] = []
    for port, names in sorted(ports.items()):
        locks = [shm_dir / f'fastrtps_port{port}_{kind}' for kind in ('el', 'sl')]
        if any(_young(shm_dir / n) for n in names) or any(p.exists() and lock_held(p) for p in locks):
            continue
        removed += _remove(shm_dir, sorted(names))
    return removed
