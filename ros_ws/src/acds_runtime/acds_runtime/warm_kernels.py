"""Compile the direct engine's kernels into numba's disk cache once, at set-up (``scripts/setup_env.sh``).

A process that runs the direct engine loads each model's compiled kernel from the cache beside its source
(:mod:`acds_common.kernels`, ~1 s in all); with no cache it compiles them first (~35 s on the 2-core machine,
issue 24), and so did the first run after a clone, each Monte Carlo worker and each test worker of a fresh
checkout at once. Two steps of every shipped scenario build every model the way its runs do, so every kernel
signature they bind is compiled here, once; a graph with a fused loop (:mod:`acds_runtime.fused_step`) composes and
compiles it there too (its first block is tried at step 2), once per structure and signature (one serves every
shipped scenario of one graph structure). A scenario that leaves a node to the user (key ``external``) runs
only on the per-process graph and is skipped.

Run as ``python -m acds_runtime.warm_kernels``; it exits non-zero, naming the scenario, if one fails to run.
"""

from __future__ import annotations

import sys
import time

from acds_common.scenario import SCENARIO_DIR, load_scenario

from .direct import DirectRun
from .launcher import LaunchError


def main() -> int:
    """Two direct-engine steps of every shipped scenario; 0, or 1 with the scenario that failed."""
    t0 = time.monotonic()
    names = sorted(p.stem for p in SCENARIO_DIR.glob('*.yaml'))
    for name in names:
        scenario = load_scenario(name)
        if scenario.get('', 'external'):
            continue
        try:
            DirectRun(scenario, steps=2).run()
        except LaunchError as exc:
            print(f'[setup] compiling the kernels: scenario {name} failed: {exc}', file=sys.stderr)
            return 1
    print(f'[setup] direct engine kernels compiled for {len(names)} scenarios in {time.monotonic() - t0:.0f} s',
          file=sys.stderr)
    return 0


if __name__ == '__main__':
    sys.exit(main())
