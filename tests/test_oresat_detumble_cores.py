"""OreSat detumble through the pure cores, without ROS (seed 003): the designed rods and the
B̂×ω law take an OreSat-like 2U CubeSat from 5°/s per axis toward rest (``tests/oresat_core_loop.py``
states the mass properties, orbit and rods). Ten minutes of sim time at the 1 s control period."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np

_spec = importlib.util.spec_from_file_location('oresat_core_loop', Path(__file__).with_name('oresat_core_loop.py'))
core_loop = sys.modules.setdefault('oresat_core_loop', importlib.util.module_from_spec(_spec))
_spec.loader.exec_module(core_loop)


def test_designed_rods_and_law_reduce_the_tumble_rate() -> None:
    run = core_loop.run(steps=600, dt_s=1.0, record_every=100)
    omega = np.array(run.omega_rad_s)
    rate = np.linalg.norm(omega, axis=1)
    energy = 0.5 * np.einsum('ni,ij,nj->n', omega, core_loop.INERTIA_KG_M2, omega)
    assert rate[0] == np.linalg.norm(core_loop.OMEGA0_RAD_S)
    assert rate[-1] < 0.7 * rate[0]
    assert np.all(np.diff(energy) < 0.0)
    assert run.energy_j > 0.0 and 0.0 < run.peak_current_a <= core_loop.ROD_REQUEST.full_current_a
