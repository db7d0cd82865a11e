"""The built-in pair of a bus scenario (``montecarlo --paired`` on the bus, :func:`canopen_bus.run_plugin.built_in`):
``oresat_c3_detumble`` with the cards given way to the magnetometer and the built-in law is ``oresat_detumble``
itself, truth digest for truth digest, once the step and the substeps are that scenario's."""

from __future__ import annotations

import yaml
from acds_common.scenario import load_scenario
from acds_runtime.direct import DirectRun
from acds_runtime.sampling import scenario_from_text
from canopen_bus.run_plugin import built_in

STEPS = 200


def test_the_built_in_pair_of_the_c3_scenario_is_oresat_detumble():
    raw = dict(load_scenario('oresat_c3_detumble').raw)
    reference = load_scenario('oresat_detumble')
    raw.update(control_period_s=reference.raw['control_period_s'], duration_orbits=reference.raw['duration_orbits'],
               dynamics=reference.raw['dynamics'])
    raw.pop('duration_s')
    pair = built_in(raw)
    assert pair is not None and 'can_bus' not in pair
    assert pair['nodes'] == reference.raw['nodes'] and pair['em_driver'] == reference.raw['em_driver']
    ours = DirectRun(scenario_from_text(yaml.safe_dump(pair, sort_keys=False)), steps=STEPS).run().summary
    assert ours['truth_digest'] == DirectRun(reference, steps=STEPS).run().summary['truth_digest']


def test_a_scenario_without_the_cards_has_no_built_in_pair():
    assert built_in(dict(load_scenario('oresat_detumble').raw)) is None
