"""Duty-cycle curve tool: measured bridge-switch duty and switching frequency vs coil current (spec §6).

Reproduces the kind of plot of seed 002 Fig. 4-10 from the simulated waveform
(not from the formula): for each commanded current the coil is run from rest
until settled in the ±ε band, then the duty cycle and the switching frequency
are measured over whole switching cycles (between the first and the last
off→on edge). The corrected eq. 4-28 is shown beside it for comparison.
Constants are those of Fig. 4-10: E = 28 V, V_ces = 0.35 V, R_L = 30 Ω,
ED = 0.6 V, ε = 0.01, with L = 20.3 H (Table 4-3).

The table and its plots are printed and drawn by ``acds duty-curve`` (``heao_mission.duty_curve_cli``).
"""

from __future__ import annotations

import numpy as np

from em_driver.bridge_switch import BridgeSwitchCoil, CoilParams, DriverParams, Waveform, duty_cycle_closed_form

__all__ = ['FIG_4_10_COIL', 'FIG_4_10_DRIVER', 'sweep_currents_a', 'measure_duty', 'duty_table', 'step_response']

#: Fig. 4-10 coil: R_L = 30 Ω (the figure's value), L = 20.3 H (Table 4-3).
FIG_4_10_COIL = CoilParams(resistance_ohm=30.0, inductance_h=20.3)
#: Fig. 4-10 driver constants.
FIG_4_10_DRIVER = DriverParams(supply_v=28.0, v_ces_v=0.35, diode_drop_v=0.6, epsilon=0.01)


def sweep_currents_a() -> np.ndarray:
    """The swept command currents, A: 0.05 to 0.85 A in 0.05 A steps (17 points)."""
    return np.round(np.arange(1, 18) * 0.05, 10)


def measure_duty(i_c_a: float, coil: CoilParams = FIG_4_10_COIL, driver: DriverParams = FIG_4_10_DRIVER,
                 settle_s: float | None = None, cycles: int = 20, max_window_s: float = 20.0) -> tuple[float, float]:
    """Measured (duty 0…1, switching frequency Hz) for command i_c_a (A) from the simulated waveform.

    Runs from rest for settle_s (default 8·τ, well past the rise into the band),
    then records in chunks until ``cycles`` whole switching cycles are seen or
    max_window_s (s) elapses. No switching at all means saturation: (1.0, 0.0)
    if the bridge stayed on, (0.0, 0.0) if it stayed off.
    """
    unit = BridgeSwitchCoil(coil, driver)
    unit.run(i_c_a, 8.0 * coil.tau_s if settle_s is None else settle_s)
    chunk_s = 0.25
    rising: list[float] = []
    falling: list[float] = []
    elapsed = 0.0
    was_on = unit.bridge_on
    while len(rising) < cycles + 1 and elapsed < max_window_s:
        wave = unit.run(i_c_a, chunk_s, record=True, record_step_s=chunk_s).waveform
        assert wave is not None
        for t, on in zip(wave.times_s[:-1], wave.bridge_on[:-1], strict=True):
            if on != was_on:
                (rising if on else falling).append(elapsed + float(t))
                was_on = bool(on)
        elapsed += chunk_s
    if len(rising) < 2:
        return (1.0 if unit.bridge_on else 0.0), 0.0
    start, end = rising[0], rising[-1]
    on_time = 0.0
    for t_up in rising[:-1]:
        t_down = next(t for t in falling if t > t_up)
        on_time += t_down - t_up
    span = end - start
    return on_time / span, (len(rising) - 1) / span


def duty_table(coil: CoilParams = FIG_4_10_COIL,
               driver: DriverParams = FIG_4_10_DRIVER) -> list[tuple[float, float, float, float, float]]:
    """Rows (current A, measured duty, measured Hz, eq. 4-28 duty, eq. 4-28 Hz)."""
    rows = []
    for i_c in sweep_currents_a():
        duty, freq = measure_duty(float(i_c), coil, driver)
        duty_eq, freq_eq = duty_cycle_closed_form(float(i_c), coil, driver)
        rows.append((float(i_c), duty, freq, duty_eq, freq_eq))
    return rows


def step_response(i_step_a: float = 0.5, duration_s: float = 4.0, coil: CoilParams = FIG_4_10_COIL,
                  driver: DriverParams = FIG_4_10_DRIVER) -> Waveform:
    """The recorded waveform of a command step 0 → ``i_step_a`` (A) from rest over ``duration_s`` (s)."""
    wave = BridgeSwitchCoil(coil, driver).run(i_step_a, duration_s, record=True, record_step_s=1e-4).waveform
    assert wave is not None
    return wave
