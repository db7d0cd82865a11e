"""Cross-package tests: make ``scripts/acds_cli`` importable and load its pytest harness."""

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / 'scripts'))
os.environ.setdefault('ROS_LOG_DIR', str(ROOT / 'runs' / 'ros_log'))

pytest_plugins = ['acds_cli.testing']
