"""Transfer assembly (TA): digitises the magnetometer and buffers telemetry (spec §5, §7; seed 002 §4.2.6–4.2.7).

The magnetometer (Table 4-5) gives per axis 0…+5 V DC, 2.5 V at zero field, 2.5 V/G,
±1 G range, 0.004 G resolution, ±0.1 % of full scale accuracy, and its bias voltage
as a separate output. The TA converts each field voltage and the bias voltage with the
same ADC and forms B = (V_field − V_bias)/2.5 V/G, so a drift of the bias reference is
cancelled when it is common to both (and shows in telemetry when it is not).
"""

from __future__ import annotations

from collections.abc import Sequence
from math import floor

import numpy as np
from acds_common import kernels
from acds_common.units import GAUSS_T, tesla_to_gauss
from acds_common.vec3 import Vec3

from acds_controller.magnetic_laws import ControllerError, as_vector3, as_xyz, check_gain

#: Magnetometer output span, V (Table 4-5: 0 to +5 V DC).
FULL_SCALE_V = 5.0
#: Magnetometer scale factor, V/G (Table 4-5).
SCALE_V_PER_GAUSS = 2.5
#: Electromagnet moment per coil ampere, A·m²/A (Table 4-3: 2062 A·m² at 0.727 A).
MOMENT_PER_AMP_AM2_PER_A = 2062.0 / 0.727

_AXES = ('x', 'y', 'z')


@kernels.helper
def count_v(v: float, lsb_v: float, top_count: float) -> float:
    """One voltage quantised to the nearest ADC count (clipped to 0…``top_count``), as the count's voltage, V.

    The count is ⌊v/LSB + ½⌋; the clip is decided on v/LSB + ½ itself (below 0, or at or above top + 1, is the
    same as the floored count below 0 or above top), so a voltage beyond any integer's range still saturates.
    ``top_count`` is a float (2ⁿ − 1 exactly), so every comparison is float with float.
    """
    x = v / lsb_v + 0.5
    return (0.0 if x < 0.0 else top_count if x >= top_count + 1.0 else floor(x)) * lsb_v


@kernels.helper
def field_xyz(volts: Sequence[float], bias_volts: Sequence[float], lsb_v: float, top_count: float,
              scale_v_per_gauss: float) -> Vec3:
    """Sensed field, T: the A/D conversion of every axis's field and bias voltage and B = (V_field − V_bias)/scale
    (seed 002 §4.2.7, Table 4-5). A kernel (:mod:`acds_common.kernels`): compiled in the direct engine, alone
    (:meth:`TransferAssembly.sense_xyz`) or in the controller's step (:func:`acds_controller.controller_step.dpa_control`)."""
    return ((count_v(volts[0], lsb_v, top_count) - count_v(bias_volts[0], lsb_v, top_count)) / scale_v_per_gauss
            * GAUSS_T,
            (count_v(volts[1], lsb_v, top_count) - count_v(bias_volts[1], lsb_v, top_count)) / scale_v_per_gauss
            * GAUSS_T,
            (count_v(volts[2], lsb_v, top_count) - count_v(bias_volts[2], lsb_v, top_count)) / scale_v_per_gauss
            * GAUSS_T)


class TransferAssembly:
    """Analog-to-digital interface between magnetometer/electromagnet drivers and the DPA (seed 002 §4.2.7).

    ADC width: 10 bits by default. Over the 0…5 V span one count is 5/1024 V = 4.9 mV =
    0.00195 G at 2.5 V/G, half the magnetometer's 0.004 G resolution. The field is a
    difference of two converted voltages (field − bias), whose quantisation error is up
    to ±1 count = ±0.002 G: with 10 bits this stays inside both the 0.004 G resolution
    and the ±0.1 % full-scale accuracy (±5 mV = ±0.002 G), so the TA does not coarsen
    the sensor. 9 bits (9.8 mV = 0.0039 G per count) would make the difference error as
    large as the resolution itself; 8 bits would be coarser than the sensor.

    Parameters: ``adc_bits`` (count, 8…24), ``full_scale_v`` (V, converter span from 0),
    ``scale_v_per_gauss`` (V/G), ``moment_per_amp_am2_per_a`` (A·m²/A, turns a moment
    command into the torquer current command for telemetry).
    """

    def __init__(
        self,
        adc_bits: int = 10,
        full_scale_v: float = FULL_SCALE_V,
        scale_v_per_gauss: float = SCALE_V_PER_GAUSS,
        moment_per_amp_am2_per_a: float = MOMENT_PER_AMP_AM2_PER_A,
    ) -> None:
        if not isinstance(adc_bits, int) or not 8 <= adc_bits <= 24:
            raise ControllerError(f'adc_bits = {adc_bits!r} must be an integer in [8, 24]')
        self.adc_bits = adc_bits
        self.full_scale_v = check_gain(full_scale_v, 'full_scale_v', 1e-3, 1e3)
        self.scale_v_per_gauss = check_gain(scale_v_per_gauss, 'scale_v_per_gauss', 1e-6, 1e6)
        self.moment_per_amp_am2_per_a = check_gain(
            moment_per_amp_am2_per_a, 'moment_per_amp_am2_per_a', 1e-6, 1e9)
        self.lsb_v = self.full_scale_v / (1 << adc_bits)
        self._top_count = float((1 << adc_bits) - 1)
        #: :func:`field_xyz`'s converter constants (LSB V, top count, scale V/G), floats.
        self.params = (self.lsb_v, self._top_count, self.scale_v_per_gauss)

        #: The A/D kernel as the dispatcher (any argument types) and bound to float triples (:func:`kernels.bound`;
        #: the converter's constants are floats by construction above: ``check_gain``, a true division, ``float``).
        self._field = kernels.compiled(field_xyz)
        self._field_floats = kernels.bound(field_xyz, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), self.lsb_v, self._top_count,
                                           self.scale_v_per_gauss)

    def digitise(self, volts: np.ndarray) -> np.ndarray:
        """Quantise volts to the nearest ADC count (clipped to 0…2ⁿ−1) and return the count's voltage, V."""
        return np.array([count_v(v, self.lsb_v, self._top_count) for v in as_xyz(volts, 'volts')])

    def sense_xyz(self, volts: Sequence[float], bias_volts: Sequence[float]) -> Vec3:
        """:meth:`sense` on finite float triples (the stepper's per-step path), T."""
        # The volts come from another model (a magnetometer's output, a message), so their types are checked here:
        # the bound kernel only on two tuples of three floats, anything else (ints from integer parameters, numpy
        # scalars, lists) through the dispatcher, which types it.
        v0, v1, v2 = volts
        b0, b1, b2 = bias_volts
        field = (self._field_floats if type(volts) is tuple and type(bias_volts) is tuple and type(v0) is float
                 and type(v1) is float and type(v2) is float and type(b0) is float and type(b1) is float
                 and type(b2) is float else self._field)
        return field(volts, bias_volts, self.lsb_v, self._top_count, self.scale_v_per_gauss)

    def sense(self, volts: np.ndarray, bias_volts: np.ndarray) -> np.ndarray:
        """Sensed field in tesla (body axes) from per-axis field volts and bias reference volts (Table 4-5)."""
        return np.array(self.sense_xyz(as_xyz(volts, 'volts'), as_xyz(bias_volts, 'bias_volts')))

    def telemetry(
        self,
        sensed_field_t: np.ndarray,
        moment_command_am2: np.ndarray,
        bias_volts: np.ndarray,
        coil_current_a: np.ndarray,
        excess_current_alarm: Sequence[bool],
    ) -> dict[str, str]:
        """Telemetry buffer of the TA as key/value strings (seed 002 §4.2.5–4.2.6; spec §7).

        Sensed field (G), moment command (A·m²) and the torquer current command it means (A),
        magnetometer bias voltage (V), coil current from the driver's e_ft (A, signed) and the
        excess-coil-current alarm per axis ('true'/'false').
        """
        b_g = tesla_to_gauss(as_vector3(sensed_field_t, 'sensed_field_t'))
        m = as_vector3(moment_command_am2, 'moment_command_am2')
        bias = as_vector3(bias_volts, 'bias_volts')
        coil = as_vector3(coil_current_a, 'coil_current_a')
        alarms = list(excess_current_alarm)
        if len(alarms) != 3:
            raise ControllerError(f'excess_current_alarm must hold 3 flags (x, y, z), got {alarms!r}')
        out: dict[str, str] = {}
        for i, axis in enumerate(_AXES):
            out[f'sensed_field_{axis}_gauss'] = f'{b_g[i]:.6g}'
            out[f'moment_command_{axis}_am2'] = f'{m[i]:.6g}'
            out[f'torquer_current_command_{axis}_a'] = f'{m[i] / self.moment_per_amp_am2_per_a:.6g}'
            out[f'magnetometer_bias_{axis}_v'] = f'{bias[i]:.6g}'
            out[f'coil_current_{axis}_a'] = f'{coil[i]:.6g}'
            out[f'excess_coil_current_alarm_{axis}'] = 'true' if alarms[i] else 'false'
        return out
