"""Cross-package tests: the CLI's workspace and a ROS log folder in the checkout (the launch_graph harness is the
pytest plugin acds_runtime installs, entry point pytest11)."""

import hashlib
import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault('ROS_LOG_DIR', str(ROOT / 'runs' / 'ros_log'))
os.environ.setdefault('ACDS_WORKSPACE', str(ROOT))


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
