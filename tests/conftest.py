"""Cross-package tests: make ``scripts/acds_cli`` importable and load its pytest harness."""

import hashlib
import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / 'scripts'))
os.environ.setdefault('ROS_LOG_DIR', str(ROOT / 'runs' / 'ros_log'))

pytest_plugins = ['acds_runtime.testing']


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
