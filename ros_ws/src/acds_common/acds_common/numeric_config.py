"""A process's numeric configuration: what its results depend on besides the scenario (spec §2, "Time and determinism").

Two processes that agree on every item of :func:`numeric_configuration` compute the same bits from the same
scenario: the interpreter, numpy and the SIMD kernels it dispatches to (:data:`acds_common.SIMD_PIN` in force
or not), OpenBLAS and the kernel it chose for this CPU, the compiler of the direct engine's kernels
(numba, llvmlite) and the project's sources those kernels and models are. A Monte Carlo study asks every
Dask worker for it before sending samples (and checks it again on each sample's task, for a worker that
joined later); the launcher hands its own to every node process, which compares before ROS starts
(:func:`acds_common.lockstep.run_node`). A difference is one line naming what differs (:func:`differences`).

The host is reported, never compared. Cheap: numba is not imported (its version is read from the installed
metadata), the sources are hashed once per process.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import importlib.util
import json
import os
import platform
import socket
from importlib.metadata import PackageNotFoundError, entry_points, version
from pathlib import Path

from . import SIMD_PIN

#: The environment variable the launcher passes its own configuration in (JSON) to every node process.
ENV = 'ACDS_NUMERIC_CONFIG'
#: The items compared, in the order a difference names them, and how a line names each.
COMPARED = {'python': 'Python', 'numpy': 'numpy', 'simd': 'numpy SIMD dispatch', 'openblas': 'OpenBLAS',
            'kernels': 'kernel compiler', 'sources': 'project sources'}
#: The project's packages besides the node packages (entry point group ``acds.nodes``) whose code computes results.
_CORE_PACKAGES = ('acds_common', 'acds_runtime')


@functools.cache
def numeric_configuration() -> dict[str, str]:
    """This process's configuration (module doc): the :data:`COMPARED` items, plus ``host`` and ``pin`` (the
    two variables of :data:`acds_common.SIMD_PIN` as this process has them), which are reported only."""
    import numpy

    return {
        'python': platform.python_version(),
        'numpy': numpy.__version__,
        'simd': ' '.join(_dispatched()) or 'baseline only',
        'openblas': _openblas(),
        'kernels': ' '.join(f'{name} {_version(name)}' for name in ('numba', 'llvmlite')),
        'sources': _sources_digest(),
        'host': socket.gethostname(),
        'pin': ' '.join(f'{key}={os.environ[key]!r}' if key in os.environ else f'{key} unset' for key in SIMD_PIN),
    }


def _dispatched() -> list[str]:
    """The SIMD targets numpy's dispatched loops use in this process: built for, present on the CPU, not disabled
    (``NPY_DISABLE_CPU_FEATURES``)."""
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__

    return [target for target in __cpu_dispatch__ if __cpu_features__.get(target)]


def _openblas() -> str:
    """OpenBLAS's version (numpy's build) and the kernel it chose at load (``OPENBLAS_CORETYPE`` or the CPU's)."""
    import numpy

    blas = numpy.show_config(mode='dicts').get('Build Dependencies', {}).get('blas', {})
    text = f'{blas.get("name", "?")} {blas.get("version", "?")}'
    core = _openblas_core()
    return f'{text} core {core}' if core else text


def _openblas_core() -> str | None:
    """The core name the loaded OpenBLAS reports (Linux: found among the process's mapped libraries), or None."""
    try:
        with open('/proc/self/maps') as fh:
            paths = sorted({line.split()[-1] for line in fh if 'openblas' in line.lower() and '.so' in line})
    except OSError:
        return None
    for path in paths:
        lib = ctypes.CDLL(path)
        for symbol in ('scipy_openblas_get_corename64_', 'scipy_openblas_get_corename', 'openblas_get_corename64_',
                       'openblas_get_corename'):
            fn = getattr(lib, symbol, None)
            if fn is not None:
                fn.restype = ctypes.c_char_p
                return fn().decode()
    return None


def _version(distribution: str) -> str:
    try:
        return version(distribution)
    except PackageNotFoundError:
        return 'absent'


def _sources_digest() -> str:
    """SHA-256 (12 hex digits) of the Python files of the project's packages: :data:`_CORE_PACKAGES` and every node
    package (``acds.nodes`` entry points: the user's own included), by package and relative path; what a run generates
    under ``__pycache__`` (the fused loops a direct run composes) is not a source and is left out, so a study's
    nodes and its launcher agree whichever of them generated it first."""
    names = set(_CORE_PACKAGES) | {ep.value.split('.')[0].split(':')[0] for ep in entry_points(group='acds.nodes')}
    digest = hashlib.sha256()
    for name in sorted(names):
        spec = importlib.util.find_spec(name)
        if spec is None or not spec.submodule_search_locations:
            digest.update(f'{name} absent\0'.encode())
            continue
        root = Path(next(iter(spec.submodule_search_locations)))
        for path in sorted(root.rglob('*.py')):
            if '__pycache__' in path.parts:  # generated from the sources at run time (the fused loops): not a source
                continue
            digest.update(f'{name}/{path.relative_to(root)}\0'.encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()[:12]


def differences(mine: dict[str, str], theirs: dict[str, str], ref: str) -> list[str]:
    """How ``theirs`` differs from ``mine`` (the configuration of ``ref``: "the client", "the launcher"), one
    phrase per differing item of :data:`COMPARED` (empty: none); a different SIMD dispatch or OpenBLAS core adds
    the two variables of the pin as ``theirs`` has them."""
    out = [f'{label} {theirs.get(key)} ({ref}: {mine.get(key)})' for key, label in COMPARED.items()
           if mine.get(key) != theirs.get(key)]
    if any(mine.get(key) != theirs.get(key) for key in ('simd', 'openblas')):
        out.append(f'its pin: {theirs.get("pin", "?")}')
    return out


def to_env() -> str:
    """This process's configuration as the value of :data:`ENV`."""
    return json.dumps(numeric_configuration(), sort_keys=True)


def from_env() -> dict[str, str] | None:
    """The configuration the launcher passed in :data:`ENV`, or None (a process not started by a launcher)."""
    text = os.environ.get(ENV)
    return json.loads(text) if text else None
