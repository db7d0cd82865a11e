"""Formation control cores: dipole solutions, spin closed forms, dump law, attitude feed-forward
(spec §10; seed 004 slides 19, 23, 27, 31–33, 48–49)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common.dipole_field import coaxial_force_n, dipole_force_n, dipole_pair_wrench, force_matrix
from acds_common.units import MU0
from acds_controller.formation_control import (
    AttitudeLaw,
    ControlledVehicle,
    DumpLaw,
    FormationController,
    HoldLaw,
    Measurement,
    SpinUpLaw,
    em_forces_n,
    min_norm_dipoles,
    solve_remaining_dipoles,
    spin_dipole_product_am4,
    steady_spin_dipole_product_am4,
)
from acds_controller.magnetic_laws import ControllerError
from hypothesis import given
from hypothesis import strategies as st

_F = st.integers(-1000, 1000).map(lambda i: i / 1e4)  # N
_R = st.integers(-5000, 5000).map(lambda i: i / 1000.0)  # m
FORCE = st.tuples(_F, _F, _F).map(np.array).filter(lambda f: np.linalg.norm(f) > 1e-3)
BASELINE = st.tuples(_R, _R, _R).map(np.array).filter(lambda r: np.linalg.norm(r) > 1.0)


@given(BASELINE, FORCE)
def test_min_norm_dipoles_make_the_commanded_force(r: np.ndarray, f: np.ndarray) -> None:
    mu_a, mu_b = min_norm_dipoles(r, f)
    assert np.allclose(dipole_force_n(mu_a, mu_b, r), f, rtol=0, atol=1e-9 * np.linalg.norm(f))
    assert np.linalg.norm(mu_a) == pytest.approx(np.linalg.norm(mu_b), rel=1e-9)
    # both dipoles lie in the plane of the baseline and the force
    n = np.cross(r, f)
    if np.linalg.norm(n) > 1e-6 * np.linalg.norm(r) * np.linalg.norm(f):
        n /= np.linalg.norm(n)
        assert abs(mu_a @ n) < 1e-9 * np.linalg.norm(mu_a) and abs(mu_b @ n) < 1e-9 * np.linalg.norm(mu_b)


def test_min_norm_is_optimal_over_the_whole_sphere() -> None:
    """The free-choice rule: no direction of μ_A on the sphere needs less |μ_A|² + |μ_B|²."""
    rng = np.random.default_rng(27)
    r = np.array([2.0, 0.5, -0.3])
    for _ in range(5):
        f = rng.normal(size=3) * 0.05
        mu_a, mu_b = min_norm_dipoles(r, f)
        best = np.linalg.norm(mu_a) ** 2 + np.linalg.norm(mu_b) ** 2
        dirs = rng.normal(size=(20000, 3))
        dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
        with np.errstate(all='ignore'):
            b = np.linalg.solve(force_matrix(dirs, r), np.broadcast_to(f, (20000, 3))[..., None])[..., 0]
        cost = 2.0 * np.linalg.norm(b, axis=1)  # optimal split |μ_A| = |μ_B| for each direction
        assert np.nanmin(cost) >= best * (1.0 - 1e-9)


def test_attraction_gives_the_coaxial_pair_and_the_steady_spin_closed_form() -> None:
    """Slides 48–49: steady spin at ω, separation d: μ_A μ_B = 2π μ_red ω² d⁵/(3μ0); equal masses
    π m ω² d⁵/(3μ0) = 32π m r⁵ ω²/(3μ0) with r = d/2 (slide 19), = 16 m x0⁵ ω²/c, c = 3μ0/(2π) (slide 49)."""
    m, d, w = 19.0, 2.5, 0.05
    r = np.array([d, 0.0, 0.0])
    f_b = np.array([-0.5 * m * w * w * d, 0.0, 0.0])  # centripetal force on B, μ_red ω² d
    mu_a, mu_b = min_norm_dipoles(r, f_b, plane_normal=[0, 0, 1])
    # both on the baseline (to the golden-section search's √ε angle resolution of a quadratic minimum)
    assert abs(mu_a[1]) < 1e-7 * abs(mu_a[0]) and abs(mu_b[1]) < 1e-7 * abs(mu_b[0])
    product = float(mu_a @ mu_b)
    closed = steady_spin_dipole_product_am4(m, m, d, w)
    assert product == pytest.approx(closed, rel=1e-9)
    assert closed == pytest.approx(math.pi * m * w * w * d ** 5 / (3 * MU0), rel=1e-13)
    assert closed == pytest.approx(32 * math.pi * m * (d / 2) ** 5 * w * w / (3 * MU0), rel=1e-13)
    assert closed == pytest.approx(16 * m * (d / 2) ** 5 * w * w / (3 * MU0 / (2 * math.pi)), rel=1e-13)
    assert coaxial_force_n(math.sqrt(closed), math.sqrt(closed), d) == pytest.approx(0.5 * m * w * w * d, rel=1e-13)


@pytest.mark.parametrize('w,wdot', [(0.05, 0.0), (0.05, 1e-3), (0.02, 2e-3), (0.0, 1e-3)])
def test_slide_19_spin_up_dipoles(w: float, wdot: float) -> None:
    """Slide 19 with B's dipole on the baseline: A at α, tan α = 2ω̇/ω², gives the centripetal m r ω²
    and tangential m r ω̇ forces (r = d/2) with μ_A μ_B = 2π μ_red d⁵ √(ω⁴ + 4ω̇²)/(3μ0)."""
    m, d = 19.0, 2.5
    product, alpha = spin_dipole_product_am4(m, m, d, w, wdot)
    mu = math.sqrt(product)
    f_b = dipole_force_n(mu * np.array([math.cos(alpha), math.sin(alpha), 0.0]), np.array([mu, 0.0, 0.0]),
                         np.array([d, 0.0, 0.0]))
    assert np.allclose(f_b, [-m * d / 2 * w * w, m * d / 2 * wdot, 0.0], rtol=0, atol=1e-12)
    if wdot == 0.0:
        assert alpha == 0.0 and product == pytest.approx(steady_spin_dipole_product_am4(m, m, d, w), rel=1e-14)


def test_solve_remaining_dipoles_for_three_vehicles() -> None:
    """Slide 23: pick one vehicle's dipole, solve the rest (3N − 3 equations, Newton)."""
    pos = np.array([[0.0, 0.0, 0.0], [3.0, 0.5, 0.0], [1.0, 3.2, 0.4]])
    truth = np.array([[800.0, -300.0, 200.0], [-400.0, 900.0, 100.0], [300.0, 300.0, -700.0]])
    forces = em_forces_n(pos, truth)
    assert np.allclose(forces.sum(axis=0), 0.0, atol=1e-15)
    guess = truth * (1.0 + np.array([[0.0], [0.2], [-0.15]]))
    sol = solve_remaining_dipoles(pos, 0, truth[0], forces, guess)
    assert np.allclose(em_forces_n(pos, sol), forces, rtol=0, atol=1e-10 * np.abs(forces).max())
    assert np.allclose(sol, truth, rtol=1e-8)  # the root reached from a nearby guess
    # two vehicles: linear in the other dipole, one Newton step from zero
    sol2 = solve_remaining_dipoles(pos[:2], 1, truth[1], em_forces_n(pos[:2], truth[:2]), np.zeros((2, 3)))
    assert np.allclose(sol2[0], truth[0], rtol=1e-10)


def test_solve_remaining_dipoles_refuses_a_singular_free_dipole() -> None:
    """In 3-D a free dipole perpendicular to the baseline cannot make a force along μ_A × r̂."""
    pos = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    with pytest.raises(ControllerError, match='singular'):
        solve_remaining_dipoles(pos, 0, [0.0, 1000.0, 0.0], np.array([[0, 0, 1e-3], [0, 0, -1e-3]]), np.zeros((2, 3)))


def _vehicle(name: str, axes: np.ndarray, limit: float) -> ControlledVehicle:
    return ControlledVehicle(name, 19.0, np.diag([0.67, 0.67, 1.34]), axes, np.full(axes.shape[1], limit))


def _meas(p: tuple[float, float, float], v: tuple[float, float, float] = (0, 0, 0), h: float = 0.0,
          b: np.ndarray | None = None, hv: np.ndarray | None = None) -> Measurement:
    return Measurement(np.array(p, dtype=float), np.array(v, dtype=float), np.eye(3), np.zeros(3),
                       np.array([0.0, 0.0, h]) if hv is None else hv, b)


def test_controller_saturates_dipoles_keeping_the_force_direction() -> None:
    """Beyond a coil's limit all dipoles scale by s: the force keeps its direction, scaled by s²."""
    axes = np.eye(3)[:, :2]
    pair = [_vehicle('a', axes, 100.0), _vehicle('b', axes, 100.0)]
    ctl = FormationController(pair, 'planar', HoldLaw((2.5, 0.0, 0.0), 0.1, 0.9), AttitudeLaw(), 0.1, 1.0)
    a, b = ctl.step(0.0, [_meas((0, 0, 0)), _meas((2.0, 0.4, 0))])
    assert max(np.abs(a.coil_moments_am2).max(), np.abs(b.coil_moments_am2).max()) == pytest.approx(100.0, rel=1e-12)
    r = np.array([2.0, 0.4, 0.0])
    achieved = dipole_force_n(a.dipole_frame_am2, b.dipole_frame_am2, r)
    cmd = b.force_command_n
    assert np.linalg.norm(np.cross(achieved, cmd)) < 1e-6 * np.linalg.norm(achieved) * np.linalg.norm(cmd)
    assert np.linalg.norm(achieved) < np.linalg.norm(cmd)
    assert np.allclose(a.force_command_n, -cmd)


def test_wheels_take_the_predicted_em_torque() -> None:
    """Slide 18: with the attitude on target the wheel command is exactly the predicted EM torque, so the
    body feels nothing (ḣ = τ_EM); and the force commanded on B is what the held dipoles make."""
    axes = np.eye(3)[:, :2]
    pair = [_vehicle('a', axes, 5000.0), _vehicle('b', axes, 5000.0)]
    law = SpinUpLaw(2.5, 0.05, 1e-3)
    ctl = FormationController(pair, 'planar', law, AttitudeLaw(), 0.1, 1.0)
    a, b = ctl.step(10.0, [_meas((0, 0, 0)), _meas((2.5, 0, 0), (0.0, 0.025, 0.0))])
    # the dipoles are aimed at the baseline half a period ahead: turned by Ω·dt/2 = 0.01 rad/s · 0.05 s
    turned = 2.5 * np.array([math.cos(5e-4), math.sin(5e-4), 0.0])
    _, t_a, f_b, t_b = dipole_pair_wrench(a.dipole_frame_am2, b.dipole_frame_am2, turned)
    assert np.allclose(f_b, b.force_command_n, rtol=1e-9)
    assert np.allclose(a.wheel_torque_body_nm, [0, 0, t_a[2]], rtol=1e-9)
    assert np.allclose(b.wheel_torque_body_nm, [0, 0, t_b[2]], rtol=1e-9)
    assert abs(t_a[2]) > 1e-4  # ramping: a shear force, hence real torques


def test_earth_dump_dipole_is_full_and_removes_momentum() -> None:
    """Slides 31–33: the vehicle with most wheel momentum goes to full dipole along −(B × h), whose Earth
    torque opposes h; the partner is solved for the formation force; hysteresis between start and done."""
    axes = np.eye(3)
    pair = [_vehicle('a', axes, 900.0), _vehicle('b', axes, 900.0)]
    ctl = FormationController(pair, 'hill', HoldLaw((3.0, 0.0, 0.0), 0.05, 0.9), AttitudeLaw(0.2, 0.8), 1.0, 0.01,
                              mean_motion_rad_s=1.1e-3, dump=DumpLaw(start_nms=0.1, done_nms=0.02))
    b = np.array([2e-5, -1e-5, 3e-5])
    h_a = np.array([0.3, -0.2, 0.1])
    a_cmd, b_cmd = ctl.step(0.0, [_meas((-1.5, 0, 0), b=b, hv=h_a), _meas((1.5, 0, 0), b=b, hv=np.array([0.05, 0, 0]))])
    assert ctl.dumping_vehicle == 0 and a_cmd.dumping and not b_cmd.dumping
    assert np.abs(a_cmd.coil_moments_am2).max() == pytest.approx(900.0, rel=1e-12)  # full dipole
    torque = np.cross(a_cmd.dipole_frame_am2, b)
    assert torque @ h_a < 0.0
    h_perp = h_a - (h_a @ b) * b / (b @ b)
    assert np.linalg.norm(np.cross(torque, h_perp)) < 1e-12 * np.linalg.norm(torque) * np.linalg.norm(h_perp)  # ∥ −h⊥
    # the partner's dipole makes the commanded force on B together with the dumping dipole
    f = dipole_force_n(a_cmd.dipole_frame_am2, b_cmd.dipole_frame_am2, np.array([3.0, 0.0, 0.0]))
    assert np.allclose(f, b_cmd.force_command_n, rtol=1e-9)
    assert b_cmd.force_command_n[0] == pytest.approx(0.5 * 19.0 * (-3 * 1.1e-3 ** 2 * 3.0), rel=1e-12)  # CW ff
    # still above done: keeps dumping A; below done: hands over to B, which now has the most
    ctl.step(1.0, [_meas((-1.5, 0, 0), b=b, hv=h_a * 0.2), _meas((1.5, 0, 0), b=b, hv=np.array([0.15, 0, 0]))])
    assert ctl.dumping_vehicle == 0
    a_cmd, b_cmd = ctl.step(2.0, [_meas((-1.5, 0, 0), b=b, hv=h_a * 0.01),
                                  _meas((1.5, 0, 0), b=b, hv=np.array([0.15, 0, 0]))])
    assert ctl.dumping_vehicle == 1
    # B's h along the baseline puts its dump dipole across it, which cannot make the radial force:
    # the formation force has priority, this step flies the min-norm pair
    assert not b_cmd.dumping
    assert np.allclose(dipole_force_n(a_cmd.dipole_frame_am2, b_cmd.dipole_frame_am2, np.array([3.0, 0.0, 0.0])),
                       b_cmd.force_command_n, rtol=1e-9)
    _, b_cmd = ctl.step(3.0, [_meas((-1.5, 0, 0), b=b, hv=h_a * 0.01),
                              _meas((1.5, 0, 0), b=b, hv=np.array([0.1, 0.1, 0.0]))])
    assert b_cmd.dumping and np.abs(b_cmd.coil_moments_am2).max() == pytest.approx(900.0, rel=1e-12)


def test_configuration_errors_name_the_problem() -> None:
    axes = np.eye(3)[:, :2]
    pair = [_vehicle('a', axes, 100.0), _vehicle('b', axes, 100.0)]
    with pytest.raises(ControllerError, match='pair'):
        FormationController(pair[:1], 'planar', HoldLaw((2, 0, 0)), AttitudeLaw(), 0.1, 1.0)
    with pytest.raises(ControllerError, match="frame 'hill'"):
        FormationController(pair, 'planar', HoldLaw((2, 0, 0)), AttitudeLaw(), 0.1, 1.0, dump=DumpLaw(0.1, 0.01))
    with pytest.raises(ControllerError, match='orthonormal'):
        ControlledVehicle('c', 19.0, np.eye(3), np.array([[1.0, 1.0], [0.0, 0.0], [0.0, 0.0]]), np.ones(2))
    with pytest.raises(ControllerError, match='leaves the dipoles'):
        min_norm_dipoles([2.0, 0, 0], [0, 0, 1e-3], plane_normal=[0, 0, 1])
