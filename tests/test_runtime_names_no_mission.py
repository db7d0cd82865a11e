"""The runtime and the CLI name no mission, no seed system and no mission topic: the missions are plug-ins of
their packages (docs/architecture.md "Adding a mission"; :mod:`acds_common.plugins`).

Every source file of ``acds_runtime`` and ``acds_cli`` is searched (case-insensitive) for the names of the
shipped missions and their seed systems (:data:`WORDS`) and for the mission topics of
:mod:`acds_common.topics` (:data:`MISSION_TOPICS`: a topic only one mission's nodes publish; the common
truth, sensor, wheel, magnetometer, dipole and mode topics are the mechanism's). ``formation`` is not in the
list: several vehicles in one graph is a feature of the mechanism (:mod:`acds_common.graph`'s vehicle
namespaces, ``Scenario.formation``), not of one mission.
"""

from __future__ import annotations

import re
from pathlib import Path

from acds_common import topics

ROOT = Path(__file__).resolve().parents[1]
SOURCES = [ROOT / 'ros_ws' / 'src' / 'acds_runtime' / 'acds_runtime', ROOT / 'ros_ws' / 'src' / 'acds_cli' / 'acds_cli']
#: Missions and seed systems: HEAO (seed 002), SSS (001), AAP / Skylab Workshop CMG dump (000), OreSat (003),
#: EMFF (004) and their subsystems (cold gas, CMGs, torque rods, the torque meter, spin mechanizations, airtrack).
WORDS = (r'heao', r'\bsss', r'\baap\b', r'workshop', r'skylab', r'oresat', r'emff', r'cold[ _-]gas', r'gn₂',
         r'\bcmgs?\b', r'torque[ _-]rods?', r'torque[ _-]meter', r'mechanizations?\b', r'airtrack')
#: Topics only one mission's nodes publish (their constants in acds_common.topics).
MISSION_TOPICS = ('CMG_TORQUE', 'SAMPLED_MOMENTUM', 'GAS_ON_TIME', 'COLD_GAS_WRENCH', 'COLD_GAS_STATE', 'COIL_POWER',
                  'COIL_DUTY', 'TRUTH_WRENCH')
PATTERN = re.compile('|'.join([*WORDS, *(rf'\b{c}\b' for c in MISSION_TOPICS),
                               *(re.escape(getattr(topics, c)) for c in MISSION_TOPICS)]), re.IGNORECASE)


def _hits() -> dict[str, list[str]]:
    found: dict[str, list[str]] = {}
    for base in SOURCES:
        for path in sorted(base.rglob('*.py')):
            if '__pycache__' in path.parts:  # generated at run time (the fused loops, composed from a graph's nodes)
                continue
            lines = [f'{i}: {line.strip()}' for i, line in enumerate(path.read_text().splitlines(), 1)
                     if PATTERN.search(line)]
            if lines:
                found[str(path.relative_to(base.parent))] = lines
    return found


def test_the_runtime_and_the_cli_name_no_mission():
    hits = {f: lines[:3] for f, lines in _hits().items()}
    assert not hits, f'mission names in the runtime or the CLI: {hits}'


if __name__ == '__main__':
    for file, lines in _hits().items():
        print(file, *lines, sep='\n  ')
