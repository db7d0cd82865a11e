"""Bound kernels (:func:`acds_common.kernels.bound`): the models' per-step calls skip numba's dispatcher.

A model binds its kernel to the one signature it calls it with and gets that specialization's entry point, which
unboxes its arguments without typing them. Checked here: the bound form gives the plain function's bits at every
model call site (the model driven plain and bound side by side); it is the bare entry point when checking is off;
with checking on (``ACDS_KERNEL_CHECK``, which this suite sets) an argument of another type is refused, never
converted, and the dispatcher still runs the same arguments correctly; the transfer assembly, whose volts come
from another model, sends anything but float triples through the dispatcher; and a plain process imports no numba.
"""

from __future__ import annotations

import random
import subprocess
import sys

import numpy as np
import pytest
from acds_common import kernels
from acds_common.environment import EarthFieldConfig, Orbit, OrbitConfig, Sun, SunConfig, TiltedDipoleField
from acds_controller.transfer_assembly import TransferAssembly, field_xyz
from dynamics.rigid_body_model import RigidBodyModel, advance_circular_dipole, advance_stages, attitude_rk4_circular_dipole
from em_driver.drive_assembly import DriveAssembly, drive_step
from magnetometer_sim.fluxgate import FluxgateAxisParams, Magnetometer

INERTIA = np.array([[2000.0, -30.0, 120.0], [-30.0, 9000.0, 8.0], [120.0, 8.0, 9500.0]])


def _plain(factory):
    """``factory()`` built on the plain kernels, whether or not this process enabled compilation already."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(kernels, '_enabled', False)
        return factory()


def _bound(factory, check: bool = True):
    """``factory()`` built on the bound compiled kernels, checking their argument types or not."""
    kernels.enable()
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv('ACDS_KERNEL_CHECK', '1' if check else '0')
        return factory()


def _body(kind: str, substeps: int):
    orbit = Orbit(OrbitConfig() if kind == 'circular' else
                  OrbitConfig(kind='elliptical', perigee_altitude_m=4e5, apogee_radius_m=8e6))
    return lambda: RigidBodyModel(INERTIA, orbit, TiltedDipoleField(EarthFieldConfig()), Sun(SunConfig()),
                                  substeps=substeps, q0_body_to_eci=(0.1, -0.2, 0.3, 0.9),
                                  omega0_body_rad_s=(1e-3, -2e-3, 5e-4))


@pytest.mark.parametrize('check', [True, False])
@pytest.mark.parametrize('kind, substeps', [('circular', 5), ('circular', 1), ('elliptical', 2)])
def test_rigid_body_bound_gives_the_plain_bits(ieee_bits, kind, substeps, check):
    """Both advance kernels (circular dipole, general stage environment) at the model's call site, 300 steps of
    random dipoles and wheel momenta, plain against bound, every float of the truth bit for bit."""
    plain, fast = _plain(_body(kind, substeps)), _bound(_body(kind, substeps), check)
    kernel = advance_circular_dipole if kind == 'circular' else advance_stages
    assert plain._advance is kernel and fast._advance is not kernel
    if not check:  # unchecked: the bare entry point of the one compiled specialization
        assert fast._advance in [o.entry_point for o in kernels.compiled(kernel).overloads.values()]
    rng = random.Random(substeps)
    for _ in range(300):
        m = rng.choice([(0.0, 0.0, 0.0), tuple(rng.uniform(-2000.0, 2000.0) for _ in range(3))])
        h, hdot = tuple(rng.uniform(-20.0, 20.0) for _ in range(3)), tuple(rng.uniform(-0.2, 0.2) for _ in range(3))
        gas = rng.choice([None, (1e-4, -2e-4, 3e-5)])
        truths = []
        for model in (plain, fast):
            model.advance(0.5, m, h, hdot, gas)
            t = model.truth(h)
            truths.append([t.values, t.b_eci_xyz])
        assert ieee_bits(truths[0]) == ieee_bits(truths[1])


def test_magnetometer_bound_gives_the_plain_bits(ieee_bits):
    """The fluxgate pair's volts at :meth:`Magnetometer.read_xyz`, with noise (the same streams), faults and
    integer-valued parameters (the biases are floats by construction all the same)."""
    params = FluxgateAxisParams(noise_std_g=1e-3, bias_v=2, rail_low_v=0, rail_high_v=5)
    plain = _plain(lambda: Magnetometer(params, seed=3, residual_field_t=(1e-7, 0.0, -2e-7)))
    fast = _bound(lambda: Magnetometer(params, seed=3, residual_field_t=(1e-7, 0.0, -2e-7)))
    rng = random.Random(5)
    for k in range(500):
        if k == 200:
            for mag in (plain, fast):
                mag.inject_fault('A', 'bias_shift', 1, 3)  # an int shift: the bias stays a float
        if k == 300:
            for mag in (plain, fast):
                mag.select_unit('B')
        b = tuple(rng.uniform(-6e-5, 6e-5) for _ in range(3))
        d = tuple(rng.uniform(-2000.0, 2000.0) for _ in range(3))
        a, c = plain.read_xyz(b, d), fast.read_xyz(b, d)
        assert ieee_bits([a.volts_xyz, a.bias_xyz, a.field_xyz]) == ieee_bits([c.volts_xyz, c.bias_xyz, c.field_xyz])


def test_drive_assembly_bound_takes_any_number_for_the_commands_and_period(ieee_bits):
    """:meth:`DriveAssembly.step_xyz` makes its commands and period floats before the bound kernel: integer
    commands and an integer period give the plain function's bits, not a refusal."""
    plain, fast = _plain(DriveAssembly), _bound(DriveAssembly)
    assert plain._step is drive_step and fast._step is not drive_step
    for command, dt in [((1000, -3, 0), 1), ((2000.5, 1, -1), 0.5), ((0, 0, 0), 2)]:
        a, b = plain.step_xyz(command, dt), fast.step_xyz(command, dt)
        assert ieee_bits(list(a.avg_dipole_am2) + list(a.coil_current_a)) == \
            ieee_bits(list(b.avg_dipole_am2) + list(b.coil_current_a))


@pytest.mark.filterwarnings('ignore::numba.core.errors.NumbaPendingDeprecationWarning')  # the list case
def test_transfer_assembly_dispatches_anything_but_float_triples(ieee_bits):
    """Float triples take the bound kernel; ints, numpy scalars and lists take the dispatcher (the bound form is
    replaced by one that fails, to show which ran), all with the plain function's bits."""
    ta = _bound(TransferAssembly)
    floats = ((1.2345, 2.5, 4.9999), (2.5, 2.5, 2.5))
    others = [((1, 2, 4), (2, 3, 2)), ((np.float64(1.2345), 2.5, 4.9999), (2.5, 2.5, 2.5)),
              ([1.2345, 2.5, 4.9999], [2.5, 2.5, 2.5]), ((1.2345, 2.5, 4.9999), (2.5, 2, 2.5))]

    def fails(*_args):
        raise AssertionError('the wrong path ran')

    bound, dispatcher = ta._field_floats, ta._field
    ta._field = fails
    assert ieee_bits(ta.sense_xyz(*floats)) == ieee_bits(field_xyz(*floats, ta.lsb_v, ta._top_count,
                                                                     ta.scale_v_per_gauss))
    ta._field, ta._field_floats = dispatcher, fails
    for volts, bias in others:
        want = field_xyz(volts, bias, ta.lsb_v, ta._top_count, ta.scale_v_per_gauss)
        assert ieee_bits(ta.sense_xyz(volts, bias)) == ieee_bits(want)
    ta._field_floats = bound


def _rk4_args() -> list:
    """The circular-dipole RK4 kernel's arguments as the model passes them."""
    model = _plain(_body('circular', 2))
    r, _v, b = model._environment(0.0)
    return [model._q, model._w, 2, 0.0, 0.5, (*r, *b), model._circular_dipole, model._inertia_t,
            model._inertia_inv_t, (100.0, -50.0, 20.0), (1.0, 2.0, 3.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), True, True]


#: One argument changed to another type: (index, value, what).
WRONG = [(2, 2.0, 'a float where an int was bound'), (3, 0, 'an int where a float was bound'),
         (9, (100, -50, 20), 'int components in a float triple'), (9, [100.0, -50.0, 20.0], 'a list for a tuple'),
         (9, np.array([100.0, -50.0, 20.0]), 'an array for a tuple'), (13, 1, 'an int where a bool was bound'),
         (9, (100.0, -50.0), 'a shorter tuple')]


@pytest.mark.parametrize('index, value, what', WRONG, ids=[w[2] for w in WRONG])
def test_checked_bound_kernel_refuses_another_type(ieee_bits, index, value, what):
    """With checking on, a bound call with one argument of another type raises TypeError naming the argument
    (and runs nothing)."""
    args = _rk4_args()
    fast = _bound(lambda: kernels.bound(attitude_rk4_circular_dipole, *args))
    assert ieee_bits(fast(*args)) == ieee_bits(attitude_rk4_circular_dipole(*args))
    wrong = list(args)
    wrong[index] = value
    with pytest.raises(TypeError, match=f'argument {index}: '):
        fast(*wrong)


def test_dispatcher_types_what_the_bound_form_refuses(ieee_bits):
    """The dispatcher (``kernels.compiled``: what a caller with other types uses) types every call: int
    components in a float triple run as the plain function runs them."""
    args = _rk4_args()
    args[9] = (100, -50, 20)
    fast = _bound(lambda: kernels.compiled(attitude_rk4_circular_dipole))
    assert ieee_bits(fast(*args)) == ieee_bits(attitude_rk4_circular_dipole(*args))


def test_checked_drive_kernel_refuses_another_array():
    """An int64 state table has float64's item size, so the bare entry point would read its bits as floats: the
    checked form refuses it."""
    assembly = _bound(DriveAssembly)
    args = [assembly._state, assembly._params, assembly._monitor, (1.0, 2.0, 3.0), 0.5]
    assembly._step(*args)
    for index, value in [(0, assembly._state.astype(np.int64)), (1, np.asfortranarray(assembly._params)),
                         (1, _readonly(assembly._params)), (3, (0, 0, 0))]:
        wrong = list(args)
        wrong[index] = value
        with pytest.raises(TypeError, match=f'argument {index}:'):
            assembly._step(*wrong)


def _readonly(a):
    a = a.copy()
    a.flags.writeable = False
    return a


#: Values of many numba types, some of one Python type and another numba type (layout, readonly, int width).
VALUES = [0.0, -1.5, 0, 7, 2 ** 63 - 1, 2 ** 63, -(2 ** 63), -(2 ** 63) - 1, True, False, None, np.float64(1.0),
          np.int64(1), (), (1.0,), (1.0, 2.0), (1.0, 2), (1, 2.0), (1.0, (2.0, 3.0)), (1.0, (2.0, 3)), ((1.0,), 2.0),
          (None, 1.0), (True, 1.0), np.zeros(3), np.zeros(3, dtype=np.int64), np.zeros(3, dtype=np.float32),
          np.zeros((2, 3)), np.zeros((2, 3), order='F'), np.zeros((3, 4))[:, ::2],
          np.zeros(6)[::2], _readonly(np.zeros(3)), _readonly(np.zeros((2, 3))), (np.zeros(3), 1.0)]


def test_the_shape_check_passes_only_values_of_the_bound_numba_type():
    """The checked call compares a walk of the arguments' Python types (``kernels._shape``) and types them with numba
    only when that differs: any two values of one shape have one numba type (else a call of another numba type
    would run unchecked), and a value the walk does not describe matches nothing, not even itself."""
    from numba import typeof

    def numba_type(value):
        try:
            return typeof(value)
        except ValueError as exc:  # an int past 64 bits: numba refuses it
            return type(exc)

    for a in VALUES:
        for b in VALUES:
            if kernels._shape(a) == kernels._shape(b):
                assert numba_type(a) == numba_type(b), (a, b)
    assert kernels._shape(2 ** 63) != kernels._shape(2 ** 63)
    assert kernels._shape(np.float64(1.0)) != kernels._shape(np.float64(1.0))


def test_unchecked_entry_point_converts_silently():
    """Why the call sites fix their types: unchecked, a float where the bound signature has an int is truncated
    (2.9 substeps run as 2) and no error is raised; checking turns that into a TypeError."""
    args = _rk4_args()
    fast = _bound(lambda: kernels.bound(attitude_rk4_circular_dipole, *args), check=False)
    wrong = list(args)
    wrong[2] = 2.9
    assert fast(*wrong) == fast(*args)


def test_plain_process_binds_the_plain_functions_and_imports_no_numba():
    """A node process (compilation not enabled): every model's kernel is the plain function, and numba is never
    imported."""
    code = (
        'import sys\n'
        'from acds_common import kernels\n'
        'from acds_controller.transfer_assembly import TransferAssembly, field_xyz\n'
        'from em_driver.drive_assembly import DriveAssembly, drive_step\n'
        'from magnetometer_sim.fluxgate import Magnetometer, magnetometer_sample\n'
        'assert kernels.bound(field_xyz, (0.0,) * 3) is field_xyz\n'
        'assert TransferAssembly()._field_floats is field_xyz\n'
        'assert DriveAssembly()._step is drive_step\n'
        'assert Magnetometer()._sample is magnetometer_sample\n'
        'assert "numba" not in sys.modules, "numba imported"\n'
    )
    subprocess.run([sys.executable, '-c', code], check=True)
