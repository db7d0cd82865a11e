"""A compiled kernel's disk cache follows the helpers it calls (acds_common.kernel_cache, issue 24).

numba's own stamp covers the kernel's file only: with it, the second run below still printed 3.0 after the helper
in another file changed (the stale machine code of the first run).
"""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
import textwrap
from pathlib import Path

RUN = """
import sys
sys.path.insert(0, {folder!r})
from acds_common import kernels
kernels.enable()
import kernel_mod
print(kernels.compiled(kernel_mod.k)(1.0))
"""


def _write(folder: Path, factor: str) -> None:
    (folder / 'helpers_mod.py').write_text(textwrap.dedent(f"""
        from acds_common import kernels


        @kernels.helper
        def twice(x):
            return {factor} * x
        """))


def _run(folder: Path) -> str:
    out = subprocess.run([sys.executable, '-c', RUN.format(folder=str(folder))], capture_output=True, text=True,
                         timeout=120, env={k: v for k, v in os.environ.items() if k != 'NUMBA_CACHE_LOCATOR_CLASSES'})
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


def test_a_changed_helper_recompiles_the_kernel_that_calls_it(tmp_path):
    _write(tmp_path, '2.0')
    (tmp_path / 'kernel_mod.py').write_text('import helpers_mod\n\n\ndef k(x):\n    return helpers_mod.twice(x) + 1.0\n')
    assert _run(tmp_path) == '3.0'
    index = next((tmp_path / '__pycache__').glob('kernel_mod.k-*.nbi'))
    written = index.stat().st_mtime_ns
    assert _run(tmp_path) == '3.0'  # nothing changed: loaded from the cache, not written again
    assert index.stat().st_mtime_ns == written
    _write(tmp_path, '3.0')
    assert _run(tmp_path) == '4.0'


def test_a_kernel_reaches_helpers_by_name_through_modules_and_through_helpers(tmp_path, monkeypatch):
    """What the stamp covers: a helper named directly, one reached as a module's attribute, one a helper calls;
    not a helper the kernel does not call."""
    (tmp_path / 'reach_a.py').write_text(textwrap.dedent("""
        from acds_common import kernels


        @kernels.helper
        def inner(x):
            return x + 1.0


        @kernels.helper
        def outer(x):
            return inner(x) * 2.0


        @kernels.helper
        def unused(x):
            return x
        """))
    (tmp_path / 'reach_b.py').write_text(textwrap.dedent("""
        from acds_common import kernels


        @kernels.helper
        def by_module(x):
            return -x
        """))
    (tmp_path / 'reach_k.py').write_text(textwrap.dedent("""
        import reach_b
        from reach_a import outer


        def k(x):
            return outer(x) + reach_b.by_module(x)
        """))
    monkeypatch.syspath_prepend(str(tmp_path))
    from acds_common import kernel_cache

    a, b, k = (importlib.import_module(name) for name in ('reach_a', 'reach_b', 'reach_k'))
    assert set(kernel_cache.reached_helpers(k.k)) == {a.outer, a.inner, b.by_module}
