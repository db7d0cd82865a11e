"""``acds info``: a bag's topics, types, counts, sim-time span and the run's scenario."""

from __future__ import annotations

from pathlib import Path

import yaml
from acds_runtime.bag.coverage import GAPS_KEY, describe
from acds_runtime.bag.reader import open_bag


def bag_info(bag_path: Path | str, *, scenario: bool = True) -> str:
    """The text ``acds info`` prints (counts, spans and types gathered in one streaming pass)."""
    bag = open_bag(bag_path)
    stats = bag.stats()
    t0, t1 = bag.span_ns()
    size = sum(f.stat().st_size for f in bag.files)
    lines = [f'bag:        {bag.path}',
             f'storage:    {bag.storage} ({size / 2**20:.2f} MiB), rosbag2 metadata version 9',
             f'sim time:   {t0 / 1e9:.3f} s … {t1 / 1e9:.3f} s ({(t1 - t0) / 60e9:.2f} min)',
             f'messages:   {bag.total} on {len(bag.types)} topics']
    if bag.info.get('scenario_name'):
        lines.append(f'scenario:   {bag.info["scenario_name"]} ({bag.info.get("steps", "?")} steps of '
                     f'{bag.info.get("control_period_s", "?")} s; nodes {bag.info.get("nodes", "?")})')
    if bag.unclosed is not None:
        lines.append(f'unclosed:   read {bag.unclosed}, without changing it (acds recover writes a repaired copy)')
    if 'recovered' in bag.info:
        lines.append(f'recovered:  {bag.info["recovered"]}')
    gaps = describe(bag.info.get(GAPS_KEY))
    if gaps is not None:
        lines.append(f'gaps:       {gaps}')
    pubs = yaml.safe_load(bag.info.get('publishers', '') or '{}') or {}
    width = max((len(t) for t in bag.types), default=10)
    lines.append('')
    lines.append(f'{"topic":{width}s}  {"type":38s} {"count":>7s}  {"first s":>9s} {"last s":>9s}  publishers')
    for topic in sorted(bag.types):
        s = stats.get(topic)
        first = f'{s.first_ns / 1e9:9.2f}' if s else ' ' * 9
        last = f'{s.last_ns / 1e9:9.2f}' if s else ' ' * 9
        lines.append(f'{topic:{width}s}  {bag.types[topic]:38s} {bag.count(topic):7d}  {first} {last}  '
                     f'{", ".join(pubs.get(topic, []))}')
    if scenario and bag.info.get('scenario'):
        lines += ['', '--- scenario (as run) ---', bag.info['scenario'].rstrip()]
    return '\n'.join(lines)
