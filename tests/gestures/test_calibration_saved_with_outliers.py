"""A touch calibration with an outlier dropped: what the wizard saves, the classifier (the
demos) and `haptable doctor` read back."""

import json
import os
import subprocess
import sys

import numpy as np

from console.config.plugins import load_plugins
from console.config.profile import load_profile
from plugins.gestures.calibration import Calibration, calibrate, target_grid
from plugins.gestures.settings import calibration_file

TABLE = (743.46, 447.29)


def with_outlier() -> Calibration:
    rng = np.random.default_rng(5)
    mm = target_grid(TABLE, 4, 3)
    px = mm * 0.8 + 30.0 + rng.normal(0, 0.5, mm.shape)
    px[5] += (70.0, -50.0)  # one touch far off its target
    cal = calibrate(px, mm)
    assert cal.outliers == [5]
    return cal


def test_a_calibration_with_an_outlier_saves_and_loads_back(tmp_path):
    cal = with_outlier()
    back = Calibration.load(cal.save(tmp_path / "touch_calibration.json"))
    q = np.array([[100.0, 100.0], [300.0, 200.0]])
    np.testing.assert_allclose(back.px_to_mm(q), cal.px_to_mm(q), atol=1e-9)
    assert back.report() == cal.report() and back.outliers == [5]


def _doctor(env: dict) -> tuple[int, dict]:
    out = subprocess.run(
        [
            sys.executable,
            "-c",
            "from console.cli.entry import main; raise SystemExit(main())",
            "doctor",
            "--json",
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    return out.returncode, json.loads(out.stdout)


def test_doctor_reads_the_saved_calibration_as_the_demos_do():
    prof = load_profile("sim", load_plugins())
    path = calibration_file(prof)
    with_outlier().save(path)
    env = dict(os.environ)
    code, data = _doctor(env)
    row = next(d for d in data["devices"] if d["kind"] == "gestures")
    assert code == 0 and row["state"] == "ok" and "touch calibration" in row["why"]
    path.write_text(path.read_text().replace('"inliers"', '"inlier"'))
    code, data = _doctor(env)
    row = next(d for d in data["devices"] if d["kind"] == "gestures")
    assert code == 1 and row["state"] == "error" and str(path) in row["why"]
    assert "k" in row["fix"] and "S" in row["fix"]


def test_the_demos_classifier_starts_with_it():
    from plugins.gestures.classifier import SvmClassifier

    prof = load_profile("sim", load_plugins())
    cal = with_outlier()
    cal.save(calibration_file(prof))
    clf = SvmClassifier.from_profile(prof)  # what the camera builds for flow and knob
    q = np.array([[120.0, 90.0]])
    np.testing.assert_allclose(clf.to_mm(q), cal.px_to_mm(q), atol=1e-9)
