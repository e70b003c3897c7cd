"""The ``[twin_inputs]`` profile section: the twin's sensors on the sound card's inputs."""

from __future__ import annotations

from console.plugin_api import Field

INPUT_FIELDS = {
    "sensor_mass_g": Field(
        "float",
        7.0,
        min=0.0,
        max=500.0,
        help="mass of the roving accelerometer glued on the glass (5-10 g: it shifts the "
        "modes near it); 0: a massless sensor",
    ),
    "sensor_mm": Field(
        "floats",
        [371.73, 223.645],
        length=2,
        min=0.0,
        max=5000.0,
        help="where the roving sensor sits at start, x y in table mm (the operator moves it)",
    ),
    "noise_m_s2_per_sqrt_hz": Field(
        "float",
        2e-4,
        min=0.0,
        max=1.0,
        help="accelerometer noise density (2e-4 m/s^2/sqrt(Hz) ~ 20 ug/sqrt(Hz): an IEPE "
        "100 mV/g sensor with the card's own noise)",
    ),
    "input_noise_v_rms": Field(
        "float",
        5e-6,
        min=0.0,
        max=1.0,
        help="the card's input noise on every channel, volts rms (a 24-bit card: ~5 uV)",
    ),
    "delay_samples": Field(
        "int",
        45,
        min=0,
        max=48000,
        help="the converters' round trip the inputs show (DAC + ADC filters and FIFOs): "
        "what a loopback measures",
    ),
    "seed": Field("int", 0, min=0, help="the sensor noise's random seed"),
}
