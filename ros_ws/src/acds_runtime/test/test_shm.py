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
