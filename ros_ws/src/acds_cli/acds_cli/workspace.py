"""Where the command line writes: the workspace (runs/ and the Foxglove layout are in it).

The workspace is ``$ACDS_WORKSPACE`` (``./scripts/acds`` declares its own checkout) or else the current
folder, as for any installed command. The shipped scenarios are the package data of this package
(``acds_cli/scenarios``, the checkout's ``scenarios/``), found by :mod:`acds_common.scenario` through the
``acds.scenarios`` entry point.
"""

from __future__ import annotations

import os
from pathlib import Path


def workspace() -> Path:
    """The folder the CLI works in."""
    return Path(os.environ.get('ACDS_WORKSPACE') or Path.cwd())


def new_run_dir(name: str) -> Path:
    """A new folder ``runs/<name>_<local time>`` in the workspace, created exclusively: a run started in the same
    second gets ``_2``, ``_3``, ... (issue 18 §5)."""
    from acds_runtime.run_folder import create_run_folder

    return create_run_folder(workspace() / 'runs', name)
