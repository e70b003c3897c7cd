"""The plate in the loop (``plugins.twin.plate.jack_plate``): the console's whole duplex path
(PortAudio's JACK host API, the sounddevice driver, the gate) measured through a JACK
client that stands for the table, on the JACK dummy server (skips where jackd is missing).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from console.cli.entry import main

REPO = Path(__file__).resolve().parents[2]
DELAY = 45  # the plate client's own delay (the converters'), in samples
#: one JACK dummy server (a session fixture) serves them all: on one xdist worker
pytestmark = [pytest.mark.hardware, pytest.mark.xdist_group("jack")]

INPUTS = """
[audio_inputs.accel]
channel = 1
kind = "accelerometer"
sensitivity = 10.2
[audio_inputs.loopback]
channel = 2
kind = "loopback"
sensitivity = 1.0
"""


def _profile(tmp_path: Path, block: int, inputs: str = INPUTS) -> Path:
    text = (REPO / "profiles" / "sim.toml").read_text(encoding="utf-8")
    audio = (
        '[audio]\ndriver = "sounddevice"\ndevice = "system"\n'
        f"sample_rate_hz = 48000\nblock_size = {block}\nfull_scale_v = 2.0\n"
    )
    text = re.sub(r"\[audio\]\n(?:[^\[\n][^\n]*\n|\n)*", audio + "\n", text, count=1)
    path = tmp_path / "jackplate.toml"
    path.write_text(text + inputs, encoding="utf-8")
    return path


@pytest.fixture
def private_dirs(tmp_path, monkeypatch):
    import shutil
    import tempfile

    run = tempfile.mkdtemp(prefix="hp-")  # short: the kernel's socket lives there
    monkeypatch.setenv("XDG_RUNTIME_DIR", run)
    monkeypatch.setenv("HAPTABLE_CONFIG_DIR", str(tmp_path / "config"))
    yield tmp_path
    shutil.rmtree(run, ignore_errors=True)


def _latency(profile: Path, capsys, *extra: str) -> dict:
    assert main(["-p", str(profile), "frf", "latency", "--json", *extra]) == 0
    return json.loads(capsys.readouterr().out.strip().splitlines()[-1])


def _plate(server, record: bool = False):
    from console.plugin_api import load_plugins, load_profile
    from plugins.twin.plate.jack_plate import JackPlate, plate_filter_from_profile

    sim = load_profile("sim", load_plugins())
    pytest.importorskip("jack", exc_type=OSError, reason="JACK-Client or libjack missing")
    return JackPlate(
        lambda fs: plate_filter_from_profile(sim, fs),
        server=server.name,
        delay_samples=DELAY,
        record=record,
    )


def test_round_trip_through_the_plate_is_what_jacks_periods_imply(
    jack_server, private_dirs, capsys, wait
):
    from console.plugin_api import load_plugins, load_profile
    from plugins.twin.plate.jack_plate import expected_round_trip_samples

    block = jack_server.block_size
    path = _profile(private_dirs, block)
    try:
        with _plate(jack_server, record=True) as plate:
            runs = [_latency(path, capsys) for _ in range(2)]
            runs.append(_latency(path, capsys, "--save"))
    finally:  # the table's kernel lingers after its last client: the next test on this
        # JACK server must find only its own PortAudio ports
        wait(
            lambda: not any(p.startswith("PortAudio") for p in jack_server.ports()),
            30,
            "the kernel to end",
        )
    assert not plate.errors
    want = expected_round_trip_samples(plate.period, block, DELAY)  # 256 + 256 + 45
    got = [r["round_trip_samples"] for r in runs]
    # repeatable: two runs of three at least on the sample. On a loaded machine a run can
    # start after an xrun that left the stream whole periods late (then it really is
    # that late): never earlier than the chain, and late by whole periods
    assert sum(abs(g - want) <= 1 for g in got) >= 2, (got, want)
    for g in got:
        periods = round((g - want) / block)
        assert periods >= 0 and abs(g - want - periods * block) <= 6, (got, want)
    # next to what PortAudio claims: the dummy card's 2 periods of output latency
    assert runs[0]["portaudio_output_latency_ms"] == pytest.approx(2 * block / 48, abs=0.01)
    # --save: the profile's overrides file holds it, and the profile reads it back
    saved = runs[-1]["measured_output_latency_ms"]
    assert Path(runs[-1]["saved"]).is_file()
    assert 0 < saved < runs[-1]["round_trip_ms"]
    again = load_profile(str(path), load_plugins())
    assert again.get("audio.measured_output_latency_ms") == pytest.approx(saved)

    # what the plate client put out as acceleration is the offline plate model's answer
    # to what it got (an FFT convolution with the continuous FRF: another method)
    from plugins.twin.plate import sensor
    from plugins.twin.plate.model import build_twin, params_from_profile

    sim = load_profile("sim", load_plugins())
    x = np.concatenate(plate.recorded_in).astype(np.float64)
    acc = np.concatenate(plate.recorded_accel)  # m/s^2, before the card's scaling
    assert np.abs(x).max() > 0.005  # the chirps did reach the plate
    tw = build_twin(params_from_profile(sim))
    tw = sensor.with_point_mass(tw, 371.73, 223.645, 0.007)
    drive = np.zeros((4, x.size))
    drive[0] = x * 2.0 * 50.0  # card -> volts at PA: full scale x the amplifier's gain
    ref = sensor.acceleration(tw, 371.73, 223.645, drive, plate.fs_hz)
    # in the chirps' band (100-2000 Hz; compared below 2.5 kHz): above it the offline
    # model's static residual grows as f^2 on the gate's faint broadband, the client's
    # high mode rolls off (the plate model keeps modes to 1250 Hz: neither is the plate)
    from scipy.signal import butter, sosfiltfilt

    band = butter(8, 2500.0, fs=plate.fs_hz, output="sos")
    acc, ref = sosfiltfilt(band, acc), sosfiltfilt(band, ref)
    err = np.sqrt(np.mean((acc - ref) ** 2) / np.mean(ref**2))
    assert err < 0.03, err  # 1.1 % measured


def test_a_profile_without_a_loopback_is_told_to_name_one(private_dirs, capsys):
    path = _profile(private_dirs, 256, inputs="")
    code = main(["-p", str(path), "frf", "latency"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code != 0
    assert len(err) == 1 and "[audio_inputs" in err[0] and "jackplate.toml" in err[0], err


def test_flow_bench_adds_the_measured_output_latency_else_the_claimed_one(stub_profile):
    from plugins.demos.dac_latency import to_dac

    handed = {"after": {"n": 3, "p50_ms": 1.0, "p99_ms": 2.0, "max_ms": 2.5}}
    measured = to_dac(handed, stub_profile(audio__measured_output_latency_ms=6.27), 0.0107)
    assert measured["after"] == {"n": 3, "p50_ms": 7.27, "p99_ms": 8.27, "max_ms": 8.77}
    assert measured["added_from"].startswith("measured")
    claimed = to_dac(handed, stub_profile(audio__measured_output_latency_ms=-1.0), 0.0107)
    assert claimed["after"]["p99_ms"] == pytest.approx(12.7)
    assert claimed["added_from"].startswith("claimed by the driver")
