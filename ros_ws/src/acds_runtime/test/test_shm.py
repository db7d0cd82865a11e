"""SHM zombie cleaning removes only entries no live participant holds (acds_runtime.shm)."""

from __future__ import annotations

import fcntl
import os
import time

from acds_runtime import shm


def _port(d, n: int, age_s: float = 60.0) -> str:
    base = f'fastrtps_port{n}'
    for name in (base, f'{base}_el', f'{base}_sl', f'sem.{base}_mutex'):
        (d / name).write_bytes(b'')
        old = time.time() - age_s
        os.utime(d / name, (old, old))
    return base


def test_only_entries_with_no_lock_held_are_removed(tmp_path):
    before = shm.snapshot(tmp_path)
    dead = _port(tmp_path, 7001)
    half = _port(tmp_path, 7002)  # a live participant holding only one of its two lock files
    young = _port(tmp_path, 7003, age_s=0.0)  # being created right now
    with open(tmp_path / f'{half}_sl', 'ab') as held:
        fcntl.flock(held, fcntl.LOCK_SH)
        removed = shm.clean_run(before, tmp_path)
    assert sorted(removed) == sorted([dead, f'{dead}_el', f'{dead}_sl', f'sem.{dead}_mutex'])
    left = set(os.listdir(tmp_path))
    assert {half, f'{half}_el', f'{half}_sl', young} <= left


def test_entries_present_before_the_run_are_never_touched(tmp_path):
    old = _port(tmp_path, 7004)
    before = shm.snapshot(tmp_path)
    assert shm.clean_run(before, tmp_path) == []
    assert old in os.listdir(tmp_path)


def test_cleaning_never_takes_a_lock_it_looks_at(tmp_path, monkeypatch):
    """Whether a lock is held is read from /proc/locks: a probe that took the lock for a moment made a Fast DDS
    participant opening that port then fail (exclusive, then shared, both refused) and lose the port."""
    before = shm.snapshot(tmp_path)
    dead = _port(tmp_path, 7005)
    live = _port(tmp_path, 7006)
    with open(tmp_path / f'{live}_el', 'ab') as held:
        fcntl.flock(held, fcntl.LOCK_EX)

        def refuse(*_args):
            raise AssertionError('the cleaning took a lock on a file it looked at')
        monkeypatch.setattr(shm.fcntl, 'flock', refuse)
        assert shm.lock_held(tmp_path / f'{live}_el') and not shm.lock_held(tmp_path / f'{dead}_el')
        removed = shm.clean_run(before, tmp_path)
    assert dead in removed and live not in removed


def test_a_lease_file_not_listed_in_proc_locks_is_probed(tmp_path, monkeypatch):
    """``probe``: a file only this project locks is also tried, in case /proc/locks names it otherwise."""
    lease = tmp_path / 'domain_42.lock'
    lease.write_bytes(b'')
    with open(lease, 'ab') as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        monkeypatch.setattr(shm, '_locked_inodes', set)  # /proc/locks lists nothing
        assert not shm.lock_held(lease)
        assert shm.lock_held(lease, probe=True)
    assert not shm.lock_held(lease, probe=True)


def test_a_port_that_was_there_before_goes_with_its_new_lock_files(tmp_path):
    """A port left without its lock files is reused as found by the next participant on its number (see
    ``clean_domain``): a zombie goes whole, the port and its mutex with the lock files the run created."""
    base = 'fastrtps_port7007'
    for name in (base, f'sem.{base}_mutex'):
        (tmp_path / name).write_bytes(b'')
    before = shm.snapshot(tmp_path)
    for name in (f'{base}_el', f'{base}_sl'):
        (tmp_path / name).write_bytes(b'')
        os.utime(tmp_path / name, (time.time() - 60, time.time() - 60))
    assert sorted(shm.clean_run(before, tmp_path)) == sorted([base, f'{base}_el', f'{base}_sl', f'sem.{base}_mutex'])
    assert os.listdir(tmp_path) == []


def test_a_leased_domain_loses_every_port_of_it_no_process_holds(tmp_path):
    domain = 3  # its ports: 8150 … 8399
    bare = 'fastrtps_port8161'  # no lock file left: a zombie all the same
    for name in (bare, f'sem.{bare}_mutex'):
        (tmp_path / name).write_bytes(b'')
        os.utime(tmp_path / name, (time.time() - 60, time.time() - 60))
    dead = _port(tmp_path, 8163)
    live = _port(tmp_path, 8165)
    young = _port(tmp_path, 8167, age_s=0.0)
    other_domain = _port(tmp_path, 8411)
    segment = 'fastrtps_0123456789abcdef'
    (tmp_path / segment).write_bytes(b'')
    with open(tmp_path / f'{live}_el', 'ab') as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        removed = shm.clean_domain(domain, tmp_path)
    assert sorted(removed) == sorted([bare, f'sem.{bare}_mutex', dead, f'{dead}_el', f'{dead}_sl',
                                      f'sem.{dead}_mutex'])
    left = set(os.listdir(tmp_path))
    assert {live, f'{live}_el', young, other_domain, segment} <= left
