"""The HEAO cold-gas reaction control subsystem: tanks, regulators, pressure switch, valves, thrusters (seed 002 §5).

Pure core (numpy-free). One :meth:`ColdGasRcs.frame` per control period Δt takes the controller's signed
on-time request per body axis and returns what the thrusters did.

**Schematic (Figure 5-1, taken as).** Two spherical tanks (7.6 in, §3.2; one gas volume) → fill valve,
pressure transducer (the "gas pressure readout" of Table 5-2: tank pressure), filter → two parallel branches,
each a latching isolation valve then a regulator ("redundant regulators and a regulator fail safe isolation
capability") → the low-pressure manifold with the pressure switch and the single relief valve (§5.2.1) → six
thruster/valves. The figure itself is not in the seed; branch *i* = isolation valve *i* + regulator *i* is
the reading that makes "the switch activates both isolation valves to the closed position … [they] can
subsequently be opened by ground command to diagnose the problem" work: ground reopens the healthy branch.

**Gas.** Nitrogen as an ideal gas (R = 296.8 J/(kg·K)), isothermal at the loading temperature: the tank
blowdown is p = m·R·T/V. At 4.6 lb in two 7.6-in spheres and 293 K that is 24.1 MPa (3494 psia), within the
6000-psi loading cart of §13.2.3; nitrogen's compressibility there (Z ≈ 1.05) is not modelled. Isothermal:
an acquisition draws ~1/3 of the load over minutes in millisecond pulses, and the tank walls hold the gas near
their temperature (adiabatic blowdown would cool it and lower both pressure and Isp; stated, not modelled).

**Thrust and flow.** The thrusters' chamber pressure is the manifold (feed) pressure; thrust scales with it,
F = F_nom·p_feed/p_set (F = C_F·A_t·p_c with fixed C_F and throat). Flow ṁ = F/(Isp·g0), so the propellant
used is exactly Σ F·t_thrust/(Isp·g0). Isp = 65 s from Table 5-3 itself: every flight-qualified tank's impulse
over its gas capacity is 64.9–65.3 lbf·s/lb (150/2.3, …, 2850/43.8), and §5.3's 300 lbf·s for the 4.6 lb system
is the same 65 s. Check against physics: the ideal infinite-expansion limit for N₂ at 293 K is
√(2γ/(γ−1)·R·T)/g0 = 79.6 s (:func:`ideal_vacuum_isp_limit_s`); 65 s is 82 % of it, the usual delivered
fraction of a small cold-gas nozzle.

**Valves.** A command of τ s starting at s opens the valve at s + t_open and closes it at s + τ + t_close
(rectangular thrust profile): thrust time τ − t_open + t_close. A request shorter than the minimum on-time
is raised to it (the minimum impulse bit F·(t_min − t_open + t_close)); a command ends t_close before the
frame's end, so every valve is shut at the frame boundary. At most ``max_open_valves`` valves are powered
at once (Table 5-2: 12 W each, "maximum of two valves operating at one time"): the driver sequences the
requests, longest first, each in the first free slot once the previous valve of that slot has shut (a couple
takes two slots from the same instant); a request that no longer fits in the frame (shorter than t_min) waits
for the controller's next frame.

**Regulators, switch, relief.** A working regulator holds the manifold at its set point while the tank is
above it (regulated flow on demand), and drops out below it (the manifold follows the tank: blowdown thrust).
A regulator that fails open (``regulator_fail_open``: its seats stuck open, "fail-open or leaking regulator"
§5.2.1) passes choked flow Γ·A·p_tank/√(R·T) from the tank; the manifold pressure rises, and when it reaches
the pressure switch's set point the switch closes both isolation valves (their closing time after the
trip); above the relief valve's crack pressure the excess gas vents overboard (counted as vented, not used).
While the switch is actuated (manifold at or above its set point) the isolation valves are held closed and
ground open commands are refused. Faults of a thruster valve: ``thruster_stuck_closed`` (commanded, no
flow) and ``thruster_stuck_open`` (flows the whole frame, unpowered; the feed pressure stays regulated, so
the pressure switch does not see it — ground closes the isolation valves).

Thruster torque and force are the frame averages of the thrust profile (N·m, N, body axes); the rigid body
integrates the average (spec §3), as it does the electromagnets' step-average dipole.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from acds_common.commands import GasCommand
from acds_common.thrusters import Arrangement
from acds_common.units import LB_KG, LBF_N, PSI_PA, STANDARD_GRAVITY_M_S2

#: Faults the cold-gas subsystem can be given (scenario ``cold_gas.fault``).
COLD_GAS_FAULTS = ('none', 'thruster_stuck_closed', 'thruster_stuck_open', 'regulator_fail_open')
#: Specific gas constant of nitrogen, J/(kg·K) (R / 28.0134 g/mol).
R_N2_J_KG_K = 8.314462618 / 0.0280134
#: Ratio of specific heats of nitrogen.
GAMMA_N2 = 1.4
#: Table 5-3 (flight-qualified tanks): diameter (in), tank weight (lb), gas capacity (lb GN₂), impulse (lbf·s).
TABLE_5_3 = ((7.6, 3.8, 2.3, 150.0), (9.6, 6.0, 4.0, 260.0), (11.5, 13.3, 7.7, 500.0), (12.7, 11.9, 9.5, 620.0),
             (13.0, 16.9, 11.5, 750.0), (15.0, 23.3, 17.5, 1140.0), (18.7, 49.5, 33.0, 2150.0),
             (20.5, 63.4, 43.8, 2850.0))
#: The cold-nitrogen specific impulse the study's tank table implies (impulse / gas capacity), s.
ISP_TABLE_5_3_S = 65.0
_CHOKED = math.sqrt(GAMMA_N2) * (2.0 / (GAMMA_N2 + 1.0)) ** ((GAMMA_N2 + 1.0) / (2.0 * (GAMMA_N2 - 1.0)))


class ColdGasError(ValueError):
    """A cold-gas configuration or input the hardware cannot have (names the key or what is wrong)."""


def table_5_3_isp_s() -> tuple[float, ...]:
    """Impulse over gas capacity of every Table 5-3 tank, s (lbf·s per lb of GN₂)."""
    return tuple(impulse / gas for _d, _w, gas, impulse in TABLE_5_3)


def ideal_vacuum_isp_limit_s(temperature_k: float) -> float:
    """Upper bound of a cold-nitrogen Isp: infinite expansion from ``temperature_k``, √(2γ/(γ−1)·R·T)/g0, s."""
    return math.sqrt(2.0 * GAMMA_N2 / (GAMMA_N2 - 1.0) * R_N2_J_KG_K * temperature_k) / STANDARD_GRAVITY_M_S2


@dataclass(frozen=True)
class RcsConfig:
    """The subsystem's hardware (SI). Pressures absolute; the tank volume is all tanks together."""

    arrangement: Arrangement
    thrust_n: float = 0.5 * LBF_N
    isp_s: float = ISP_TABLE_5_3_S
    valve_open_delay_s: float = 0.005
    valve_close_delay_s: float = 0.003
    min_on_time_s: float = 0.020
    max_open_valves: int = 2
    tank_volume_m3: float = 2 * math.pi / 6 * (7.6 * 0.0254) ** 3
    load_mass_kg: float = 4.6 * LB_KG
    temperature_k: float = 293.0
    regulator_set_pa: float = 150.0 * PSI_PA
    switch_trip_pa: float = 200.0 * PSI_PA
    relief_crack_pa: float = 250.0 * PSI_PA
    manifold_volume_m3: float = 50e-6
    regulator_seat_area_m2: float = 0.05e-6
    isolation_close_delay_s: float = 0.030

    def __post_init__(self) -> None:
        positive = ('thrust_n', 'isp_s', 'min_on_time_s', 'tank_volume_m3', 'load_mass_kg', 'temperature_k',
                    'regulator_set_pa', 'manifold_volume_m3')
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ColdGasError(f'{name} = {value!r} must be > 0')
        for name in ('valve_open_delay_s', 'valve_close_delay_s', 'regulator_seat_area_m2', 'isolation_close_delay_s'):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) >= 0.0):
                raise ColdGasError(f'{name} = {getattr(self, name)!r} must be ≥ 0')
        if self.min_on_time_s <= self.valve_open_delay_s:
            raise ColdGasError(f'min_on_time {self.min_on_time_s * 1e3:g} ms must exceed the valve opening delay '
                               f'{self.valve_open_delay_s * 1e3:g} ms (a shorter pulse gives no thrust)')
        if self.max_open_valves < 1:
            raise ColdGasError('max_open_valves must be at least 1')
        p0 = self.tank_pressure_pa(self.load_mass_kg)
        if p0 <= self.regulator_set_pa:
            raise ColdGasError(f'tank pressure at t0 {p0 / PSI_PA:.0f} psia ({self.load_mass_kg / LB_KG:g} lb in '
                               f'{self.tank_volume_m3 * 1e6:.0f} cm³ at {self.temperature_k:g} K) is not above the '
                               f'regulator set point {self.regulator_set_pa / PSI_PA:g} psia')
        if not self.regulator_set_pa < self.switch_trip_pa < self.relief_crack_pa:
            raise ColdGasError(f'pressures must rise regulator set point {self.regulator_set_pa / PSI_PA:g} < pressure '
                               f'switch {self.switch_trip_pa / PSI_PA:g} < relief {self.relief_crack_pa / PSI_PA:g} psia')

    def tank_pressure_pa(self, mass_kg: float) -> float:
        """Isothermal ideal-gas tank pressure of ``mass_kg`` of nitrogen, Pa."""
        return mass_kg * R_N2_J_KG_K * self.temperature_k / self.tank_volume_m3

    def manifold_mass_kg(self, pressure_pa: float) -> float:
        """Gas in the low-pressure manifold at ``pressure_pa``, kg."""
        return pressure_pa * self.manifold_volume_m3 / (R_N2_J_KG_K * self.temperature_k)

    @property
    def exhaust_velocity_m_s(self) -> float:
        """Isp·g0, m/s."""
        return self.isp_s * STANDARD_GRAVITY_M_S2

    @property
    def minimum_impulse_bit_ns(self) -> float:
        """Impulse of a minimum-on-time pulse at the set pressure, N·s."""
        return self.thrust_n * (self.min_on_time_s - self.valve_open_delay_s + self.valve_close_delay_s)


@dataclass(frozen=True)
class Fault:
    """An injected fault: ``kind`` (:data:`COLD_GAS_FAULTS`), thruster 0–5 or regulator 0–1,
    from ``time_s`` on."""

    kind: str = 'none'
    index: int = 0
    time_s: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in COLD_GAS_FAULTS:
            raise ColdGasError(f'fault {self.kind!r} is not one of {", ".join(COLD_GAS_FAULTS)}')
        top = 1 if self.kind == 'regulator_fail_open' else 5
        if not 0 <= self.index <= top:
            raise ColdGasError(f'fault index {self.index} out of range 0–{top} for {self.kind}')


@dataclass(frozen=True)
class Pulse:
    """One valve pulse in a frame: thruster index, command start and length, thrust start and duration (s)."""

    thruster: int
    command_start_s: float
    command_s: float
    thrust_start_s: float
    thrust_s: float


@dataclass(frozen=True)
class FrameResult:
    """What the subsystem did over one frame [t, t + Δt]."""

    thrust_n: float  # thrust of a firing thruster this frame (feed pressure at the frame start)
    thrust_time_s: tuple[float, ...]  # per thruster, s of thrust in the frame
    command_s: tuple[float, ...]  # per thruster, commanded on-time (powered), s
    torque_nm: tuple[float, float, float]  # frame average, body
    force_n: tuple[float, float, float]  # frame average, body
    used_kg: float  # propellant through the thrusters this frame
    vented_kg: float  # through the relief valve this frame
    max_open: int  # most valves open at one instant in the frame
    pulses: tuple[Pulse, ...]
    deferred: tuple[int, ...]  # thrusters whose request did not fit in the frame (the controller asks again)
    events: tuple[str, ...]


def schedule(requests_s: Sequence[tuple[tuple[int, ...], float]], dt: float,
             cfg: RcsConfig) -> tuple[list[Pulse], list[int]]:
    """Sequence (thrusters, on-time) requests into valve pulses in one frame; return the pulses and the deferred.

    A request is one thruster or a couple (fired together, one slot each, from the moment both slots are free).
    Longest request first (ties: thruster order), each in the first of ``max_open_valves`` slots to come
    free; a request is raised to the minimum on-time and cut so its valves shut by the frame's end; one that
    no longer fits (shorter than the minimum on-time) is deferred.
    """
    t_od, t_cd, t_min = cfg.valve_open_delay_s, cfg.valve_close_delay_s, cfg.min_on_time_s
    slots = [0.0] * cfg.max_open_valves
    pulses, deferred = [], []
    for group, tau in sorted(requests_s, key=lambda r: (-r[1], r[0])):
        ks = sorted(range(len(slots)), key=lambda i: (slots[i], i))[:len(group)]
        start = max(slots[k] for k in ks)
        on = min(max(tau, t_min), dt - t_cd - start)
        if len(ks) < len(group) or on < t_min:
            deferred.extend(group)
            continue
        for j, k in zip(group, ks, strict=True):
            pulses.append(Pulse(j, start, on, start + t_od, on - t_od + t_cd))
            slots[k] = start + on + t_cd
    return pulses, deferred


def most_open(intervals: Sequence[tuple[float, float]]) -> int:
    """Most intervals [a, b) open at one instant."""
    edges = sorted([(a, 1) for a, b in intervals if b > a] + [(b, -1) for a, b in intervals if b > a])
    count = best = 0
    for _t, step in edges:  # at equal times a closing edge (−1) sorts first
        count += step
        best = max(best, count)
    return best


@dataclass
class ColdGasRcs:
    """The subsystem's state and its per-frame physics (module docstring)."""

    cfg: RcsConfig
    fault: Fault = field(default_factory=Fault)
    isolation_open: list[bool] = field(default_factory=lambda: [True, True])
    bank_power: bool = True
    transducer_power: bool = True

    def __post_init__(self) -> None:
        self.tank_kg = self.cfg.load_mass_kg
        self.manifold_kg = self.cfg.manifold_mass_kg(self.cfg.regulator_set_pa) if any(self.isolation_open) else 0.0
        self.tank_kg -= self.manifold_kg  # the manifold was charged from the load
        self.switch_actuated = False
        self.regulator_failed = [False, False]
        self.stuck: dict[int, str] = {}
        self.used_kg = self.vented_kg = self.impulse_ns = 0.0
        self.valve_cycles = [0] * 6
        self.fault_active = False
        self.events: list[str] = []

    # ------------------------------------------------------------------ state
    @property
    def tank_pa(self) -> float:
        """Tank pressure, Pa."""
        return self.cfg.tank_pressure_pa(self.tank_kg)

    @property
    def feed_pa(self) -> float:
        """Manifold (thruster feed) pressure, Pa."""
        c = self.cfg
        return self.manifold_kg * R_N2_J_KG_K * c.temperature_k / c.manifold_volume_m3

    @property
    def propellant_kg(self) -> float:
        """Gas left in tanks and manifold, kg."""
        return self.tank_kg + self.manifold_kg

    # --------------------------------------------------------------- commands
    def apply(self, cmd: GasCommand) -> tuple[bool, str]:
        """Apply a ground command (Table 5-2; :class:`acds_common.commands.GasCommand`).

        Returns (accepted, what was done or why not). An isolation valve is not opened while the pressure switch
        is actuated (its circuit holds both closed).
        """
        if cmd.device == 'isolation':
            assert cmd.valve is not None
            i = cmd.valve - 1
            if cmd.on and self.switch_actuated:
                return False, (f'isolation valve {i + 1} held closed: pressure switch actuated (feed '
                               f'{self.feed_pa / PSI_PA:.0f} psia ≥ {self.cfg.switch_trip_pa / PSI_PA:g} psia)')
            self.isolation_open[i] = cmd.on
            return True, f'isolation valve {i + 1} {"open" if cmd.on else "closed"}'
        setattr(self, 'bank_power' if cmd.device == 'bank' else 'transducer_power', cmd.on)
        return True, f'{"thruster bank" if cmd.device == "bank" else "pressure transducer"} power {"on" if cmd.on else "off"}'

    # ------------------------------------------------------------------ frame
    def frame(self, t_s: float, dt: float, request_xyz: Sequence[float]) -> FrameResult:
        """One frame: signed on-time requests per body axis (s; sign = torque direction) → thrust, torque, gas."""
        cfg, arr = self.cfg, self.cfg.arrangement
        events: list[str] = []
        self._inject(t_s, events)
        requests = []
        if self.bank_power:
            for i in range(3):
                r = float(request_xyz[i])
                if not math.isfinite(r):
                    raise ColdGasError(f'on-time request {list(request_xyz)} is not finite')
                if r != 0.0:
                    requests.append((arr.thrusters_of_axis[2 * i + (0 if r > 0.0 else 1)], abs(r)))
        pulses, deferred = schedule(requests, dt, cfg)
        command = [0.0] * 6
        thrust_time = [0.0] * 6
        intervals = []
        for p in pulses:
            command[p.thruster] += p.command_s
            self.valve_cycles[p.thruster] += 1
            if self.stuck.get(p.thruster) != 'closed':
                thrust_time[p.thruster] += p.thrust_s
                intervals.append((p.thrust_start_s, p.thrust_start_s + p.thrust_s))
        for j, how in self.stuck.items():
            if how == 'open':
                thrust_time[j] = dt
                intervals.append((0.0, dt))
        thrust = cfg.thrust_n * self.feed_pa / cfg.regulator_set_pa
        demand = sum(thrust * t for t in thrust_time) / cfg.exhaust_velocity_m_s
        supply_cut = not any(o and not f for o, f in zip(self.isolation_open, self.regulator_failed, strict=True))
        if supply_cut and demand > self.manifold_kg > 0.0:  # the trapped gas runs out within the frame
            thrust *= self.manifold_kg / demand
        elif supply_cut and self.manifold_kg <= 0.0:
            thrust = 0.0
        impulses = [thrust * t for t in thrust_time]
        used = sum(impulses) / cfg.exhaust_velocity_m_s
        vented = self._pneumatics(t_s, dt, used, events)
        torque = [0.0, 0.0, 0.0]
        force = [0.0, 0.0, 0.0]
        for j, imp in enumerate(impulses):
            if imp:
                tau, d = arr.torque_per_thrust[j], arr.force_per_thrust[j]
                for i in range(3):
                    torque[i] += tau[i] * imp / dt
                    force[i] += d[i] * imp / dt
        self.used_kg += used
        self.vented_kg += vented
        self.impulse_ns += sum(impulses)
        return FrameResult(thrust, tuple(thrust_time), tuple(command), (torque[0], torque[1], torque[2]),
                           (force[0], force[1], force[2]), used, vented, most_open(intervals), tuple(pulses),
                           tuple(deferred), tuple(events))

    def _inject(self, t_s: float, events: list[str]) -> None:
        f = self.fault
        if f.kind == 'none' or self.fault_active or t_s < f.time_s:
            return
        self.fault_active = True
        if f.kind == 'regulator_fail_open':
            self.regulator_failed[f.index] = True
            events.append(f'fault at t={t_s:.1f} s: regulator {f.index + 1} failed open')
        else:
            self.stuck[f.index] = 'open' if f.kind == 'thruster_stuck_open' else 'closed'
            axes = self.cfg.arrangement.axis_names(f.index)
            events.append(f'fault at t={t_s:.1f} s: thruster T{f.index + 1} ({axes}) valve stuck {self.stuck[f.index]}')

    def _pneumatics(self, t_s: float, dt: float, used: float, events: list[str]) -> float:
        """Tank → regulators → manifold over the frame with the thrusters drawing ``used``; returns the vented kg."""
        cfg = self.cfg
        rt = R_N2_J_KG_K * cfg.temperature_k
        m_set = cfg.manifold_mass_kg(cfg.regulator_set_pa)
        m_trip = cfg.manifold_mass_kg(cfg.switch_trip_pa)
        m_relief = cfg.manifold_mass_kg(cfg.relief_crack_pa)
        leaking = [b for b in (0, 1) if self.isolation_open[b] and self.regulator_failed[b]]
        healthy = any(self.isolation_open[b] and not self.regulator_failed[b] for b in (0, 1))
        leak_rate = len(leaking) * _CHOKED * cfg.regulator_seat_area_m2 * self.tank_pa / math.sqrt(rt)
        leak_time = dt
        net = leak_rate - used / dt
        if leaking and not self.switch_actuated and net > 0.0 and self.manifold_kg + net * dt >= m_trip:
            t_trip = max(0.0, (m_trip - self.manifold_kg) / net)
            leak_time = min(dt, t_trip + cfg.isolation_close_delay_s)
            self.isolation_open = [False, False]
            self.switch_actuated = True
            events.append(f'pressure switch actuated at t={t_s + t_trip:.3f} s: feed reached '
                          f'{cfg.switch_trip_pa / PSI_PA:g} psia; isolation valves 1 and 2 closed')
        leak = min(leak_rate * leak_time, self.tank_kg)
        self.tank_kg -= leak
        manifold = self.manifold_kg + leak - used
        if healthy and not self.switch_actuated:
            if self.tank_pa > cfg.regulator_set_pa:
                supply = min(max(0.0, m_set - manifold), self.tank_kg)
                self.tank_kg -= supply
                manifold += supply
            else:  # regulator dropout: the manifold follows the tank
                total = self.tank_kg + manifold
                v_t, v_m = cfg.tank_volume_m3, cfg.manifold_volume_m3
                self.tank_kg, manifold = total * v_t / (v_t + v_m), total * v_m / (v_t + v_m)
        vented = max(0.0, manifold - m_relief)
        self.manifold_kg = max(0.0, manifold - vented)
        if self.switch_actuated and self.manifold_kg < m_trip:
            self.switch_actuated = False
            events.append(f'pressure switch released at t={t_s + dt:.1f} s: feed {self.feed_pa / PSI_PA:.0f} psia')
        elif self.manifold_kg >= m_trip and not self.switch_actuated:
            self.switch_actuated = True
            self.isolation_open = [False, False]
            events.append(f'pressure switch actuated at t={t_s + dt:.1f} s: feed {self.feed_pa / PSI_PA:.0f} psia; '
                          'isolation valves 1 and 2 closed')
        return vented

    def telemetry(self) -> dict[str, str]:
        """Table 5-2 telemetry and the state, as strings."""
        return {
            'gas_pressure_psia': f'{self.tank_pa / PSI_PA:.1f}' if self.transducer_power else 'off',
            'isolation_valve_1': 'open' if self.isolation_open[0] else 'closed',
            'isolation_valve_2': 'open' if self.isolation_open[1] else 'closed',
            'pressure_switch': 'actuated' if self.switch_actuated else 'open',
            'thruster_bank_power': 'on' if self.bank_power else 'off',
            'feed_pressure_psia': f'{self.feed_pa / PSI_PA:.2f}',
            'propellant_lb': f'{self.propellant_kg / LB_KG:.5f}',
            'used_lb': f'{self.used_kg / LB_KG:.5f}',
            'vented_lb': f'{self.vented_kg / LB_KG:.5f}',
            'impulse_lbf_s': f'{self.impulse_ns / LBF_N:.4f}',
            'valve_cycles': ' '.join(str(c) for c in self.valve_cycles),
        }
