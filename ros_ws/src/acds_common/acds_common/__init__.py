"""Shared pieces every ACDS node needs: units, topic names, scenario loading, the lockstep base.

Importing it pins numpy's SIMD kernels (:func:`pin_simd_kernels`), so a scenario gives the same bits on every
x86-64 machine, whatever its vector units. The project's environment imports it where Python starts, before any
program run with it imports numpy: ``scripts/setup_env.sh`` installs ``acds_simd_pin.pth`` in its site-packages.
"""

import os
import platform
import sys
import warnings

#: numpy's own dispatched loops (exp, sin, sums, …) and OpenBLAS (matmul, solve, eig) pick kernels by the CPU: the
#: AVX-512 ones round differently in the last bit from the AVX2 ones (measured: the AAP Workshop and EMFF truth
#: digests differ between a Sapphire Rapids and an AVX2 machine; with these two settings they agree). The
#: project's data are those of the AVX2 (x86-64-v3) kernels on every x86-64 machine that has AVX2 and FMA.
SIMD_PIN = {'NPY_DISABLE_CPU_FEATURES': 'X86_V4 AVX512_ICL AVX512_SPR', 'OPENBLAS_CORETYPE': 'Haswell'}


def pin_simd_kernels() -> None:
    """Set :data:`SIMD_PIN` in this process's environment (and so its children's), unless the user set them.

    It must run before numpy is first imported (its kernels are chosen then): this package's import does it, and
    the environment's startup hook (``acds_simd_pin.pth``, module doc) imports this package in every Python process
    the environment starts (a ``dask worker`` too, which imports numpy before any task runs). A process that imported
    numpy before (one started with ``python -S``, which skips the hook) may compute other last bits on an
    AVX-512 machine: it gets a warning, and the numeric-configuration check (:mod:`acds_common.numeric_config`)
    refuses it as a Dask worker or a node. Only on x86-64 with AVX2 and FMA (an
    older or other CPU keeps its own kernels).
    """
    if platform.machine() not in ('x86_64', 'AMD64') or not _has_avx2_fma():
        return
    if 'numpy' in sys.modules and any(os.environ.get(k) != v for k, v in SIMD_PIN.items()):
        warnings.warn('numpy was imported before acds_common: on an AVX-512 machine its kernels may change the last '
                      'bits of the results (set ' + ' '.join(f'{k}="{v}"' for k, v in SIMD_PIN.items())
                      + ' before Python starts)', RuntimeWarning, stacklevel=3)
    for key, value in SIMD_PIN.items():
        os.environ.setdefault(key, value)


def _has_avx2_fma() -> bool:
    try:
        with open('/proc/cpuinfo') as fh:
            for line in fh:
                if line.startswith('flags'):
                    flags = set(line.split(':', 1)[1].split())
                    return {'avx2', 'fma'} <= flags
    except OSError:
        pass
    return False


pin_simd_kernels()
