"""Wall time of the main job with the IGRF field over the study's dipole (issue 12 §6): measured, not asserted.

    .venv/bin/python scripts/igrf_wall_ratio.py [--steps 3000] [--engine graph|direct] [--repeats 2] [--epoch 2025.5]

Runs the main job (``main_job`` of ``scenarios/roles.json``) shortened to ``--steps`` control steps, without
recording, alternately with ``earth.model: dipole`` (as shipped) and ``earth.model: igrf``, and prints each wall
time and the ratio of the medians. The graph engine is the main job's (six processes); ``direct`` runs the same steppers in
this process.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
from pathlib import Path

from acds_common.scenario import load_scenario, shipped_role
from acds_runtime.direct import DirectRun
from acds_runtime.launcher import GraphRun

MAIN_JOB = shipped_role('main_job')


def wall_s(scenario_path: str, steps: int, engine: str, run_dir: Path) -> float:
    """Wall seconds of one run of ``steps`` steps (the engine's own measure, from the first step to the last)."""
    scenario = load_scenario(scenario_path)
    if engine == 'direct':
        return DirectRun(scenario, steps=steps).run().wall_seconds
    with GraphRun(scenario, run_dir, steps=steps, echo=lambda _line: None) as graph:
        return graph.wait().wall_seconds


def main() -> int:
    """Print the walls and the IGRF/dipole ratio."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--steps', type=int, default=3000, help='control steps per run (default 3000: 25 min sim)')
    parser.add_argument('--engine', choices=('graph', 'direct'), default='graph')
    parser.add_argument('--repeats', type=int, default=2, help='runs of each model (default 2)')
    parser.add_argument('--epoch', type=float, default=2025.5, help='IGRF date, decimal year (default 2025.5)')
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix='acds_igrf_ratio_') as tmp:
        igrf = Path(tmp) / 'igrf_main_job.yaml'
        igrf.write_text(f'extends: {MAIN_JOB}\nname: {MAIN_JOB}_igrf\nearth:\n  model: igrf\n'
                        f'  epoch_year: {args.epoch}\n')
        walls: dict[str, list[float]] = {'dipole': [], 'igrf': []}
        for i in range(args.repeats):
            for model, path in (('dipole', MAIN_JOB), ('igrf', str(igrf))):
                wall = wall_s(path, args.steps, args.engine, Path(tmp) / f'{model}_{i}')
                walls[model].append(wall)
                print(f'{model:6s} run {i + 1}: {args.steps} steps in {wall:7.2f} s wall ({args.engine} engine)',
                      flush=True)
    dipole, igrf_wall = statistics.median(walls['dipole']), statistics.median(walls['igrf'])
    print(f'main job {MAIN_JOB}, {args.steps} steps, {args.engine} engine: dipole {dipole:.2f} s, '
          f'IGRF {igrf_wall:.2f} s (medians); IGRF/dipole wall-time ratio {igrf_wall / dipole:.2f}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
