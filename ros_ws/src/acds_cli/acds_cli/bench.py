"""``acds bench``: measured speed of what users run, printed (never asserted in tests), one run.

1. graph: the six-node main job (``scenarios/roles.json``; every node its own process, recording on, the node
   processes placed on two CPUs as the launcher places them; and again placed by the OS), steady-state lockstep
   steps/s after the first 10 % of the steps, CPU ms per step of every node process and of the launcher (its run
   monitor and recorder), and the deliveries per step (each message published × the subscriptions that receive it);
2. bare ring: as many plain rclpy processes as the graph has nodes, passing one message
   around (same QoS, same EventsExecutor spun the same way) — cycles/s, the ceiling a lockstep could reach; placed by
   the OS, and placed by the launcher's rule (a chain: one CPU);
3. direct engine: the same scenario's steppers in one process (``--engine direct``), after a short
   run that loads its compiled kernels and fused loop (:mod:`acds_common.kernels`, :mod:`acds_runtime.fused_step`;
   that one-time load, paid once per process, is printed beside it); then the same run without the fused loop
   (every step through the Python step program), and each model's fused kernel alone (µs per step);
4. kernel: the rigid body + environment (``RigidBodyModel.advance`` + ``truth``) alone at
   the scenario's control period and substeps, with the attitude kernel compiled as the direct engine runs it;
5. dispersion: a fixed 20-sample study of the same scenario (case 1), samples 0–19 of seed
   :data:`DISPERSION_SEED` with the default draws, each run to acquisition capture on the direct engine,
   one after the other in this process (``montecarlo --jobs 1``): samples/s; and a sample's fixed cost (CPU ms per
   sample of the same samples run one step each: its scenario loaded, its steppers, step and run summary built)
   and its draw's (CPU ms per sample drawn as the study draws it, in the study's own process);
6. flight-software sample: the scenario with one node left to an example node, started and stopped per sample as
   ``montecarlo --external ... --fsw-command`` (``bench_flight_software`` of ``scenarios/roles.json``)
   does (:func:`acds_runtime.flight_software.run_fsw_sample`): the overhead of a sample (wall seconds of a
   :data:`FSW_SHORT_STEPS`-step sample, the median of :data:`FSW_REPEATS`: the graph's processes and the user's node
   started, joined, stopped) and the steps/s of a :data:`FSW_STEPS`-step sample beyond it.

The direct engine and the dispersion are also given per second of this process's CPU time: on a machine
shared with other work, the wall rate measures the load as much as the code.

``--json`` prints one object with the keys ``graph_steps_per_s``, ``bare_chain_steps_per_s``,
``ratio``, ``hops``, ``placement`` (the CPUs the launcher placed the node processes on, :mod:`acds_runtime.placement`;
null when it does not place them: not exactly two CPUs) and, when it does, the graph placed by the OS
(``graph_os_placed_steps_per_s``, ``ratio_os_placed``: against the same ring) and the ring placed by the same rule
(``bare_chain_placed_steps_per_s``, ``ratio_placed``: the placed graph against it), ``deliveries_per_step``
(and ``deliveries_by_topic``: per step, each topic's messages × the subscriptions that receive them, the monitor's
included), ``direct_steps_per_s``, ``direct_steps_per_cpu_s``,
``direct_kernel_load_s``, ``direct_unfused_steps_per_s`` and ``direct_unfused_steps_per_cpu_s`` (the direct engine
without its fused loop), ``direct_fused_share`` (the steps the fused loop ran), ``fused_loop_us_per_step`` (wall µs a
step inside it), ``fused_us_per_model`` (node → µs per step of its fused kernel alone), ``core_steps_per_s``,
``core_steps_per_cpu_s``, ``direct_kernel_ratio`` and
``direct_kernel_ratio_cpu`` (the whole six-model step against the rigid-body kernel alone: direct / core, per wall and
per CPU second), ``dispersion_samples_per_s``, ``dispersion_samples_per_cpu_s``, ``dispersion_sample_overhead_ms``,
``dispersion_draw_ms``, ``fsw_sample_overhead_s``,
``fsw_sample_steps_per_s``, ``cores``, ``cpu_model`` and ``simd`` (the SIMD targets numpy dispatches to here:
figures compare between hosts of one model and level only), ``cpu_ms_per_step`` and ``load_average``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from acds_common.scenario import shipped_role

#: The graph, direct, kernel and dispersion lines' scenario: the main job.
SCENARIO = shipped_role('main_job')
#: Fewest steps a measurement takes: the graph line measures from the tenth step to MONITOR_LAG (50) + 2 steps
#: before the end, while every node process lives (:func:`graph_rate`).
MIN_STEPS = 500
#: The dispersion line's study: samples 0…DISPERSION_SAMPLES − 1 of this seed.
DISPERSION_SEED, DISPERSION_SAMPLES = 1, 20
#: The flight-software sample line: its scenario, node and command (docs/flight_software.md's), the short sample's steps, how
#: many short samples (their median is the overhead), the long sample's steps.
FSW_SCENARIO, FSW_NODE, FSW_COMMAND = (shipped_role('bench_flight_software')[k] for k in ('scenario', 'node', 'command'))
FSW_SHORT_STEPS, FSW_REPEATS, FSW_STEPS = 2, 3, 2000
#: The fused step's cost per model: each node's kernel timed at this step of the main job, this many calls.
COST_STEP, COST_REPEATS = 200, 20000


def bench_steps(text: str) -> int:
    """``--steps``: a number of control steps, MIN_STEPS … the most a run may have."""
    from .arguments import step_count

    value = step_count(text)
    if value < MIN_STEPS:
        raise argparse.ArgumentTypeError(f'{value} steps is too few to measure: at least {MIN_STEPS}')
    return value


def cpu_model(cpuinfo: str | None = None) -> str:
    """The CPU's model name (``/proc/cpuinfo``, or ``cpuinfo`` given), else what :mod:`platform` says (an aarch64
    ``/proc/cpuinfo`` has no model name): a bench's figures compare only between hosts of one model and one SIMD
    level (Measurements)."""
    if cpuinfo is None:
        try:
            cpuinfo = Path('/proc/cpuinfo').read_text()
        except OSError:
            cpuinfo = ''
    for line in cpuinfo.splitlines():
        key, sep, value = line.partition(':')
        if sep and key.strip() == 'model name' and value.strip():
            return value.strip()
    return platform.processor() or platform.machine() or 'unknown'


def _cpu_s(pid: int) -> float:
    """User + system CPU seconds of a live process (from /proc)."""
    fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def _self_cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def graph_rate(steps: int, place: bool = True) -> dict[str, Any]:
    """Steady-state steps/s, CPU ms/step per process and deliveries/step of the recorded six-node graph (``place``:
    its node processes placed as the launcher places them, :mod:`acds_runtime.placement`; else by the OS)."""
    from acds_common import topics
    from acds_common.graph import MONITOR_LAG
    from acds_common.scenario import load_scenario
    from acds_runtime.launcher import GraphRun

    sc = load_scenario(SCENARIO)
    skip = steps // 10
    # The last mark while every node process lives: the monitor takes in step k with the nodes at most MONITOR_LAG
    # steps ahead, and they leave after the last step (a mark at the last step read the /proc of a node gone).
    last = steps - 2 - MONITOR_LAG
    marks: dict[str, Any] = {}
    work = Path(tempfile.mkdtemp(prefix='acds_bench_'))
    graph = GraphRun(sc, work / 'run', steps=steps, echo=lambda _l: None, record=work / 'bag', place=place)

    def sample() -> dict[str, float]:
        cpu = {name: _cpu_s(p.popen.pid) for name, p in graph.processes.items()}
        cpu['launcher (monitor + recorder)'] = _self_cpu_s()
        return cpu

    def progress(k: int, _total: int, wall: float) -> None:
        if k == skip:
            marks['t0'], marks['cpu0'] = wall, sample()
        elif k == last and 't1' not in marks:
            marks['t1'], marks['cpu1'] = wall, sample()
            mon = graph.monitor
            assert mon is not None
            subs = {name: mon.node.count_subscribers(name) for name in [*mon.topics, topics.CLOCK]}
            marks['by_topic'] = {name: mon.count(name) * n / max(1, k) for name, n in subs.items()}

    graph.progress = progress
    try:
        with graph:
            graph.wait()
    finally:
        shutil.rmtree(work, ignore_errors=True)
    span = last - skip
    wall = marks['t1'] - marks['t0']
    cpu = {name: 1e3 * (marks['cpu1'][name] - marks['cpu0'][name]) / span for name in marks['cpu0']}
    by_topic = dict(sorted(marks['by_topic'].items(), key=lambda item: (-item[1], item[0])))
    return {'steps_per_s': span / wall, 'cpu_ms_per_step': cpu, 'deliveries_per_step': sum(by_topic.values()),
            'deliveries_by_topic': by_topic, 'hops': len(graph.processes), 'placement': graph.placement}


def bare_chain_rate(hops: int, cycles: int, place: bool = False) -> float:
    """Cycles/s of a ring of ``hops`` rclpy processes relaying one message (the graph's QoS and executor; ``place``:
    its processes placed by the launcher's rule, :func:`acds_runtime.placement.chain_shape`, else by the OS)."""
    from acds_common.lockstep import CPU_ENV
    from acds_runtime.launcher import FASTDDS_PROFILE, DomainLease
    from acds_runtime.placement import chain_shape, placement_cpus
    from acds_runtime.placement import place as place_on

    cpus = placement_cpus() if place else None
    plan = place_on(chain_shape(str(i) for i in range(hops)), cpus) if cpus else {}
    lease = DomainLease()
    env = dict(os.environ, ROS_DOMAIN_ID=str(lease.domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               FASTRTPS_DEFAULT_PROFILES_FILE=str(FASTDDS_PROFILE))
    env.pop(CPU_ENV, None)
    procs = [subprocess.Popen([sys.executable, '-m', 'acds_cli.bare_chain', str(i), str(hops), str(cycles)],
                              env=dict(env, **{CPU_ENV: str(plan[str(i)])}) if str(i) in plan else env,
                              stdout=subprocess.PIPE,
                              text=True) for i in range(hops)]
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


def direct_rate(steps: int) -> dict[str, Any]:
    """The direct engine on the scenario (no recording), with its fused loop (:mod:`acds_runtime.fused_step`) and
    without it (every step through the step program), one right after the other: steps per wall second and per CPU
    second of each, the wall seconds of the first, short run (numba's import, the compiled kernels' and the fused
    loop's load), the share of steps the loop ran and its own µs per step, and each model's fused kernel in µs per
    step (:meth:`~acds_runtime.direct.DirectRun.fused_stage_costs`: at step :data:`COST_STEP`, its inputs held)."""
    from acds_common.scenario import load_scenario
    from acds_runtime.direct import DirectRun

    t0 = time.perf_counter()
    DirectRun(load_scenario(SCENARIO), steps=COST_STEP).run()
    load = time.perf_counter() - t0
    out: dict[str, Any] = {'load_s': load}
    for fused in (True, False):
        run = DirectRun(load_scenario(SCENARIO), steps=steps, fused=fused)
        cpu0 = time.process_time()
        result = run.run()
        out[fused] = (result.steps / result.wall_seconds, result.steps / (time.process_time() - cpu0))
        if run.fused_loop is not None:
            out['fused_share'] = run.fused_loop.fused_steps / result.steps
            out['loop_us'] = run.fused_loop.compiled_s / max(run.fused_loop.fused_steps, 1) * 1e6
    out['models_us'] = DirectRun(load_scenario(SCENARIO), steps=steps).fused_stage_costs(COST_STEP, COST_REPEATS)
    return out


def dispersion_rate() -> dict[str, float]:
    """Samples per wall second and per CPU second of the fixed case-1 study, a sample's fixed cost and its draw's
    (module doc, item 5)."""
    from acds_common.scenario import load_scenario
    from acds_runtime.montecarlo import run_samples
    from acds_runtime.sampling import Sampler

    sampler = Sampler(load_scenario(SCENARIO), DISPERSION_SEED)
    cpu0 = time.process_time()
    texts = [sampler.draw(i).kept().text for i in range(DISPERSION_SAMPLES)]
    draw = time.process_time() - cpu0
    wall0, cpu0 = time.perf_counter(), time.process_time()
    summaries, _ = run_samples(texts, progress=False)
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    failed = [s['error'] for s in summaries if 'error' in s]
    if failed:
        raise RuntimeError(f'dispersion benchmark: a sample failed: {failed[0]}')
    cpu0 = time.process_time()
    run_samples(texts, steps=1, progress=False)
    fixed = time.process_time() - cpu0
    return {'per_s': DISPERSION_SAMPLES / wall, 'per_cpu_s': DISPERSION_SAMPLES / cpu,
            'overhead_ms': 1e3 * fixed / DISPERSION_SAMPLES, 'draw_ms': 1e3 * draw / DISPERSION_SAMPLES}


def fsw_sample_cost() -> tuple[float, float]:
    """Overhead (s) of a flight-software sample and its steps/s beyond it (module doc, item 6)."""
    import statistics

    from acds_common.scenario import load_scenario
    from acds_runtime.flight_software import FswCommand, FswSpec, run_fsw_sample
    from acds_runtime.sampling import Sampler

    text = Sampler(load_scenario(FSW_SCENARIO), DISPERSION_SEED).draw(0).text
    with tempfile.TemporaryDirectory(prefix='acds_bench_fsw_') as folder:
        spec = FswSpec(FswCommand.parse(FSW_COMMAND), (FSW_NODE,), folder)

        def wall(steps: int) -> float:
            t0 = time.perf_counter()
            summary = run_fsw_sample(spec, text, steps)
            if 'error' in summary:
                raise RuntimeError(f'flight-software sample benchmark: the sample failed: {summary["error"]}')
            return time.perf_counter() - t0
        overhead = statistics.median(wall(FSW_SHORT_STEPS) for _ in range(FSW_REPEATS))
        long = wall(FSW_STEPS)
    return overhead, (FSW_STEPS - FSW_SHORT_STEPS) / max(1e-9, long - overhead)


def core_rate(steps: int) -> tuple[float, float]:
    """Steps per wall second and per CPU second of the rigid body + environment kernel alone (the scenario's body,
    orbit, field, substeps)."""
    import numpy as np
    from acds_common import kernels
    from acds_common.scenario import load_scenario
    from dynamics.configuration import RIGID_BODY_SECTIONS, build_rigid_body

    kernels.enable()
    sc = load_scenario(SCENARIO)
    model = build_rigid_body(*(sc.values[s] for s in RIGID_BODY_SECTIONS))
    dipole, zero = np.array([100.0, -50.0, 20.0]), np.zeros(3)
    dt = sc.control_period_s
    t0, cpu0 = time.perf_counter(), time.process_time()
    for _ in range(steps):
        model.advance(dt, dipole, zero, zero)
        model.truth(zero)
    return steps / (time.perf_counter() - t0), steps / (time.process_time() - cpu0)


#: Entry-point group of modules adding figures to the bench: each has ``bench(args) -> (JSON fields, printed lines)``.
BENCH_ENTRY_POINTS = 'acds.bench'


def _bench_modules() -> list:
    from importlib.metadata import entry_points
    return [ep.load() for ep in sorted(entry_points(group=BENCH_ENTRY_POINTS), key=lambda e: e.name)]


def main(args: argparse.Namespace) -> int:
    """Run the measurements and print them (``--json``: last line one JSON object)."""
    from acds_common.numeric_config import numeric_configuration
    from acds_runtime.placement import describe, placement_cpus

    simd = numeric_configuration()['simd']

    graph = graph_rate(args.steps)
    bare = bare_chain_rate(graph['hops'], args.steps)
    # Placed on two CPUs as the launcher places a graph: the graph both ways, the ring both ways (the same rule puts
    # a ring, a chain with nothing beside it, on one CPU), side by side.
    placed = placement_cpus() is not None
    graph_os = graph_rate(args.steps, place=False)['steps_per_s'] if placed else None
    bare_placed = bare_chain_rate(graph['hops'], args.steps, place=True) if placed else None
    measured = direct_rate(max(args.steps, 5000))
    (direct, direct_cpu), (unfused, unfused_cpu) = measured[True], measured[False]
    kernel_load, models = measured['load_s'], measured['models_us']
    core, core_cpu = core_rate(max(args.steps, 5000))
    dispersion = dispersion_rate()
    fsw_overhead, fsw_rate = fsw_sample_cost()
    result = {'graph_steps_per_s': round(graph['steps_per_s'], 1), 'bare_chain_steps_per_s': round(bare, 1),
              'ratio': round(graph['steps_per_s'] / bare, 3), 'hops': graph['hops'],
              'placement': describe(graph['placement']) if graph['placement'] else None,
              'graph_os_placed_steps_per_s': None if graph_os is None else round(graph_os, 1),
              'ratio_os_placed': None if graph_os is None else round(graph_os / bare, 3),
              'bare_chain_placed_steps_per_s': None if bare_placed is None else round(bare_placed, 1),
              'ratio_placed': None if bare_placed is None else round(graph['steps_per_s'] / bare_placed, 3),
              'deliveries_per_step': round(graph['deliveries_per_step'], 2),
              'deliveries_by_topic': {k: round(v, 2) for k, v in graph['deliveries_by_topic'].items()},
              'direct_steps_per_s': round(direct, 1), 'direct_steps_per_cpu_s': round(direct_cpu, 1),
              'direct_kernel_load_s': round(kernel_load, 3),
              'direct_unfused_steps_per_s': round(unfused, 1), 'direct_unfused_steps_per_cpu_s': round(unfused_cpu, 1),
              'direct_fused_share': round(measured.get('fused_share', 0.0), 4),
              'fused_loop_us_per_step': round(measured.get('loop_us', 0.0), 3),
              'fused_us_per_model': {name: round(us, 3) for name, us in models.items()},
              'core_steps_per_s': round(core, 1), 'core_steps_per_cpu_s': round(core_cpu, 1),
              'direct_kernel_ratio': round(direct / core, 3), 'direct_kernel_ratio_cpu': round(direct_cpu / core_cpu, 3),
              'dispersion_samples_per_s': round(dispersion['per_s'], 3),
              'dispersion_samples_per_cpu_s': round(dispersion['per_cpu_s'], 3),
              'dispersion_sample_overhead_ms': round(dispersion['overhead_ms'], 2),
              'dispersion_draw_ms': round(dispersion['draw_ms'], 2),
              'fsw_sample_overhead_s': round(fsw_overhead, 3), 'fsw_sample_steps_per_s': round(fsw_rate, 1),
              'cores': os.cpu_count(), 'cpu_model': cpu_model(), 'simd': simd,
              'cpu_ms_per_step': {k: round(v, 3) for k, v in graph['cpu_ms_per_step'].items()},
              'load_average': [round(x, 2) for x in os.getloadavg()]}
    print(f'six-node graph ({SCENARIO}, recording on):    {graph["steps_per_s"]:10.1f} steps/s'
          + (f'  (placed: {describe(graph["placement"])})' if graph['placement'] else '  (placed by the OS)'))
    for name, ms in graph['cpu_ms_per_step'].items():
        print(f'    CPU {name:34s} {ms:8.3f} ms/step')
    print(f'deliveries per step:                              {graph["deliveries_per_step"]:10.2f}')
    for name, n in graph['deliveries_by_topic'].items():
        print(f'    {name:45s} {n:6.2f}')
    print(f'bare rclpy ring ({graph["hops"]} processes):                 {bare:10.1f} cycles/s')
    print(f'ratio graph / bare ring:                          {graph["steps_per_s"] / bare:10.3f}')
    if graph_os is not None and bare_placed is not None:
        print(f'six-node graph placed by the OS:                  {graph_os:10.1f} steps/s  (ratio to the ring '
              f'{graph_os / bare:.3f})')
        print(f'bare ring placed by the same rule (one CPU):      {bare_placed:10.1f} cycles/s  (ratio of the placed '
              f'graph to it {graph["steps_per_s"] / bare_placed:.3f})')
    print(f'direct engine (one process, no DDS):              {direct:10.1f} steps/s  ({direct_cpu:.1f} per CPU s; '
          f'{kernel_load:.2f} s once per process to load its compiled kernels)')
    print(f'direct engine without the fused loop:             {unfused:10.1f} steps/s  ({unfused_cpu:.1f} per CPU s)')
    print(f'fused loop: {measured.get("fused_share", 0.0):.1%} of the steps, {measured.get("loop_us", 0.0):.2f} µs per '
          'step inside it; each model\'s kernel alone, µs per step:')
    for name, us in models.items():
        print(f'    {name:44s} {us:8.3f}')
    print(f'rigid body + environment kernel:                  {core:10.1f} steps/s  ({core_cpu:.1f} per CPU s)')
    print(f'ratio direct engine / kernel:                     {direct / core:10.3f}  ({direct_cpu / core_cpu:.3f} per CPU s)')
    print(f'dispersion ({DISPERSION_SAMPLES} case-1 samples to capture, direct): {dispersion["per_s"]:10.3f} samples/s '
          f'({dispersion["per_cpu_s"]:.3f} per CPU s; a sample\'s fixed cost {dispersion["overhead_ms"]:.1f} CPU ms, '
          f'its draw {dispersion["draw_ms"]:.1f} CPU ms)')
    print(f'flight-software sample ({FSW_SCENARIO}, the example node started per sample): {fsw_overhead:.2f} s '
          f'overhead per sample (graph + node started, joined, stopped), then {fsw_rate:.1f} steps/s')
    for module in _bench_modules():  # other packages' figures (entry-point group acds.bench)
        fields, lines = module.bench(args)
        result.update(fields)
        for line in lines:
            print(line)
    print(f'machine: {os.cpu_count()} cores ({result["cpu_model"]}; numpy SIMD {simd}), load average '
          f'{", ".join(f"{x:.2f}" for x in os.getloadavg())}')
    if args.json:
        print(json.dumps(result))
    return 0
