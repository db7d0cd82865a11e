"""``acds bench``: measured speed, printed (never asserted in tests).

1. graph: full-graph lockstep steps/s of ``free_tumble_heao_b`` (every node its own process);
2. bare chain: a ring of the same number of plain rclpy processes passing one message
   around (same QoS, same executor) — cycles/s, the ceiling the lockstep could reach;
3. core: ``RigidBodyModel.advance`` steps/s with no ROS at all.
``hops`` is the number of processes one step passes through sequentially (the
graph's node count). Steady-state rates exclude start-up (discovery).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

SCENARIO = 'free_tumble_heao_b'


def graph_rate(steps: int) -> tuple[float, int]:
    """Steady-state lockstep steps/s of the scenario's graph (steps after the first 10 %)."""
    from acds_common.scenario import load_scenario

    from .launcher import GraphRun

    sc = load_scenario(SCENARIO)
    marks: dict[int, float] = {}
    skip = steps // 10

    def progress(k: int, _total: int, wall: float) -> None:
        if k in (skip, steps):
            marks[k] = wall

    run_dir = Path(os.environ.get('TMPDIR', '/tmp')) / f'acds_bench_{os.getpid()}'
    with GraphRun(sc, run_dir, steps=steps, echo=lambda _l: None, progress=progress) as graph:
        graph.wait()
    return (steps - skip) / (marks[steps] - marks[skip]), len(sc.get('', 'nodes'))


def bare_chain_rate(hops: int, cycles: int) -> float:
    """Cycles/s of a ring of ``hops`` rclpy processes relaying one message."""
    from .launcher import FASTDDS_PROFILE, DomainLease

    lease = DomainLease()
    env = dict(os.environ, ROS_DOMAIN_ID=str(lease.domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               FASTRTPS_DEFAULT_PROFILES_FILE=str(FASTDDS_PROFILE))
    procs = [subprocess.Popen([sys.executable, '-m', 'acds_cli.bare_chain', str(i), str(hops), str(cycles)],
                              env=env, stdout=subprocess.PIPE, text=True) for i in range(hops)]
    try:
        out, _ = procs[0].communicate(timeout=600)
        for p in procs[1:]:
            p.wait(timeout=30)
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.wait()
        lease.close()
    return float(out.strip().splitlines()[-1])


def core_rate(steps: int) -> float:
    """Steps/s of the rigid-body core alone (same scenario, no ROS)."""
    import numpy as np
    from acds_common.scenario import load_scenario
    from dynamics.environment import EarthFieldConfig, Orbit, OrbitConfig, Sun, SunConfig, TiltedDipoleField
    from dynamics.rigid_body_model import RigidBodyModel, inertia_tensor

    sc = load_scenario(SCENARIO)
    o = sc.values['orbit']
    model = RigidBodyModel(
        inertia_tensor(*sc.get('spacecraft', 'inertia')),
        Orbit(OrbitConfig(kind='circular', altitude_m=o['altitude'], inclination_rad=o['inclination'])),
        TiltedDipoleField(EarthFieldConfig()), Sun(SunConfig()),
        substeps=sc.get('dynamics', 'substeps'), omega0_body_rad_s=sc.get('spacecraft', 'initial_rates'))
    zero = np.zeros(3)
    t0 = time.perf_counter()
    for _ in range(steps):
        model.advance(sc.control_period_s, zero, zero, zero)
        model.truth(zero)
    return steps / (time.perf_counter() - t0)


def main(args: argparse.Namespace) -> int:
    """Run the three measurements and print them (``--json``: last line one JSON object)."""
    graph, hops = graph_rate(args.steps)
    bare = bare_chain_rate(hops, args.steps)
    core = core_rate(min(args.steps, 2000))
    result = {'graph_steps_per_s': round(graph, 1), 'bare_chain_steps_per_s': round(bare, 1),
              'ratio': round(graph / bare, 3), 'core_steps_per_s': round(core, 1), 'hops': hops,
              'cores': os.cpu_count()}
    print(f'full-graph lockstep ({SCENARIO}, {hops} processes + monitor): {graph:10.1f} steps/s')
    print(f'bare rclpy chain ({hops} hops per cycle):                      {bare:10.1f} cycles/s')
    print(f'ratio graph / bare chain:                                  {graph / bare:10.3f}')
    print(f'rigid-body core only (no ROS):                             {core:10.1f} steps/s')
    print(f'machine cores: {os.cpu_count()}')
    if args.json:
        print(json.dumps(result))
    return 0
