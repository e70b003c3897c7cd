"""Haptic files as large as real ones: 1000 breakpoints import whole.

The breakpoints of an imported file live beside the library (``signals/NAME.json``,
``console.signals.breakpoint_data``) and the library entry names them
(``glide(100 V, @NAME) * env(@NAME) + bursts(@NAME)``), so no file is thinned to fit an
expression. The files are generated here; the played envelope (the carrier's crests) is
compared with the file's breakpoints interpolated by numpy, the round trip export ->
import with the Hilbert envelope of both sides. The ``.haptic`` keys follow the public
files of facebook/meta-haptics-sdk, ``core/haptic_data/test_files/multiple_emphasis.haptic``
(metadata with ``author``, emphases on amplitude breakpoints, a frequency envelope
starting after 0).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.signal import find_peaks, hilbert

from console.cli.main import main
from console.config.signal_library import get_signal, library_data, library_path
from console.signals.breakpoint_data import data_path
from console.signals.design import render
from console.signals.expr import parse

FS = 48_000
PEAK_V = 100.0  # sim: the largest sine the gate allows on the patches


def _haptic_doc(n: int, emphases: bool) -> dict:
    """``n`` amplitude breakpoints over 5 s: a slow swell with seeded jitter, 0 at the
    ends, a few emphases; 200 frequency breakpoints in 0.6..0.9."""
    rng = np.random.default_rng(7)
    t = np.linspace(0.0, 5.0, n)
    a = 0.4 + 0.2 * np.sin(2 * np.pi * 0.7 * t) + rng.uniform(-0.05, 0.05, n)
    a[[0, -1]] = 0.0
    amp = [
        {"time": float(ti), "amplitude": round(float(ai), 4)} for ti, ai in zip(t, a, strict=True)
    ]
    if emphases:
        for k in (n * 3 // 20, n * 2 // 5, n * 13 // 20, n * 9 // 10):
            amp[k]["emphasis"] = {"amplitude": 0.3, "frequency": 0.7}
    tf = np.linspace(0.0, 5.0, 200)
    freq = [{"time": float(ti), "frequency": round(0.75 + 0.15 * np.sin(ti), 4)} for ti in tf]
    return {
        "version": {"major": 1, "minor": 0, "patch": 0},
        "metadata": {"editor": "test", "author": "HapTable tests", "source": "",
                     "project": "", "tags": ["Test"], "description": "1000 breakpoints"},
        "signals": {"continuous": {"envelopes": {"amplitude": amp, "frequency": freq}}},
    }  # fmt: skip


def _ahap_doc(n: int) -> dict:
    """One continuous event of 5 s under an intensity curve of ``n`` control points, in
    ParameterCurves of 16 points (what Core Haptics accepts), each starting where the one
    before ended."""
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 5.0, n)
    v = np.clip(0.5 + 0.3 * np.sin(2 * np.pi * 0.5 * t) + rng.uniform(-0.1, 0.1, n), 0, 1)
    v[[0, -1]] = 0.0
    pattern: list = [{"Event": {"Time": 0.0, "EventType": "HapticContinuous",
                                "EventDuration": 5.0, "EventParameters": [
                                    {"ParameterID": "HapticIntensity", "ParameterValue": 1.0},
                                    {"ParameterID": "HapticSharpness", "ParameterValue": 0.8}]}}]  # fmt: skip
    i = 0
    while i < n - 1:
        j = min(i + 16, n)
        pts = [{"Time": round(float(t[k] - t[i]), 6), "ParameterValue": round(float(v[k]), 4)}
               for k in range(i, j)]  # fmt: skip
        pattern.append({"ParameterCurve": {"ParameterID": "HapticIntensityControl",
                                           "Time": round(float(t[i]), 6),
                                           "ParameterCurveControlPoints": pts}})  # fmt: skip
        i = j - 1
    return {"Version": 1.0, "Pattern": pattern}


def _rendered(name: str) -> np.ndarray:
    lib = library_path("sim")
    return render(parse(get_signal(lib, name).expr, data=library_data(lib)), FS, max_s=60)


def _crest_error(x: np.ndarray, t_ref, a_ref, skip: list[float]) -> float:
    """Largest gap between the carrier's crests and the file's breakpoints, as a
    fraction of full scale (away from the gate's end ramps and the bursts)."""
    k, _ = find_peaks(np.abs(x))
    t, crest = k / FS, np.abs(x[k])
    ok = (t > 0.03) & (t < t_ref[-1] - 0.03)
    for s in skip:
        ok &= np.abs(t - s - 0.01) > 0.03
    ref = np.interp(t[ok], t_ref, a_ref) * PEAK_V
    return float(np.max(np.abs(crest[ok] - ref)) / PEAK_V)


def _import(path, name, capsys) -> str:
    capsys.readouterr()
    assert main(["signals", "import", str(path), "--name", name]) == 0
    return capsys.readouterr().out


def test_1000_breakpoint_haptic_imports_whole_plays_and_round_trips(tmp_path, capsys):
    doc = _haptic_doc(1000, emphases=True)
    f = tmp_path / "big.haptic"
    f.write_text(json.dumps(doc), encoding="utf-8")
    out = _import(f, "big", capsys)
    assert "1000 amplitude breakpoints" in out and "4 bursts" in out
    expr = get_signal(library_path("sim"), "big").expr
    assert expr == "glide(100 V, @big) * env(@big) + bursts(@big)"
    assert data_path(library_path("sim"), "big").is_file()
    amp = doc["signals"]["continuous"]["envelopes"]["amplitude"]
    t_ref = np.array([p["time"] for p in amp])
    a_ref = np.array([p["amplitude"] for p in amp])
    x = _rendered("big")
    err = _crest_error(x, t_ref, a_ref, [float(t_ref[k]) for k in (150, 400, 650, 900)])
    assert err < 0.01, f"envelope off by {err:.2%}"
    assert main(["signals", "play", "big", "--patch", "PA", "--dry-run"]) == 0
    assert main(["signals", "show", "big"]) == 0
    assert "5.000 s" in capsys.readouterr().out


@pytest.mark.parametrize("fmt", ["haptic", "ahap"])
def test_export_then_import_keeps_1000_breakpoints_within_1_percent(fmt, tmp_path, capsys):
    f = tmp_path / "plain.haptic"
    f.write_text(json.dumps(_haptic_doc(1000, emphases=False)), encoding="utf-8")
    _import(f, "plain", capsys)
    back = tmp_path / f"back.{fmt}"
    assert main(["signals", "export", "plain", "--format", fmt, "-o", str(back)]) == 0
    _import(back, "back", capsys)
    x0, x1 = _rendered("plain"), _rendered("back")
    n = min(x0.size, x1.size)
    assert abs(x0.size - x1.size) <= 2
    e0, e1 = np.abs(hilbert(x0[:n])), np.abs(hilbert(x1[:n]))
    inner = slice(round(0.02 * FS), n - round(0.02 * FS))  # the transform's own edges
    err = float(np.max(np.abs(e0[inner] - e1[inner])) / PEAK_V)
    assert err < 0.01, f"round trip envelope off by {err:.2%}"


def test_1000_point_ahap_imports_within_1_percent(tmp_path, capsys):
    doc = _ahap_doc(1000)
    f = tmp_path / "big.ahap"
    f.write_text(json.dumps(doc), encoding="utf-8")
    out = _import(f, "bigahap", capsys)
    assert "67 HapticIntensityControl" in out
    t_ref, a_ref = [], []
    for e in doc["Pattern"][1:]:
        c = e["ParameterCurve"]
        for p in c["ParameterCurveControlPoints"]:
            t_ref.append(c["Time"] + p["Time"])
            a_ref.append(p["ParameterValue"])
    t_ref, keep = np.unique(np.array(t_ref), return_index=True)
    err = _crest_error(_rendered("bigahap"), t_ref, np.array(a_ref)[keep], [])
    assert err < 0.01, f"envelope off by {err:.2%}"
    assert main(["signals", "play", "bigahap", "--patch", "PALL", "--dry-run"]) == 0


def _one_line(capsys, *argv) -> str:
    capsys.readouterr()
    rc = main(list(argv))
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    return err[0]


DAMAGES = [
    ("edited", lambda d: d.replace('"level":[0.0,', '"level":[0.5,'), ("sha256", "does not match")),
    ("truncated", lambda d: d[: len(d) // 2], ("line 1",)),
    ("not-a-number", lambda d: d.replace('"level":[', '"level":["x",'), ("env.level", "number")),
    ("wrong-length", lambda d: d.replace('"level":[0.0,', '"level":['), ("env.level", "values")),
    ("missing", None, ("@cut", "missing")),
]  # fmt: skip


def test_damaged_data_file_is_one_line_and_never_plays(tmp_path, capsys):
    f = tmp_path / "cut.haptic"
    f.write_text(json.dumps(_haptic_doc(50, emphases=False)), encoding="utf-8")
    _import(f, "cut", capsys)
    data = data_path(library_path("sim"), "cut")
    good = data.read_text()
    for i, (what, damage, words) in enumerate(DAMAGES):
        if damage is None:
            data.unlink()
        else:
            data.write_text(damage(good))
        action = ["play", "cut", "--patch", "PA", "--dry-run"] if i % 2 else ["show", "cut"]
        line = _one_line(capsys, "signals", *action)
        assert str(data) in line and "--replace" in line, (what, line)
        for w in words:
            assert w in line, (what, line)
    # re-importing mends it; rm takes the data with the entry
    assert main(["signals", "import", str(f), "--name", "cut", "--replace"]) == 0
    assert main(["signals", "play", "cut", "--patch", "PA", "--dry-run"]) == 0
    capsys.readouterr()
    assert main(["signals", "rm", "cut"]) == 0
    assert "and its breakpoint data" in capsys.readouterr().out
    assert not data.exists()


def test_refused_import_leaves_the_saved_data_as_it_was(tmp_path, capsys):
    f = tmp_path / "keep.haptic"
    f.write_text(json.dumps(_haptic_doc(100, emphases=False)), encoding="utf-8")
    _import(f, "keep", capsys)
    data = data_path(library_path("sim"), "keep")
    before = data.read_bytes()
    g = tmp_path / "other.haptic"
    g.write_text(json.dumps(_haptic_doc(120, emphases=True)), encoding="utf-8")
    line = _one_line(capsys, "signals", "import", str(g), "--name", "keep")
    assert "'keep'" in line and "--replace" in line
    assert data.read_bytes() == before


def test_data_reference_outside_the_library_is_one_line(capsys):
    line = _one_line(capsys, "signals", "show", "sine(100 Hz, 1 V, 1 s) * env(@nowhere)")
    assert "@nowhere" in line and "missing" in line
    with pytest.raises(Exception, match="kept beside the signal library"):
        parse("sine(100 Hz, 1 V, 1 s) * env(@x)")


def test_the_shape_of_metas_multiple_emphasis_file_imports(tmp_path, capsys):
    """facebook/meta-haptics-sdk core/haptic_data/test_files/multiple_emphasis.haptic as
    published: every key is one this reader knows (nothing dropped but bursts that would
    overlap), the frequency envelope starts at 10 ms, the last breakpoint is at 9 s."""
    amp = [{"time": round(0.01 * i, 2), "amplitude": 0.2,
            "emphasis": {"amplitude": 0.6, "frequency": 0.7}} for i in range(18)]  # fmt: skip
    amp.append({"time": 9.0, "amplitude": 0.5})
    freq = [{"time": 0.01, "frequency": 0.99}, {"time": 0.02, "frequency": 0.54},
            {"time": 0.025, "frequency": 0.8}, {"time": 0.23, "frequency": 0.9}]  # fmt: skip
    doc = {"version": {"major": 1, "minor": 0, "patch": 0},
           "metadata": {"editor": "VSCode", "author": "SDK Team", "source": "", "project": "",
                        "tags": ["Test"], "description": "Testing"},
           "signals": {"continuous": {"envelopes": {"amplitude": amp, "frequency": freq}}}}  # fmt: skip
    f = tmp_path / "multiple_emphasis.haptic"
    f.write_text(json.dumps(doc), encoding="utf-8")
    out = _import(f, "meta", capsys)
    assert "19 amplitude breakpoints, 4 frequency breakpoints, 18 emphases" in out
    dropped = out.split("dropped: ")[1].splitlines()[0]
    assert all(d.strip().startswith("transient at") for d in dropped.split(",")), dropped
    assert main(["signals", "play", "meta", "--patch", "PA", "--dry-run"]) == 0
