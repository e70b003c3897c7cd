"""What the console writes for a profile goes to the user's state directory, never beside
the profile: a profile in a read-only folder calibrates and saves; a path the profile names
is honoured; an old default file beside the profile is read and said so, once."""

from __future__ import annotations

import json
import logging
import os
import shutil
import stat
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from console.cli.main import main
from console.config import profile_files
from console.config.profile import PROJECT_PROFILES, load_profile
from console.core.errors import UserError
from console.files import paths

TABLE = (743.46, 447.29)


@pytest.fixture(autouse=True)
def _fresh_log_memory(monkeypatch):
    monkeypatch.setattr(profile_files, "_told", set())


@pytest.fixture
def ro_folder(tmp_path):
    """A folder holding a copy of the sim profile as ``bench.toml``, made read-only (root
    may write anyway: the tests also check that nothing in it changed)."""
    folder = tmp_path / "readonly"
    folder.mkdir()
    shutil.copy(PROJECT_PROFILES / "sim.toml", folder / "bench.toml")
    yield folder
    folder.chmod(stat.S_IRWXU)


def _lock(folder: Path) -> list[str]:
    folder.chmod(stat.S_IRUSR | stat.S_IXUSR)
    return sorted(os.listdir(folder))


def _touch_fit():
    """A real touch calibration fitted to a known homography (camera px -> table mm)."""
    import cv2

    from plugins.gestures.calibration import calibrate, target_grid

    mm = np.asarray(target_grid(TABLE, 4, 3), float)
    src = np.float32([[0, 0], [TABLE[0], 0], [TABLE[0], TABLE[1]], [0, TABLE[1]]])
    dst = np.float32([[40, 30], [600, 45], [610, 450], [30, 440]])
    h = cv2.getPerspectiveTransform(src, dst)
    px = cv2.perspectiveTransform(mm.reshape(-1, 1, 2), h).reshape(-1, 2)
    return calibrate(px, mm), px, mm


def test_defaults_are_in_the_profiles_state_directory(ro_folder, plugins):
    from plugins.gestures.settings import calibration_file, model_file
    from plugins.projector.settings import calibration_path_for

    prof = load_profile(ro_folder / "bench.toml", plugins)
    home = paths.profile_state_dir("bench")
    assert calibration_file(prof) == home / "touch_calibration.json"
    assert model_file(prof) == home / "gestures.skops"
    assert calibration_path_for(prof) == home / "projector.json"
    assert str(home).startswith(os.environ["HAPTABLE_STATE_DIR"])


def test_touch_calibration_saved_on_a_read_only_profile_is_read_back(ro_folder, plugins):
    """The console's wizard saves where the classifier reads, outside the profile's folder."""
    from console.session.calibration import TouchCalibration
    from plugins.gestures.classifier import SvmClassifier

    before = _lock(ro_folder)
    prof = load_profile(ro_folder / "bench.toml", plugins)
    wizard = TouchCalibration(SimpleNamespace(profile=prof, emit=lambda event: None))
    with pytest.raises(UserError, match="run it first"):
        wizard.save()
    wizard.result, px, mm = _touch_fit()
    dest = wizard.save()
    assert dest == paths.profile_state_dir("bench", "touch_calibration.json")
    assert json.loads(dest.read_text())["format"].startswith("haptable-touch-calibration")
    assert sorted(os.listdir(ro_folder)) == before
    clf = SvmClassifier.from_profile(prof)
    assert clf.to_mm is not None
    np.testing.assert_allclose(clf.to_mm(px), mm, atol=0.5)


def test_projector_calibration_on_a_read_only_profile(ro_folder, capsys):
    before = _lock(ro_folder)
    prof = str(ro_folder / "bench.toml")
    assert main(["-p", prof, "projector", "--set-corner", "2", "1275", "3"]) == 0
    out = capsys.readouterr().out
    home = paths.profile_state_dir("bench", "projector.json")
    assert f"saved {home}" in out
    saved = json.loads(home.read_text())
    assert [1275.0, 3.0] in [[float(v) for v in p["px"]] for p in saved["points"]]
    assert sorted(os.listdir(ro_folder)) == before


def test_a_path_the_profile_names_is_honoured(tmp_path, plugins):
    from plugins.gestures.settings import calibration_file
    from plugins.projector.settings import calibration_path_for

    text = (PROJECT_PROFILES / "sim.toml").read_text()
    assert "[vision]" not in text and "[projector]" not in text
    text += '\n[vision]\ncalibration = "cal/touch.json"\n'
    text += '\n[projector]\ncalibration_path = "proj.json"\n'
    (tmp_path / "named.toml").write_text(text)
    prof = load_profile(tmp_path / "named.toml", plugins)
    assert calibration_file(prof) == tmp_path / "cal" / "touch.json"
    assert calibration_path_for(prof) == tmp_path / "proj.json"
    fit, _, _ = _touch_fit()
    fit.save(calibration_file(prof))  # its folder is made
    assert (tmp_path / "cal" / "touch.json").is_file()
    assert not paths.profile_state_dir("named").exists()


def test_an_old_default_file_beside_the_profile_is_read_and_said_once(ro_folder, plugins, caplog):
    from plugins.gestures.classifier import SvmClassifier
    from plugins.gestures.settings import calibration_file

    fit, px, mm = _touch_fit()
    old = fit.save(ro_folder / "touch_calibration.json")  # where earlier versions kept it
    before = _lock(ro_folder)
    prof = load_profile(ro_folder / "bench.toml", plugins)
    home = paths.profile_state_dir("bench", "touch_calibration.json")
    with caplog.at_level(logging.WARNING, logger="haptable.files"):
        clf = SvmClassifier.from_profile(prof)
        assert calibration_file(prof) == home
    np.testing.assert_allclose(clf.to_mm(px), mm, atol=0.5)  # the old file's content
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1, lines
    assert str(old) in lines[0] and str(home) in lines[0] and "[vision] calibration" in lines[0]
    assert home.read_bytes() == old.read_bytes()
    assert sorted(os.listdir(ro_folder)) == before  # the old one stays where it was

    # a later run: both exist, the state directory's is used and the old one named
    profile_files._told.clear()
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="haptable.files"):
        assert calibration_file(prof) == home
    (line,) = [r.getMessage() for r in caplog.records]
    assert "not used" in line and str(old) in line and str(home) in line


def test_an_old_projector_calibration_keeps_its_old_name(ro_folder, plugins):
    from plugins.projector.geometry import default_calibration, save_calibration
    from plugins.projector.settings import calibration_path_for

    cal = default_calibration((1280, 800)).with_point((TABLE[0], 0.0), (1250.0, 30.0))
    save_calibration(cal, ro_folder / "bench.projector.json")
    _lock(ro_folder)
    prof = load_profile(ro_folder / "bench.toml", plugins)
    home = calibration_path_for(prof)
    assert home == paths.profile_state_dir("bench", "projector.json")
    assert home.read_bytes() == (ro_folder / "bench.projector.json").read_bytes()


def test_a_state_directory_that_cannot_be_written_is_one_line(ro_folder, plugins, monkeypatch):
    from plugins.gestures.settings import calibration_file

    fit, _, _ = _touch_fit()
    fit.save(ro_folder / "touch_calibration.json")
    blocker = ro_folder.parent / "a-file"
    blocker.write_text("")
    monkeypatch.setenv("HAPTABLE_STATE_DIR", str(blocker / "state"))
    prof = load_profile(ro_folder / "bench.toml", plugins)
    with pytest.raises(UserError) as err:
        calibration_file(prof)
    msg = str(err.value)
    assert "\n" not in msg and "HAPTABLE_STATE_DIR" in msg and str(blocker) in msg
    with pytest.raises(UserError, match="cannot write the touch calibration"):
        fit.save(blocker / "state" / "touch_calibration.json")
