"""The gesture dataset format: round trip, synthesis, recording, CLI, and every loader error."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from console.core.errors import UserError
from plugins.gestures.dataset import (
    GESTURES,
    load_dataset,
    read_png,
    read_sample,
    write_background,
    write_sample,
)
from plugins.gestures.dataset_commands import COMMANDS
from plugins.gestures.synth import record, synth


def _frames(n, seed=0, shape=(480, 640)):
    return np.random.default_rng(seed).integers(0, 256, (n, *shape), dtype=np.uint8)


def _one_line(exc: pytest.ExceptionInfo) -> str:
    msg = str(exc.value)
    assert "\n" not in msg
    return msg


def test_round_trip_keeps_frames_labels_and_backgrounds(tmp_path):
    fr = _frames(5)
    bg = _frames(1, 1)[0]
    write_sample(
        tmp_path,
        "drag",
        "s1_000",
        fr,
        subject="s1",
        hand="left",
        fps=60,
        background=bg,
        extra={"note": "x"},
    )
    write_sample(tmp_path, "one_finger", "s2_000", fr[:1], subject="s2", hand="right", fps=30)
    root_bg = _frames(1, 2)[0]
    write_background(tmp_path, root_bg)
    samples = load_dataset(tmp_path, check_images=True)
    assert [s.name for s in samples] == ["drag/s1_000", "one_finger/s2_000"]
    d, o = samples
    assert (d.gesture, d.subject, d.hand, d.fps, d.kind) == ("drag", "s1", "left", 60.0, "dynamic")
    assert np.array_equal(d.frames(), fr) and np.array_equal(d.background(), bg)
    assert d.meta == {"note": "x"}
    assert o.kind == "static" and o.n_frames == 1
    assert np.array_equal(o.background(), root_bg)  # falls back to DATASET/background.png
    assert np.array_equal(d.frames(limit=4), fr[:4])
    meta = json.loads((tmp_path / "drag/s1_000/sample.json").read_text())
    assert meta == {"subject": "s1", "gesture": "drag", "hand": "left", "fps": 60, "note": "x"}


def test_a_dataset_made_by_hand_with_cv2_loads(tmp_path):
    """Someone else's recording: plain cv2.imwrite PNGs and a hand-written sample.json."""
    d = tmp_path / "ds" / "zoom" / "take1"
    d.mkdir(parents=True)
    for i in range(4):
        cv2.imwrite(str(d / f"frame_{i:03d}.png"), _frames(1, i)[0])
    (d / "sample.json").write_text(
        '{"subject": "anna", "gesture": "zoom", "hand": "right", "fps": 59.94}'
    )
    (s,) = load_dataset(tmp_path / "ds")
    assert s.frames().shape == (4, 480, 640) and s.fps == 59.94 and s.background() is None


def _sample(tmp_path, gesture="drag", n=4, name="s1_000", **meta):
    d = write_sample(
        tmp_path,
        gesture,
        name,
        _frames(max(n, 4))[:n] if n >= 4 else _frames(4),
        subject="s1",
        hand="right",
        fps=60,
    )
    for p in d.glob("frame_*.png"):
        if int(p.stem.split("_")[1]) >= n:
            p.unlink()
    if meta:
        m = json.loads((d / "sample.json").read_text())
        m.update(meta)
        (d / "sample.json").write_text(json.dumps(m))
    return d


@pytest.mark.parametrize(
    ("breakage", "expect"),
    [
        (lambda d: (d / "sample.json").unlink(), "no sample.json"),
        (lambda d: (d / "sample.json").write_text('{"subject": "s1", '), "malformed JSON"),
        (lambda d: (d / "sample.json").write_text("[1, 2]"), "not an object"),
        (lambda d: (d / "sample.json").write_bytes(b"\xff\xfe{"), "not UTF-8"),
        (
            lambda d: (d / "sample.json").write_text('{"subject": "s1", "gesture": "drag"}'),
            "missing 'hand'",
        ),
        (lambda d: _set(d, gesture="wave"), "unknown gesture 'wave'"),
        (lambda d: _set(d, gesture="zoom"), "in the 'drag' folder"),
        (lambda d: _set(d, hand="both"), "'left' or 'right'"),
        (lambda d: _set(d, fps=0), "positive number"),
        (lambda d: _set(d, fps="60"), "positive number"),
        (lambda d: _set(d, subject=""), "non-empty string"),
        (lambda d: (d / "frame_003.png").unlink(), "needs at least 4"),
        (lambda d: (d / "frame_001.png").rename(d / "frame_007.png"), "frame_001.png is missing"),
    ],
)
def test_loader_errors_name_the_sample(tmp_path, breakage, expect):
    d = _sample(tmp_path)
    breakage(d)
    with pytest.raises(UserError) as exc:
        load_dataset(tmp_path)
    msg = _one_line(exc)
    assert expect in msg and str(d) in msg


def _set(d: Path, **kw):
    m = json.loads((d / "sample.json").read_text())
    m.update(kw)
    (d / "sample.json").write_text(json.dumps(m))


@pytest.mark.parametrize(
    ("image", "expect"),
    [
        (np.zeros((480, 320), np.uint8), "320 x 480 px; expected 640 x 480"),
        (np.zeros((480, 640, 3), np.uint8), "3 channels"),
        (np.zeros((480, 640), np.uint16), "uint16 pixels"),
        (None, "not a readable PNG"),
    ],
)
def test_bad_frame_images_are_refused_naming_the_file(tmp_path, image, expect):
    d = _sample(tmp_path, "one_finger", n=4)
    p = d / "frame_002.png"
    if image is None:
        p.write_bytes(b"this is not a png")
    else:
        cv2.imwrite(str(p), image)
    (s,) = load_dataset(tmp_path)  # cheap listing does not decode
    with pytest.raises(UserError) as exc:
        s.frames()
    msg = _one_line(exc)
    assert expect in msg and "one_finger/s1_000/frame_002.png" in msg
    with pytest.raises(UserError):
        load_dataset(tmp_path, check_images=True)


def test_frames_of_mixed_sizes_are_refused_when_size_is_free(tmp_path):
    d = _sample(tmp_path, "drag", n=4)
    cv2.imwrite(str(d / "frame_001.png"), np.zeros((240, 320), np.uint8))
    with pytest.raises(UserError, match="all frames of a sample must have one size"):
        read_sample(d).frames(size_px=None)


def test_dataset_level_errors(tmp_path):
    with pytest.raises(UserError, match="no such dataset folder"):
        load_dataset(tmp_path / "nope")
    with pytest.raises(UserError, match="no samples found"):
        load_dataset(tmp_path)
    (tmp_path / "waving").mkdir()
    with pytest.raises(UserError, match="unknown gesture folder 'waving'"):
        load_dataset(tmp_path)


def test_read_png_directly_names_the_file(tmp_path):
    with pytest.raises(UserError, match="cannot read"):
        read_png(tmp_path / "missing.png")


def test_synth_small_set_is_complete_labelled_and_deterministic(tmp_path):
    a = synth(tmp_path / "a", subjects=2, reps=1, seed=3, workers=1)
    assert a["samples"] == 20 and a["subjects"] == ["s1", "s2"]
    samples = load_dataset(tmp_path / "a", check_images=True)
    assert len(samples) == 20
    assert {s.gesture for s in samples} == set(GESTURES)
    assert {s.hand for s in samples if s.subject == "s1"} == {"right"}
    assert {s.hand for s in samples if s.subject == "s2"} == {"left"}  # the last is left-handed
    for s in samples:
        assert s.n_frames == (6 if s.kind == "static" else 8)
        assert s.background_path == s.path / "background.png"
        t = s.truth()
        assert t["gesture"] == s.gesture and t["subject"] == s.subject and t["hand"] == s.hand
        assert len(t["frames"]) == s.n_frames
    b = synth(tmp_path / "b", subjects=2, reps=1, seed=3, workers=2, gestures=("drag", "zoom"))
    assert b["samples"] == 4
    for g in ("drag", "zoom"):  # same seed, other worker count: identical files
        for f in ("frame_000.png", "frame_007.png", "background.png", "truth.json"):
            pa, pb = (tmp_path / x / g / "s2_000" / f for x in ("a", "b"))
            assert pa.read_bytes() == pb.read_bytes()
    c = synth(tmp_path / "c", subjects=1, reps=1, seed=4, workers=1, gestures=("drag",))
    assert c["samples"] == 1
    fa = cv2.imread(str(tmp_path / "a/drag/s1_000/frame_000.png"), cv2.IMREAD_UNCHANGED)
    fc = cv2.imread(str(tmp_path / "c/drag/s1_000/frame_000.png"), cv2.IMREAD_UNCHANGED)
    assert not np.array_equal(fa, fc)


def test_synth_refuses_a_non_empty_folder_and_bad_counts(tmp_path):
    (tmp_path / "x.txt").write_text("keep me")
    with pytest.raises(UserError, match="not empty"):
        synth(tmp_path, subjects=1, reps=1)
    with pytest.raises(UserError, match="at least 1"):
        synth(tmp_path / "n", subjects=0, reps=1)
    with pytest.raises(UserError, match="unknown"):
        synth(tmp_path / "g", subjects=1, reps=1, gestures=("wave",))
    with pytest.raises(UserError, match="--left-handed 3"):
        synth(tmp_path / "h", subjects=2, reps=1, left_handed=3)


def test_record_from_the_twin_camera(tmp_path):
    from plugins.twin.camera.camera import TwinCamera

    cam = TwinCamera(realtime=False)
    p1 = record(cam, tmp_path, "rotate", "s4", hand="left", frames=6)
    p2 = record(cam, tmp_path, "open_hand", "s4")
    p3 = record(cam, tmp_path, "rotate", "s4", frames=5)
    assert (p1.name, p3.name) == ("s4_000", "s4_001")
    by = {s.path: s for s in load_dataset(tmp_path, check_images=True)}
    assert by[p1].n_frames == 6 and by[p1].hand == "left" and by[p1].gesture == "rotate"
    assert by[p2].n_frames == 6 and by[p2].meta["source"] == "twin"
    assert by[p1].fps == 60.0


class _PlainCamera:
    """A camera with nothing but the protocol (like a real driver)."""

    def __init__(self, frames=None):
        self.frames, self.k = frames, 0

    def read(self, timeout_s=0.1):
        from console.core.types import Frame

        if self.frames is not None and self.k >= self.frames:
            return None
        self.k += 1
        return Frame(image=np.full((480, 640), self.k, np.uint8), seq=self.k, t_capture_s=0.0)

    def status(self):
        return {"driver": "plain", "fps": 30.0, "dropped": 0}

    def close(self):
        pass


def test_record_from_any_camera_and_errors(tmp_path):
    from plugins.gestures.synth import capture_background

    cam = _PlainCamera()
    bg = capture_background(cam, n_frames=3)
    p = record(cam, tmp_path, "wipe", "s1", frames=4, background=bg)
    (s,) = load_dataset(tmp_path, check_images=True)
    assert s.path == p and s.fps == 30.0 and s.meta["source"] == "plain"
    assert [int(f[0, 0]) for f in s.frames()] == [4, 5, 6, 7] and s.background()[0, 0] == 2
    with pytest.raises(UserError, match="no frame"):
        record(_PlainCamera(frames=0), tmp_path, "drag", "s1", frames=4, timeout_s=0.05)
    with pytest.raises(UserError, match="needs at least 4"):
        record(cam, tmp_path, "drag", "s1", frames=2)
    with pytest.raises(UserError, match="unknown"):
        record(cam, tmp_path, "wave", "s1")


def _parse(name, argv):
    configure, run, _ = COMMANDS[name]
    parser = argparse.ArgumentParser()
    configure(parser)
    return parser.parse_args(argv), run


def test_cli_synth_and_record(tmp_path, plugins, capsys):
    args, run = _parse(
        "synth",
        [
            "--subjects",
            "1",
            "--reps",
            "1",
            "--out",
            str(tmp_path / "d"),
            "--gestures",
            "drag,l_shape",
            "--workers",
            "1",
            "--json",
        ],
    )
    assert run(args, None) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["samples"] == 2
    from console.config.profile import PROJECT_PROFILES, load_profile

    toml = tmp_path / "fast.toml"
    sim = (PROJECT_PROFILES / "sim.toml").read_text()  # a profile needs its patches
    toml.write_text(sim + "\n[twin_camera]\nrealtime = false\n")
    ctx = SimpleNamespace(profile=load_profile(toml, plugins), pm=plugins)
    args, run = _parse(
        "record",
        [
            "--gesture",
            "zoom",
            "--subject",
            "s9",
            "--out",
            str(tmp_path / "d"),
            "--frames",
            "5",
            "--background",
            "--json",
        ],
    )
    assert run(args, ctx) == 0
    out = json.loads(capsys.readouterr().out)
    s = read_sample(out["sample"])
    assert s.gesture == "zoom" and s.n_frames == 5 and s.background_path.parent == s.path
    assert len(load_dataset(tmp_path / "d")) == 3
