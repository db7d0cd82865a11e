"""The mode sets, one definition each: the mode manager commands them, the controller obeys them, the
scenario starts in one of them (spec §8; seed 002 §4.3 for HEAO, seed 000 for the AAP Workshop).

The mode names travel as text in the ``mode`` status (:mod:`acds_common.messages`); these tuples are the
vocabulary both ends check against.
"""

from __future__ import annotations

#: HEAO DPA modes (seed 002 §4.3): acquisition Mode 1A (magnetics only), Mode 1B (wheels + magnetics), cruise.
HEAO_MODES = ('standby', 'mode_1a', 'mode_1b', 'celestial_scan', 'celestial_point')
#: The HEAO cruise modes (after acquisition capture).
HEAO_CRUISE_MODES = ('celestial_scan', 'celestial_point')
#: A HEAO mode as a compiled kernel reads it (:mod:`acds_common.kernels`: no strings inside): its index in HEAO_MODES.
HEAO_MODE_INDEX = {mode: i for i, mode in enumerate(HEAO_MODES)}
STANDBY, MODE_1A, MODE_1B, CELESTIAL_SCAN, CELESTIAL_POINT = (HEAO_MODE_INDEX[m] for m in (
    'standby', 'mode_1a', 'mode_1b', 'celestial_scan', 'celestial_point'))
#: Modes in which the cold-gas thrusters fly the spacecraft (seed 002 §3.1: sun acquisition and reacquisition on
#: gas): rate damping on the gyros, then sun acquisition on the sun sensor and gyros. The heao_cold_gas mode logic
#: sequences them and hands over to the wheels (Mode 1B); the controller's gas law runs in them.
GAS_MODES = ('gas_rate_damping', 'gas_sun_acquisition')
#: AAP Workshop computer modes (seed 000): CMG attitude hold, hold with the magnetic momentum dump, standby.
WORKSHOP_MODES = ('standby', 'cmg_hold', 'cmg_dump')
#: The Workshop modes a run may start in (``modes.initial_mode`` of ``modes.system: aap``): standby is a
#: mode the ground commands, not one the Workshop is launched into (and the HEAO logic starts in it too).
WORKSHOP_INITIAL_MODES = ('cmg_hold', 'cmg_dump')
#: Every ``modes.initial_mode`` a scenario may give.
INITIAL_MODES = (*HEAO_MODES, *WORKSHOP_INITIAL_MODES, *GAS_MODES)
