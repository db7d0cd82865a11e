"""Cross-package tests: the CLI's workspace and a ROS log folder in the checkout (the launch_graph harness is the
pytest plugin acds_runtime installs, entry point pytest11)."""

import hashlib
import os
import struct
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault('ROS_LOG_DIR', str(ROOT / 'runs' / 'ros_log'))
os.environ.setdefault('ACDS_WORKSPACE', str(ROOT))
# Bound compiled kernels check every call's argument types (acds_common.kernels.bound), here and in the runs the
# tests start: a call site whose types are not what it bound fails the suite instead of being converted.
os.environ.setdefault('ACDS_KERNEL_CHECK', '1')


@pytest.fixture
def folder_state():
    """``folder_state(folder)``: every entry under ``folder`` with the SHA-256 of each file; equal before and
    after means nothing there was created, changed, renamed or removed."""
    def state(folder: Path) -> dict[str, str]:
        out = {}
        for entry in sorted(Path(folder).rglob('*')):
            if entry.is_file():
                with entry.open('rb') as fh:
                    out[str(entry.relative_to(folder))] = hashlib.file_digest(fh, 'sha256').hexdigest()
            else:
                out[str(entry.relative_to(folder))] = 'folder'
        return out
    return state


@pytest.fixture(scope='module')
def compile_kernels():
    """:func:`acds_common.kernels.compiled` with compilation enabled in this process (the direct engine's kernels)."""
    from acds_common import kernels

    kernels.enable()
    return kernels.compiled


@pytest.fixture
def ieee_bits():
    """``ieee_bits(value)``: every float of a nested result as its IEEE bytes (so −0.0 ≠ 0.0 and a NaN is itself),
    other leaves as they are: what the compiled-against-plain kernel tests compare."""
    def bits(value: object) -> list:
        if isinstance(value, tuple | list):
            return [b for v in value for b in bits(v)]
        return [struct.pack('<d', value) if isinstance(value, float) else value]
    return bits


@pytest.fixture
def play_domain():
    """A ROS domain for ``acds play`` outside the launcher's DOMAIN_RANGE: no run ever lands on it, so playback
    never reaches another test's graph (play leases it while it plays; one per pytest worker)."""
    from acds_runtime.launcher import DOMAIN_RANGE

    domain = 150 + os.getpid() % 80
    assert domain not in DOMAIN_RANGE
    return domain
