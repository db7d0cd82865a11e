"""CubeSat torque rods: ferromagnetic core + dual winding + PWM H-bridge from the 7.2 V bus (spec §9; seed 003).

Seed: 003_oresat_magnetorquers.md ("Constraints", "Material Selection", "Design"): a torque
rod is "a ferromagnetic cylinder wound with an excitation coil"; electrically "a serial
connection of resistor, inductor …, mathematically modeled with a single current loop";
7.2 V bus, 0.5 W and < 100 g each, "dual wounds of coil in case of single point of failure",
36 AWG wire, cores of CK30, Permendur or Permalloy.

Magnetics (SI; one winding of n turns carrying i, the other winding on the same core):

* Core: a cylinder of length l and radius r, treated as the prolate spheroid of the same
  length and diameter (uniform magnetisation M). Demagnetising factor along the axis,
  Osborn (Phys. Rev. 67, 351, 1945) / Stoner (Phil. Mag. 36, 803, 1945), with m = l/(2r):
  N_d = [m·ln(m + √(m²−1))/√(m²−1) − 1]/(m² − 1) (m > 1; the oblate form for m < 1; 1/3
  at m = 1, → 0 as m → ∞). The seed's ref. [4] formula 4[ln(l/r) − 1]/[(l/r)² − 4 ln(l/r)]
  (:func:`demagnetizing_factor_seed`) is the long-rod asymptote of the same thing: it agrees
  within 2 % from l/r = 20 (0.5 % at 40) but is zero at l/r = e and negative below (−1 at l/r = 2).
* Applied field of the winding (long solenoid): H_a = n·i/l. Inside the core
  H_in = H_a − N_d·M, M = χ·H_in with χ = µ_r − 1, so M = χ_app·H_a with the apparent
  susceptibility χ_app = χ/(1 + N_d·χ) (seed 002 Appendix's µ' = µ/(1 + (µ−1)L)).
* Dipole: air-core part i·Σπr_j² over the turns (the winding's own loops) plus the core's
  M·V_core. In the thin-winding limit this is the seed's
  M = n·i·πr²·[1 + (µ_r − 1)/(1 + N_d(µ_r − 1))].
* Saturation: the core magnetisation is linear up to the point where the core flux density
  B = µ0(H_in + M) = µ0·µ_r·H_a/(1 + N_d·χ) reaches the material's B_sat, and constant beyond
  (negligible coercivity and a linear region, as the seed requires of the material:
  anhysteretic, piecewise linear). The seed's flux-density formula
  B = µ0 n I/(l_c(N_d + (l_c − N_d)/µ_r)) has a typo: (1 − N_d), not (l_c − N_d) (it is
  the same B as above, divided through by µ_r).
* Winding: both windings wound together (bifilar) in layers of round wire at pitch d_ins
  (insulated diameter), square packing, spanning the core length; turns and radii follow
  from the wire length exactly for whole layers (continuous in between). Wire length
  l_w = R/W_w, W_w the wire's Ω/m (seed "Design"). Identical bifilar windings have identical
  R and L; the unpowered one's bridge is high-impedance (EMF ≤ V < V + 2·V_diode), so it
  carries no current unless it was carrying some when it was switched off.
* Inductance of one winding: L = µ0·n/l·[Σ_j πr_j² + n·(1 − N_d)·χ_app·πr²] (flux of H_a
  through every turn plus the core's flux µ0(1 − N_d)M·πr²); thin-winding limit
  µ0·n²·πr²·µ_r/(l(1 + N_d(µ_r − 1))), the seed's L with (µ_r − 1) for µ_r in the N_d term.
  L is the unsaturated value (the core's incremental permeability falls when it saturates;
  designs from ``torque_rod_design`` keep the core unsaturated at full current by default).

Electronics (:class:`PwmDriverParams`): each winding has its own H-bridge on the 7.2 V bus,
driven by PWM with slow (synchronous) decay: on-phase the bus V across the winding plus the
two conducting MOSFETs (R_bridge), off-phase the winding shorted through the two low-side
MOSFETs, so the loop resistance R + R_bridge and τ = L/(R + R_bridge) are the same in both
phases and the period-average current is exactly D·V/(R + R_bridge) in steady state (linear
in duty; reversal passes through zero because the MOSFETs conduct both ways). The RL circuit
is integrated exactly between edges (``rl_circuit``), whole periods in closed form.
PWM at 20 kHz with 10-bit duty: 20 kHz is far above the rods' 1/(2πτ) (τ of a few ms: the
peak-to-peak ripple ≈ (V/R)·D(1 − D)·T/τ is at most 0.7 % of full scale for τ = 1.8 ms, and
the dipole averages it exactly), inside the
50 kHz limit of small integrated H-bridges of the DRV8833 class (HS + LS R_DS(on) 0.36 Ω
typ., V_M 2.7–10.8 V), and 10 bits need only a 20.5 MHz timer clock; a step of 1/1024 of
full scale is 0.07 mA for a 0.5 W rod. A disabled bridge (unpowered or dead) leaves the
winding's current to decay through two body diodes back into the bus
(−(V + 2·V_diode) across the winding, winding resistance only) until zero.

The assembly (:class:`TorqueRodAssembly`) has the HEAO drive assembly's interface
(``step(moment_command_am2, dt_s) -> AssemblyResult``, ``select_eea``, ``inject_failure``,
``unit_fault``, ``active_units``) so the em_driver node can host it as a driver kind.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import NamedTuple

import numpy as np
from acds_common.units import MU0

from em_driver import rl_circuit
from em_driver.bridge_switch import CoilFault, EmDriverError
from em_driver.drive_assembly import UNITS, AssemblyResult, alarm_events, axis_of, standby_unit

__all__ = [
    'CoreMaterial',
    'CORE_MATERIALS',
    'MagnetWire',
    'magnet_wire',
    'demagnetizing_factor',
    'demagnetizing_factor_seed',
    'RodProperties',
    'rod_properties',
    'TorqueRod',
    'PwmDriverParams',
    'TorqueRodWinding',
    'TorqueRodAssembly',
]


# ------------------------------------------------------------------------------------------ materials


@dataclass(frozen=True)
class CoreMaterial:
    """Soft-magnetic core material (seed 003 "Material Selection").

    relative_permeability: µ_r of the linear region (dimensionless).
    saturation_t: B_sat, T. density_kg_m3: kg/m³. source: where the numbers come from.
    """

    name: str
    relative_permeability: float
    saturation_t: float
    density_kg_m3: float
    source: str

    def __post_init__(self) -> None:
        if not (self.relative_permeability >= 1.0 and self.saturation_t > 0.0 and self.density_kg_m3 > 0.0):
            raise EmDriverError(f'core material {self.name!r}: need µ_r >= 1, B_sat > 0 T, density > 0 kg/m³')


#: The seed's three core options. Numbers and their sources (the seed lists the materials only,
#: and gives ρ = 8.74 g/cm³ and µ = 100,000 for "permalloy 80" in its notebook).
CORE_MATERIALS: dict[str, CoreMaterial] = {
    'permalloy': CoreMaterial(
        'permalloy', 1.0e5, 0.75, 8740.0,
        '80 % Ni–Fe(–Mo) permalloy: B_s 0.75 T (PML India Ni–Fe alloy table: 80 % NiFe 0.75 T, µ_max 570,000); '
        'µ_r 100,000 and ρ 8.74 g/cm³ from the seed notebook (conservative against µ_max)'),
    'permendur': CoreMaterial(
        'permendur', 5.0e3, 2.25, 8120.0,
        'Fe–49 % Co–2 % V (vanadium permendur, the HEAO core of seed 002): B_s 2.25 T, µ_max 18,000, '
        'ρ 8.12 g/cm³ (PML India table); µ_r 5,000 taken as the amplitude permeability below µ_max'),
    'ck30': CoreMaterial(
        'ck30', 500.0, 2.0, 7850.0,
        'Ck30 / C30E carbon steel (0.3 % C), no datasheet found: B_sat 2.0 T estimated from iron’s 2.15 T '
        'diluted by ≈4.5 vol % cementite, µ_r 500 below the 4,000 of ultra-low-carbon steel (seed 004 '
        'shielding table), ρ 7.85 g/cm³; estimates, and its coercivity is not negligible'),
}


@dataclass(frozen=True)
class MagnetWire:
    """Round enamelled copper magnet wire.

    awg: gauge; bare_diameter_m, insulated_diameter_m (winding pitch), m;
    ohm_per_m: resistance per metre at 20 °C (the seed's W_w), Ω/m;
    copper_density_kg_m3, enamel_density_kg_m3: kg/m³.
    """

    awg: int
    bare_diameter_m: float
    insulated_diameter_m: float
    ohm_per_m: float
    copper_density_kg_m3: float = 8960.0
    enamel_density_kg_m3: float = 1300.0

    def __post_init__(self) -> None:
        if not (0.0 < self.bare_diameter_m < self.insulated_diameter_m and self.ohm_per_m > 0.0):
            raise EmDriverError(f'magnet wire AWG {self.awg}: need 0 < bare diameter < insulated diameter and '
                                f'Ω/m > 0, got {self.bare_diameter_m!r}, {self.insulated_diameter_m!r}, '
                                f'{self.ohm_per_m!r}')

    @property
    def mass_per_m_kg(self) -> float:
        """Copper + enamel mass per metre, kg/m."""
        a_cu = math.pi * self.bare_diameter_m ** 2 / 4.0
        a_en = math.pi * self.insulated_diameter_m ** 2 / 4.0 - a_cu
        return a_cu * self.copper_density_kg_m3 + a_en * self.enamel_density_kg_m3


#: Annealed copper (IACS) resistivity at 20 °C, Ω·m.
COPPER_RESISTIVITY_OHM_M = 1.0 / 58.0e6
#: Heavy-film (double build) minimum insulation increment on the diameter, mils (NEMA MW 1000 round
#: copper magnet wire, as tabulated in the Centelsa magnet-wire catalogue).
HEAVY_BUILD_INCREMENT_MIL = {30: 1.4, 31: 1.3, 32: 1.2, 33: 1.1, 34: 1.0, 35: 0.9, 36: 0.8, 37: 0.8,
                             38: 0.7, 39: 0.6, 40: 0.6}
_MIL_M = 25.4e-6
#: The gauges the ASTM B258 diameter formula is used for here (0 to 56 AWG).
AWG_GAUGES = range(0, 57)


def magnet_wire(awg: int, insulation_build_m: float | None = None) -> MagnetWire:
    """Magnet wire of gauge ``awg``: d = 0.127 mm·92^((36 − AWG)/39) (ASTM B258), Ω/m from IACS copper.

    36 AWG: 0.127 mm bare, 1.361 Ω/m (the seed's W_w = 0.001361 Ω/mm), 0.147 mm over the heavy
    film. ``insulation_build_m`` (diameter increase) defaults to the heavy build for AWG 30–40.
    """
    if int(awg) != awg or int(awg) not in AWG_GAUGES:
        raise EmDriverError(f'awg must be a whole gauge {AWG_GAUGES[0]}…{AWG_GAUGES[-1]}, got {awg!r}')
    awg = int(awg)
    d = 0.127e-3 * 92.0 ** ((36 - awg) / 39.0)
    if insulation_build_m is None:
        if awg not in HEAVY_BUILD_INCREMENT_MIL:
            raise EmDriverError(f'no heavy-build insulation table entry for AWG {awg} (have '
                                f'{min(HEAVY_BUILD_INCREMENT_MIL)}–{max(HEAVY_BUILD_INCREMENT_MIL)}); '
                                'give insulation_build_m')
        insulation_build_m = HEAVY_BUILD_INCREMENT_MIL[awg] * _MIL_M
    if not (math.isfinite(insulation_build_m) and insulation_build_m > 0.0):
        raise EmDriverError(f'insulation_build_m must be > 0 m, got {insulation_build_m!r}')
    return MagnetWire(awg, d, d + insulation_build_m, COPPER_RESISTIVITY_OHM_M / (math.pi * d * d / 4.0))


# ------------------------------------------------------------------------------- demagnetising factor


def demagnetizing_factor(length_m: np.ndarray | float, radius_m: np.ndarray | float) -> np.ndarray:
    """Axial demagnetising factor of a rod as the spheroid of the same length and diameter (Osborn 1945).

    m = l/(2r) (length over diameter). Prolate (m > 1):
    N = [m·arccosh(m)/√(m²−1) − 1]/(m² − 1); oblate (m < 1): N = [1 − m·arccos(m)/√(1−m²)]/(1 − m²);
    sphere N = 1/3 (the series 1/3 − 4(m−1)/15 is used within 1e-4 of m = 1, where the closed
    forms lose digits). Works on arrays.
    """
    m = np.asarray(length_m, dtype=float) / (2.0 * np.asarray(radius_m, dtype=float))
    if not np.all(np.isfinite(m) & (m > 0.0)):
        raise EmDriverError(f'rod length and radius must be finite and > 0, got aspect l/(2r) = {m!r}')
    out = np.empty_like(m)
    near = np.abs(m - 1.0) < 1e-4
    pro = (m > 1.0) & ~near
    obl = (m < 1.0) & ~near
    q = m[pro] ** 2 - 1.0
    out[pro] = (m[pro] * np.arccosh(m[pro]) / np.sqrt(q) - 1.0) / q
    p = 1.0 - m[obl] ** 2
    out[obl] = (1.0 - m[obl] * np.arccos(m[obl]) / np.sqrt(p)) / p
    out[near] = 1.0 / 3.0 - 4.0 * (m[near] - 1.0) / 15.0
    return out


def demagnetizing_factor_seed(length_m: float, radius_m: float) -> float:
    """The seed's ref. [4] rod formula N_d = 4[ln(l/r) − 1]/[(l/r)² − 4 ln(l/r)] (long-rod asymptote).

    Valid only for long rods: it is 0 at l/r = e and negative below (see the module docstring).
    """
    a = length_m / radius_m
    return 4.0 * (math.log(a) - 1.0) / (a * a - 4.0 * math.log(a))


# ---------------------------------------------------------------------------------------- the rod


class RodProperties(NamedTuple):
    """Derived quantities of a rod (floats, or arrays when the inputs are arrays); SI.

    turns: per winding; layers: of the whole (bifilar) winding; outer_radius_m: over the winding;
    resistance_ohm, inductance_h: one winding; air_moment_per_a: Σπr_j² of one winding, A·m²/A;
    core_moment_per_a: core's linear dipole per ampere of one winding, A·m²/A;
    core_max_moment_am2: core's dipole at saturation, A·m²; flux_per_a_t: core B per ampere, T/A;
    n_d: demagnetising factor; chi_app: apparent susceptibility; mass_kg: wire + core.
    """

    turns: np.ndarray
    layers: np.ndarray
    outer_radius_m: np.ndarray
    resistance_ohm: np.ndarray
    inductance_h: np.ndarray
    air_moment_per_a: np.ndarray
    core_moment_per_a: np.ndarray
    core_max_moment_am2: np.ndarray
    flux_per_a_t: np.ndarray
    n_d: np.ndarray
    chi_app: np.ndarray
    wire_mass_kg: np.ndarray
    core_mass_kg: np.ndarray
    mass_kg: np.ndarray


def rod_properties(length_m: np.ndarray | float, radius_m: np.ndarray | float, material: CoreMaterial,
                   wire: MagnetWire, wire_length_m: np.ndarray | float, windings: int = 2) -> RodProperties:
    """Every derived quantity of a rod (module docstring), vectorised over length, radius and wire length.

    ``wire_length_m`` is per winding; ``windings`` wound together (bifilar) on the core.
    """
    length = np.asarray(length_m, dtype=float)
    radius = np.asarray(radius_m, dtype=float)
    l_w = np.asarray(wire_length_m, dtype=float)
    d = wire.insulated_diameter_m
    per_layer = length / d
    # Whole layers j = 0…J−1 at radii r + (j + ½)d hold 2π·per_layer·(rJ + dJ²/2) of wire: solve for J.
    total_wire = windings * l_w
    layers = (-radius + np.sqrt(radius ** 2 + d * total_wire / (math.pi * per_layer))) / d
    turns = layers * per_layer / windings
    area_sum = math.pi * per_layer * (radius ** 2 * layers + radius * d * layers ** 2 + d ** 2 * layers ** 3 / 3.0)
    air_per_a = area_sum / windings
    n_d = demagnetizing_factor(length, radius)
    chi = material.relative_permeability - 1.0
    chi_app = chi / (1.0 + n_d * chi)
    core_area = math.pi * radius ** 2
    core_per_a = chi_app * turns * core_area  # M·V per ampere: χ_app·(n/l)·πr²·l
    mu_r = material.relative_permeability
    m_at_bsat = material.saturation_t * chi / (MU0 * mu_r)  # M where B = µ0(M/χ + M) reaches B_sat
    inductance = MU0 * turns / length * (air_per_a + turns * (1.0 - n_d) * chi_app * core_area)
    flux_per_a = MU0 * mu_r * turns / length / (1.0 + n_d * chi)
    wire_mass = total_wire * wire.mass_per_m_kg
    core_mass = core_area * length * material.density_kg_m3
    return RodProperties(turns, layers, radius + layers * d, l_w * wire.ohm_per_m, inductance, air_per_a,
                         core_per_a, m_at_bsat * core_area * length, flux_per_a, n_d, chi_app, wire_mass,
                         core_mass, wire_mass + core_mass)


@dataclass(frozen=True)
class TorqueRod:
    """One torque rod: core (length, radius, material), wire, wire length per winding, number of windings.

    All SI. ``props`` holds every derived quantity (:func:`rod_properties`).
    """

    core_length_m: float
    core_radius_m: float
    material: CoreMaterial
    wire: MagnetWire
    wire_length_per_winding_m: float
    windings: int = 2

    def __post_init__(self) -> None:
        for name in ('core_length_m', 'core_radius_m', 'wire_length_per_winding_m'):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise EmDriverError(f'TorqueRod.{name} must be a finite positive number, got {value!r}')
        if self.windings not in (1, 2):
            raise EmDriverError(f'TorqueRod.windings must be 1 or 2, got {self.windings!r}')

    @cached_property
    def props(self) -> RodProperties:
        """Derived quantities as floats."""
        p = rod_properties(self.core_length_m, self.core_radius_m, self.material, self.wire,
                           self.wire_length_per_winding_m, self.windings)
        return RodProperties(*(float(x) for x in p))

    @property
    def linear_moment_per_a(self) -> float:
        """Dipole per ampere (summed over the windings' currents) below saturation, A·m²/A."""
        return self.props.air_moment_per_a + self.props.core_moment_per_a

    @property
    def saturation_current_a(self) -> float:
        """Summed winding current at which the core saturates, A."""
        return self.props.core_max_moment_am2 / self.props.core_moment_per_a

    def moment_am2(self, current_a: np.ndarray | float) -> np.ndarray:
        """Dipole, A·m², for the summed current of the windings (same sense), A: air part + saturating core."""
        i = np.asarray(current_a, dtype=float)
        p = self.props
        return p.air_moment_per_a * i + np.clip(p.core_moment_per_a * i, -p.core_max_moment_am2,
                                                p.core_max_moment_am2)

    def current_for_moment_a(self, moment_am2: float) -> float:
        """Inverse of :meth:`moment_am2` (it is strictly increasing), A."""
        p = self.props
        m_knee = self.linear_moment_per_a * self.saturation_current_a
        if abs(moment_am2) <= m_knee:
            return moment_am2 / self.linear_moment_per_a
        return math.copysign((abs(moment_am2) - p.core_max_moment_am2) / p.air_moment_per_a, moment_am2)

    def core_flux_density_t(self, current_a: float) -> float:
        """Core flux density of the linear model, T (exceeds B_sat only if the core saturates)."""
        return self.props.flux_per_a_t * current_a


# ------------------------------------------------------------------------------------------- driver


@dataclass(frozen=True)
class PwmDriverParams:
    """H-bridge PWM driver of one winding (module docstring for the choices).

    supply_v: bus, V (7.2, seed 003). frequency_hz: PWM, Hz (20 kHz). resolution_bits: duty
    resolution (10). bridge_resistance_ohm: two conducting MOSFETs, Ω (0.36, DRV8833-class).
    diode_drop_v: body-diode forward drop, V (0.7). current_sense_gain_v_per_a: telemetry
    e_ft per ampere, V/A (20: 1.4 V at a 0.5 W rod's 69 mA; chosen, the seed has no sensor).
    """

    supply_v: float = 7.2
    frequency_hz: float = 20e3
    resolution_bits: int = 10
    bridge_resistance_ohm: float = 0.36
    diode_drop_v: float = 0.7
    current_sense_gain_v_per_a: float = 20.0

    def __post_init__(self) -> None:
        for name in ('supply_v', 'frequency_hz', 'current_sense_gain_v_per_a'):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise EmDriverError(f'PwmDriverParams.{name} must be a finite positive number, got {value!r}')
        for name in ('bridge_resistance_ohm', 'diode_drop_v'):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise EmDriverError(f'PwmDriverParams.{name} must be finite and >= 0, got {value!r}')
        if int(self.resolution_bits) != self.resolution_bits or not 1 <= self.resolution_bits <= 16:
            raise EmDriverError(f'PwmDriverParams.resolution_bits must be 1…16, got {self.resolution_bits!r}')

    def quantize(self, duty: float) -> float:
        """Signed duty rounded to the timer resolution, clipped to [−1, 1]."""
        steps = 2 ** int(self.resolution_bits)
        return math.copysign(min(round(abs(duty) * steps), steps) / steps, duty)


@dataclass(frozen=True)
class _Run:
    """One winding over one control period: end current (A), charge ∫i dt (A·s), net bus energy (J),
    PWM edges, an upper bound on |i| over the period (A) and the cumulative charge at given times."""

    end_current_a: float
    charge_as: float
    bus_energy_j: float
    switches: int
    peak_bound_a: float
    charge_at: Callable[[np.ndarray], np.ndarray] = field(repr=False)


class TorqueRodWinding:
    """One winding with its H-bridge, integrated exactly (module docstring). Keeps its current between calls."""

    def __init__(self, rod: TorqueRod, driver: PwmDriverParams) -> None:
        self.rod = rod
        self.driver = driver
        self.loop_resistance_ohm = rod.props.resistance_ohm + driver.bridge_resistance_ohm
        self.tau_s = rod.props.inductance_h / self.loop_resistance_ohm
        #: Steady current at full duty, A.
        self.full_current_a = driver.supply_v / self.loop_resistance_ohm
        self.current_a = 0.0
        self.fault: CoilFault | None = None
        #: Bridge enabled (the active unit); a disabled bridge is high-impedance.
        self.powered = True
        self._polarity = 1.0

    def set_fault(self, fault: CoilFault | str | None) -> None:
        """Inject 'open_winding', 'stuck_on_bridge' or 'dead_driver', or clear with None."""
        self.fault = CoilFault.parse(fault, 'winding')

    def run(self, duty: float, dt_s: float) -> _Run:
        """Drive at signed ``duty`` (−1…1, already quantised) for dt_s, s, as the fault and power state allow."""
        if self.fault is CoilFault.OPEN_WINDING:
            self.current_a = 0.0
            return _Run(0.0, 0.0, 0.0, 0, 0.0, lambda t: np.zeros_like(t))
        if self.fault is CoilFault.DEAD_DRIVER or not self.powered:
            return self._diode_decay(dt_s)
        if self.fault is CoilFault.STUCK_ON_BRIDGE:
            duty = self._polarity
        elif duty != 0.0:
            self._polarity = math.copysign(1.0, duty)
        run = pwm_response(self.current_a, duty, dt_s, self.full_current_a, self.tau_s, self.driver)
        self.current_a = run.end_current_a
        return run

    def _diode_decay(self, dt_s: float) -> _Run:
        """Bridge off: |i| falls toward −(V + 2·V_d)/R through the body diodes, then stays at zero."""
        i0 = self.current_a
        if i0 == 0.0:
            return _Run(0.0, 0.0, 0.0, 0, 0.0, lambda t: np.zeros_like(t))
        r = self.rod.props.resistance_ohm
        tau = self.rod.props.inductance_h / r
        i_inf = -math.copysign((self.driver.supply_v + 2.0 * self.driver.diode_drop_v) / r, i0)
        t_zero = rl_circuit.time_to_reach_s(i0, i_inf, 0.0, tau)
        t_end = min(dt_s, t_zero)
        i_end, charge = rl_circuit.segment(i0, i_inf, tau, t_end)
        self.current_a = 0.0 if t_end >= t_zero else i_end

        def charge_at(t: np.ndarray) -> np.ndarray:
            s = np.minimum(np.asarray(t, dtype=float), t_end)
            return i_inf * s + (i0 - i_inf) * tau * (1.0 - np.exp(-s / tau))

        # Current flows against the bus while the diodes conduct: energy goes back into it.
        return _Run(self.current_a, charge, -self.driver.supply_v * abs(charge), 0, abs(i0), charge_at)


def pwm_response(i0_a: float, duty: float, dt_s: float, full_current_a: float, tau_s: float,
                 driver: PwmDriverParams) -> _Run:
    """Exact PWM response over dt_s from i0_a at signed duty (slow decay), τ = tau_s, i_on = ±full_current_a.

    The duty holds from the start of the control period (the timer restarts at the update):
    whole periods in closed form (``rl_circuit.pwm_periods``), then the partial period on for
    min(D·T, remainder) and off for the rest.
    """
    period = 1.0 / driver.frequency_hz
    d = abs(duty)
    i_on = math.copysign(full_current_a, duty) if d > 0.0 else 0.0
    n = int(math.floor(dt_s / period + 1e-9))
    rem = max(0.0, dt_s - n * period)
    whole = rl_circuit.pwm_periods(i0_a, i_on, tau_s, period, d, n)
    t_on = min(d * period, rem)
    i_mid, q_on = rl_circuit.segment(whole.end_current_a, i_on, tau_s, t_on)
    i_end, q_off = rl_circuit.segment(i_mid, 0.0, tau_s, rem - t_on)
    charge = whole.area_as + q_on + q_off
    bus_energy = driver.supply_v * math.copysign(1.0, i_on) * (whole.area_on_as + q_on) if d > 0.0 else 0.0
    edges = 2 * n + (2 if 0.0 < t_on < rem else 0) if 0.0 < d < 1.0 else 0

    def charge_at(t: np.ndarray) -> np.ndarray:
        """Cumulative charge at period boundaries k·T (k ≤ n) and at dt_s (t must be one of these)."""
        t = np.asarray(t, dtype=float)
        k = np.minimum(np.rint(t / period), n)
        out = rl_circuit.pwm_cumulative_charge(i0_a, i_on, tau_s, period, d, k)
        return np.where(t >= dt_s, charge, out)

    return _Run(i_end, charge, bus_energy, edges, max(abs(i0_a), full_current_a if d > 0.0 else 0.0), charge_at)


# ----------------------------------------------------------------------------------------- assembly


class _Axis:
    """One rod: two windings (units A and B) with their bridges, and the mismatch alarm."""

    def __init__(self, rod: TorqueRod, driver: PwmDriverParams) -> None:
        self.rod = rod
        names = UNITS[:rod.windings]
        self.units = {name: TorqueRodWinding(rod, driver) for name in names}
        self.active = names[0]
        self.command = 0.0
        self.alarm = False

    @property
    def full_current_a(self) -> float:
        return self.units[self.active].full_current_a

    def duty_for(self, driver: PwmDriverParams) -> float:
        """Quantised signed duty for the held moment command (saturated at the rod's full-duty moment)."""
        i_full = self.full_current_a
        m_max = float(self.rod.moment_am2(i_full))
        m = min(max(self.command, -m_max), m_max)
        return driver.quantize(self.rod.current_for_moment_a(m) / i_full)


class TorqueRodAssembly:
    """Three torque rods (x, y, z body axes), each with two windings + H-bridges, active/standby (seed 003).

    rods: three :class:`TorqueRod` (e.g. the same design three times); driver: PWM driver of
    every winding. The moment command is saturated at each rod's full-duty moment and turned
    into a duty through the rod's moment curve (open loop: steady current D·V/(R + R_bridge)).
    Alarm (excess-coil-current / mismatch, as the HEAO telemetry): the active winding's end
    current differs from what a healthy winding would have from the same start current by more
    than ``mismatch_tolerance_frac`` of full-duty current (the rods settle within milliseconds,
    so one control period decides). With ``auto_switch_to_standby`` an alarmed axis switches to
    its other winding by itself.
    """

    def __init__(self, rods: Sequence[TorqueRod], driver: PwmDriverParams | None = None,
                 auto_switch_to_standby: bool = False, mismatch_tolerance_frac: float = 0.1) -> None:
        if len(rods) != 3:
            raise EmDriverError(f'TorqueRodAssembly needs exactly 3 rods, got {len(rods)}')
        if not (math.isfinite(mismatch_tolerance_frac) and 0.0 < mismatch_tolerance_frac < 1.0):
            raise EmDriverError(f'mismatch_tolerance_frac must be in (0, 1), got {mismatch_tolerance_frac!r}')
        self.driver = PwmDriverParams() if driver is None else driver
        self._axes = [_Axis(rod, self.driver) for rod in rods]
        self.auto_switch_to_standby = auto_switch_to_standby
        self.mismatch_tolerance_frac = mismatch_tolerance_frac
        self._pending_events: list[str] = []

    @property
    def active_units(self) -> tuple[str, str, str]:
        """Active winding per axis ('A' or 'B')."""
        x, y, z = (a.active for a in self._axes)
        return x, y, z

    def max_moment_am2(self) -> np.ndarray:
        """Per-axis dipole at full duty of the active winding, A·m² (the law's saturation level)."""
        return np.array([float(a.rod.moment_am2(a.full_current_a)) for a in self._axes])

    def select_eea(self, axis: int, unit: str) -> None:
        """Make winding ``unit`` ('A'/'B') and its bridge the active one on ``axis`` (the HEAO EEA SELECT command)."""
        ax = self._axis(axis)
        self._check_unit(ax, unit)
        if unit != ax.active:
            ax.active = unit
            self._pending_events.append(f'axis {axis}: winding select -> unit {unit}')

    def inject_failure(self, axis: int, unit: str, kind: str | None) -> None:
        """Fail one winding/bridge: 'open_winding', 'stuck_on_bridge' or 'dead_driver'; None clears it."""
        ax = self._axis(axis)
        self._check_unit(ax, unit)
        ax.units[unit].set_fault(kind)

    def unit_fault(self, axis: int, unit: str) -> CoilFault | None:
        """The failure injected into one winding, or None."""
        ax = self._axis(axis)
        self._check_unit(ax, unit)
        return ax.units[unit].fault

    def step(self, moment_command_am2: np.ndarray, dt_s: float) -> AssemblyResult:
        """Drive the three rods for dt_s (s) toward moment_command_am2 (A·m², body axes).

        A NaN/inf component is rejected: that axis holds its last valid command and the result
        carries a diagnostic. ``power_w`` is the net bus power of both windings (energy pushed
        back by a decaying winding counts negative); ``duty`` is |D| of the active bridge.
        """
        command = np.asarray(moment_command_am2, dtype=float)
        if command.shape != (3,):
            raise EmDriverError(f'moment_command_am2 must have shape (3,), got {command.shape}')
        if not (math.isfinite(dt_s) and dt_s > 0.0):
            raise EmDriverError(f'dt_s must be a finite positive time, got {dt_s!r}')
        diagnostics: list[str] = []
        events, self._pending_events = self._pending_events, []
        out = {k: np.zeros(3) for k in ('avg', 'end', 'cur', 'cmd', 'eft', 'duty', 'power')}
        switches = np.zeros(3, dtype=int)
        for k, ax in enumerate(self._axes):
            if math.isfinite(command[k]):
                ax.command = float(command[k])
            else:
                diagnostics.append(f'axis {k}: rejected non-finite moment command {command[k]!r}; '
                                   f'holding last valid command {ax.command:g}')
            duty = ax.duty_for(self.driver)
            active = ax.units[ax.active]
            start_a = active.current_a
            runs = {}
            for name, unit in ax.units.items():
                unit.powered = name == ax.active
                runs[name] = unit.run(duty if unit.powered else 0.0, dt_s)
            out['avg'][k] = self._average_dipole(ax.rod, list(runs.values()), dt_s)
            out['end'][k] = float(ax.rod.moment_am2(sum(u.current_a for u in ax.units.values())))
            out['power'][k] = sum(r.bus_energy_j for r in runs.values()) / dt_s
            out['cur'][k] = active.current_a
            out['cmd'][k] = duty * active.full_current_a
            out['eft'][k] = self.driver.current_sense_gain_v_per_a * active.current_a
            out['duty'][k] = abs(duty)
            switches[k] = runs[ax.active].switches
            healthy = pwm_response(start_a, duty, dt_s, active.full_current_a, active.tau_s, self.driver)
            events.extend(self._monitor(k, ax, active.current_a, healthy.end_current_a))
        figures = (*(tuple(map(float, out[k])) for k in ('avg', 'end', 'cur', 'cmd', 'eft', 'duty', 'power')),
                   tuple(map(int, switches)))  # in drive_assembly.FIGURES order
        x, y, z = (a.alarm for a in self._axes)
        return AssemblyResult(figures, alarms=(x, y, z), active_units=self.active_units, events=tuple(events),
                              diagnostics=tuple(diagnostics))

    #: The stepper's per-step entry (:meth:`DriveAssembly.step_xyz`'s counterpart): the rods' own checked step.
    step_xyz = step

    def _average_dipole(self, rod: TorqueRod, runs: list[_Run], dt_s: float) -> float:
        """Time-average dipole over the period, A·m².

        Exact while the summed current stays below the core's saturation current (the moment is
        linear in it); otherwise the saturating moment curve is averaged over the PWM periods'
        mean currents (exact charges per period; the intra-period ripple is neglected there).
        """
        if sum(r.peak_bound_a for r in runs) <= rod.saturation_current_a:
            return rod.linear_moment_per_a * sum(r.charge_as for r in runs) / dt_s
        period = 1.0 / self.driver.frequency_hz
        n = int(math.floor(dt_s / period + 1e-9))
        grid = np.append(np.arange(n + 1) * period, dt_s) if dt_s > n * period else np.arange(n + 1) * period
        charge = sum(r.charge_at(grid) for r in runs)
        widths = np.diff(grid)
        mean_i = np.diff(charge) / widths
        return float(np.sum(rod.moment_am2(mean_i) * widths) / dt_s)

    def _monitor(self, k: int, ax: _Axis, measured_a: float, expected_a: float) -> list[str]:
        """Mismatch alarm on the active winding; optional switch to the standby winding."""
        alarm = bool(abs(measured_a - expected_a) > self.mismatch_tolerance_frac * ax.full_current_a)
        switch = alarm and self.auto_switch_to_standby and len(ax.units) == 2
        events = alarm_events(k, ax.active, ax.alarm, alarm,
                              lambda: (f'{measured_a * 1e3:.3f} mA', f'{expected_a * 1e3:.3f} mA'), switch)
        ax.alarm = alarm
        if switch:
            ax.active = standby_unit(ax.active)
        return events

    def _axis(self, axis: int) -> _Axis:
        return axis_of(self._axes, axis)

    @staticmethod
    def _check_unit(ax: _Axis, unit: str) -> None:
        if unit not in ax.units:
            raise EmDriverError(f'unit must be one of {tuple(ax.units)}, got {unit!r}')
