"""A run's default folder, created exclusively: two runs started in the same second never share one.

``runs/<stem>_<YYYYmmdd_HHMMSS>`` is made with ``mkdir`` (no ``exist_ok``); when another run made it
first (same scenario, same second) the next free ``…_2``, ``…_3``, … is taken, so each run's
``domain_id``, ``params.yaml`` and bag stay its own and ``acds record --run-dir`` joins the run the
folder names (issue 18 item 5).
"""

from __future__ import annotations

import time
from pathlib import Path


def create_run_folder(parent: Path, stem: str) -> Path:
    """Create and return ``parent/<stem>_<local time to the second>`` (or its first free ``_N`` variant)."""
    parent = Path(parent)
    parent.mkdir(parents=True, exist_ok=True)
    base = f'{stem}_{time.strftime("%Y%m%d_%H%M%S")}'
    n = 1
    while True:
        path = parent / (base if n == 1 else f'{base}_{n}')
        try:
            path.mkdir()
            return path
        except FileExistsError:
            n += 1
