"""Malformed profiles, gesture datasets, frames and skops models through the real CLI.

Every case is generated here (no committed binaries) and run as a user would:
``haptable ... `` in-process. A bad input must give exactly one stderr line
``haptable: error: FILE: ...`` naming the file and the key or value, and exit 2: never
an internal error (exit 3), never silently accepted (exit 0). Frames a camera can really
produce (all white, all black, saturated noise) must instead be answered (exit 0).
"""

from __future__ import annotations

import json
import os
import shutil
import struct
import zipfile
import zlib
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from console.cli.main import main
from console.config.profile import PROJECT_PROFILES
from plugins.gestures.model import GESTURES

SIM = (PROJECT_PROFILES / "sim.toml").read_text()

#: name -> (kind, builder(tmp_path, fixtures) -> (argv, [parts the line must hold]))
CASES: dict[str, tuple[str, Callable]] = {}


def case(kind: str, name: str):
    def deco(fn):
        CASES[f"{kind}-{name}"] = (kind, fn)
        return fn

    return deco


def tally(name: str, code: int, clear: bool, line: str = "") -> None:
    """With $HAPTABLE_MALFORMED_TALLY set, append each case's outcome there (for the
    before/after counts in the issue's closing note)."""
    if path := os.environ.get("HAPTABLE_MALFORMED_TALLY"):
        what = {0: "accepted", 3: "internal"}.get(code, "line" if clear else f"exit{code}-unclear")
        with open(path, "a") as f:
            f.write(f"{name}\t{what}\t{line[:400]!r}\n")


def run_cli(capsys, argv: list[str]) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


# ---------------------------------------------------------------------------- profiles
def profile_case(name: str, text: str | bytes, *parts: str, edit: tuple[str, str] | None = None):
    """A profile case: ``text`` (or SIM with ``edit``) written to bad.toml, loaded by
    ``haptable --profile bad.toml play sine-PA --dry-run``."""

    @case("profile", name)
    def build(tmp: Path, fx) -> tuple[list, list[str]]:
        p = tmp / "bad.toml"
        body = text
        if edit is not None:
            assert edit[0] in SIM, edit
            body = SIM.replace(edit[0], edit[1], 1)
        if isinstance(body, bytes):
            p.write_bytes(body)
        else:
            p.write_text(body, encoding="utf-8")
        return ["--profile", p, "play", "sine-PA", "--dry-run"], ["bad.toml", *parts]


profile_case("not-utf8", b'[profile]\ntitle = "caf\xe9"\n', "UTF-8")
profile_case("syntax-error", "", "line 9", edit=("width_mm = 743.46", "width_mm = ="))
profile_case("syntax-unclosed-table", "", "line", edit=("[table]", "[table"))
profile_case("deep-array", "a = " + "[" * 10000 + "]" * 10000 + "\n", "nest")
profile_case("deep-inline-table", "a = " + "{b = " * 3000 + "1" + "}" * 3000 + "\n", "nest")
profile_case("deep-dotted-section", "[" + ".".join(["a"] * 3000) + "]\nx = 1\n", "[a]")
profile_case("empty-file", "", "[patches", "PA")
profile_case("only-title", '[profile]\ntitle = "x"\n', "[patches", "PA")
profile_case(
    "no-patches",
    "",
    "[patches",
    edit=(SIM[SIM.index("[patches.PA]") : SIM.index("[screen]")], ""),
)
profile_case("patch-missing-channel", "", "relay_channel", edit=("relay_channel = 3\n", ""))
profile_case(
    "string-for-float", "", "width_mm", '"wide"', edit=("width_mm = 743.46", 'width_mm = "wide"')
)
profile_case(
    "nan-float", "", "full_scale_v", "nan", edit=("full_scale_v = 2.0", "full_scale_v = nan")
)
profile_case(
    "inf-float", "", "piezo_max_v", "inf", edit=("piezo_max_v = 250.0", "piezo_max_v = inf")
)
profile_case(
    "nan-in-list",
    "",
    "origin_mm",
    edit=("origin_mm = [41.73, 43.645]", "origin_mm = [nan, 43.645]"),
)
profile_case("nan-int", "", "channels", edit=("channels = 8", "channels = nan"))
profile_case("nan-unbounded", "", "exposure", edit=("fps = 60.0", "fps = 60.0\nexposure = -nan"))
profile_case("bool-for-int", "", "channels", edit=("channels = 8", "channels = true"))
profile_case(
    "date-for-float", "", "thickness_mm", edit=("thickness_mm = 3.18", "thickness_mm = 1979-05-27")
)
profile_case(
    "out-of-range", "", "sample_rate_hz", edit=("sample_rate_hz = 48000", "sample_rate_hz = 1")
)
profile_case(
    "huge-int-in-float", "", "width_mm", edit=("width_mm = 743.46", "width_mm = 1" + "0" * 400)
)
profile_case("4000-digit-int", "", "digits", edit=("rows = 7", "rows = 1" + "0" * 4400))
profile_case("guard-zero", "", "guard_ms", edit=("guard_ms = 5.0", "guard_ms = 0.0"))
profile_case(
    "switch-zero", "", "switch_time_ms", edit=("switch_time_ms = 2.0", "switch_time_ms = 0")
)
profile_case(
    "guard-shorter-than-switch",
    "",
    "guard_ms",
    "switch_time_ms",
    edit=("switch_time_ms = 2.0\nguard_ms = 5.0", "switch_time_ms = 3.0\nguard_ms = 1.5"),
)
profile_case(
    "screen-on-patch-channel",
    "",
    "relay_channel = 1",
    edit=("relay_channel = 5", "relay_channel = 1"),
)
profile_case(
    "two-patches-one-channel",
    "",
    "relay_channel = 1",
    edit=("relay_channel = 2", "relay_channel = 1"),
)
profile_case(
    "channel-beyond-board",
    "",
    "relay_channel = 5",
    "channels",
    edit=("channels = 8", "channels = 4"),
)
profile_case("unknown-patch", "", "PE", edit=("[patches.PD]", "[patches.PE]"))
profile_case("section-not-table", "table = 5\n" + SIM.replace("[table]", "[tablex]"), "[table")
profile_case(
    "patch-not-table",
    "",
    "patches.PA",
    edit=("[patches.PA]\n", "[patches]\nPA = 1\n[patches.PZ]\n"),
)
profile_case("unicode-key", "", "title\\u200b", edit=("title = ", '"title\u200b" = '))
profile_case("newline-in-key", "", "\\n", edit=("title = ", '"ti\\ntle" = '))
profile_case("newline-in-section", '["pat\\nches"]\nx = 1\n' + SIM, "\\n")
profile_case("rtl-override-key", "", "\\u202e", edit=("title = ", '"\u202eeltit" = '))
profile_case(
    "newline-in-driver",
    "",
    "driver",
    edit=('driver = "twin"\nsample', 'driver = "tw\\nin"\nsample'),
)
profile_case("nul-in-value", "", "line", edit=("title = ", 'title = "\x00"\nx = '))


@case("profile", "huge-file")
def _huge_profile(tmp: Path, fx):
    p = tmp / "bad.toml"
    with open(p, "wb") as f:
        f.write(SIM.encode())
        f.write(b"# " + b"x" * 1000 + b"\n")
        f.truncate(50 * 1024 * 1024)  # sparse: 50 MB without writing them
    return ["--profile", p, "play", "sine-PA", "--dry-run"], ["bad.toml", "MB"]


@case("profile", "a-directory")
def _dir_profile(tmp: Path, fx):
    p = tmp / "bad.toml"
    p.mkdir()
    return ["--profile", p, "play", "sine-PA", "--dry-run"], ["bad.toml"]


@case("profile", "bad-profile-for-gestures")
def _gestures_bad_profile(tmp: Path, fx):
    p = tmp / "bad.toml"
    p.write_text(SIM.replace("body_threshold", "x") + "\n[vision]\nbody_threshold = -5\n")
    return ["--profile", p, "gestures", "classify", fx.model, fx.sample], [
        "bad.toml",
        "body_threshold",
    ]


# ---------------------------------------------------------------------------- datasets
class Fixtures:
    """A good model and a good sample (copied per case), built once per module."""

    def __init__(self, model: Path, sample: Path, dataset: Path):
        self.model, self.sample_src, self.dataset_src = model, sample, dataset
        self.sample = sample

    def copy_sample(self, tmp: Path) -> Path:
        d = tmp / "set" / "drag" / "s1_000"
        shutil.copytree(self.sample_src.parent.parent, tmp / "set")
        return d

    def copy_dataset(self, tmp: Path) -> Path:
        shutil.copytree(self.dataset_src, tmp / "ds")
        return tmp / "ds"


def png_bytes(img: np.ndarray) -> bytes:
    import cv2

    ok, buf = cv2.imencode(".png", img)
    assert ok
    return buf.tobytes()


def png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def bomb_png(width: int, height: int) -> bytes:
    """A small file whose header declares a huge 8-bit greyscale image."""
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    rows = zlib.compress(b"\x00" * (width + 1) * 4)
    return (
        b"\x89PNG\r\n\x1a\n"
        + png_chunk(b"IHDR", ihdr)
        + png_chunk(b"IDAT", rows)
        + png_chunk(b"IEND", b"")
    )


def sample_case(name: str, *parts: str, where: str = "s1_000"):
    """A case on one sample folder: ``edit(folder)`` then ``gestures classify``; the
    line names ``where`` (the sample, or the dataset's background)."""

    def deco(edit):
        @case("dataset", name)
        def build(tmp: Path, fx):
            d = fx.copy_sample(tmp)
            edit(d)
            return ["gestures", "classify", fx.model, d], [where, *parts]

        return edit

    return deco


def set_meta(d: Path, **kw) -> None:
    meta = json.loads((d / "sample.json").read_text())
    meta.update(kw)
    (d / "sample.json").write_text(json.dumps(meta))


@sample_case("no-sample-json", "sample.json")
def _(d):
    (d / "sample.json").unlink()


@sample_case("bad-json", "sample.json", "line")
def _(d):
    (d / "sample.json").write_text('{"subject": "s1", "gesture": ')


@sample_case("deep-json", "sample.json", "nest")
def _(d):
    (d / "sample.json").write_text("[" * 100000 + "]" * 100000)


@sample_case("deep-json-value", "sample.json", "nest")
def _(d):
    meta = json.loads((d / "sample.json").read_text())
    text = json.dumps(meta)[:-1] + ', "notes": ' + "[" * 100000 + "]" * 100000 + "}"
    (d / "sample.json").write_text(text)


@sample_case("json-not-object", "sample.json", "list")
def _(d):
    (d / "sample.json").write_text("[1, 2]")


@sample_case("json-not-utf8", "sample.json", "UTF-8")
def _(d):
    (d / "sample.json").write_bytes(b'{"subject": "s\xe9"}')


@sample_case("missing-key", "sample.json", "hand")
def _(d):
    meta = json.loads((d / "sample.json").read_text())
    del meta["hand"]
    (d / "sample.json").write_text(json.dumps(meta))


@sample_case("fps-string", "fps", "'60'")
def _(d):
    set_meta(d, fps="60")


@sample_case("fps-nan", "fps", "nan")
def _(d):
    (d / "sample.json").write_text(
        '{"subject": "s1", "gesture": "drag", "hand": "right", "fps": NaN}'
    )


@sample_case("fps-bool", "fps", "True")
def _(d):
    set_meta(d, fps=True)


@sample_case("fps-huge", "fps")
def _(d):
    set_meta(d, fps=1e300)


@sample_case("subject-number", "subject", "5")
def _(d):
    set_meta(d, subject=5)


@sample_case("subject-newline", "subject", "\\n")
def _(d):
    set_meta(d, subject="s1\nsecond line")


@sample_case("hand-both", "hand", "both")
def _(d):
    set_meta(d, hand="both")


@sample_case("hand-list", "hand")
def _(d):
    set_meta(d, hand=["left"])


@sample_case("unknown-gesture", "gesture", "wave")
def _(d):
    set_meta(d, gesture="wave")


@sample_case("gesture-dict", "gesture")
def _(d):
    set_meta(d, gesture={"a": 1})


@sample_case("gesture-folder-mismatch", "gesture", "zoom")
def _(d):
    set_meta(d, gesture="zoom")


@sample_case("frame-wrong-size", "frame_001.png", "320 x 240")
def _(d):
    (d / "frame_001.png").write_bytes(png_bytes(np.zeros((240, 320), np.uint8)))


@sample_case("frame-colour", "frame_001.png", "channels")
def _(d):
    (d / "frame_001.png").write_bytes(png_bytes(np.zeros((480, 640, 3), np.uint8)))


@sample_case("frame-16-bit", "frame_001.png", "uint16")
def _(d):
    (d / "frame_001.png").write_bytes(png_bytes(np.zeros((480, 640), np.uint16)))


@sample_case("frame-truncated", "frame_001.png", "PNG")
def _(d):
    b = (d / "frame_001.png").read_bytes()
    (d / "frame_001.png").write_bytes(b[: len(b) // 2])


@sample_case("frame-not-png", "frame_001.png", "PNG")
def _(d):
    (d / "frame_001.png").write_text("hello")


@sample_case("frame-jpeg-named-png", "frame_001.png", "PNG")
def _(d):
    import cv2

    ok, buf = cv2.imencode(".jpg", np.zeros((480, 640), np.uint8))
    (d / "frame_001.png").write_bytes(buf.tobytes())


@sample_case("frame-zero-bytes", "frame_001.png", "empty")
def _(d):
    (d / "frame_001.png").write_bytes(b"")


@sample_case("frame-directory", "frame_001.png")
def _(d):
    (d / "frame_001.png").unlink()
    (d / "frame_001.png").mkdir()


@sample_case("frame-device", "frame_001.png", "regular file")
def _(d):
    (d / "frame_001.png").unlink()
    (d / "frame_001.png").symlink_to("/dev/zero")


@sample_case("frame-decompression-bomb", "frame_001.png", "30000 x 30000")
def _(d):
    (d / "frame_001.png").write_bytes(bomb_png(30000, 30000))


@sample_case("frame-gap", "frame_001.png", "missing")
def _(d):
    (d / "frame_001.png").rename(d / "frame_009.png")


@sample_case("too-few-frames", "4")
def _(d):
    for p in sorted(d.glob("frame_*.png"))[2:]:
        p.unlink()


@sample_case("background-not-png", "background.png", "PNG", where="set/background.png")
def _(d):
    (d.parent.parent / "background.png").write_text("not an image")


@sample_case("background-wrong-size", "background.png", "320 x 240", where="set/background.png")
def _(d):
    (d.parent.parent / "background.png").write_bytes(png_bytes(np.zeros((240, 320), np.uint8)))


@sample_case("background-bomb", "background.png", "30000 x 30000", where="set/background.png")
def _(d):
    (d.parent.parent / "background.png").write_bytes(bomb_png(30000, 30000))


def dataset_case(name: str, *parts: str):
    """A case on a whole dataset: ``edit(root)`` then ``gestures eval ROOT``."""

    def deco(edit):
        @case("dataset", name)
        def build(tmp: Path, fx):
            root = fx.copy_dataset(tmp)
            edit(root)
            return ["gestures", "eval", root, "--no-cache", "--json"], ["ds", *parts]

        return edit

    return deco


@dataset_case("unknown-gesture-folder", "wave")
def _(root):
    (root / "wave").mkdir()


@dataset_case("empty-dataset", "no samples")
def _(root):
    for d in root.iterdir():
        if d.is_dir():
            shutil.rmtree(d)


@dataset_case("eval-deep-json", "sample.json", "nest")
def _(root):
    (root / "zoom" / "s1_000" / "sample.json").write_text("{" + '"a":{' * 50000 + "}" * 50001)


@dataset_case("eval-frame-bomb", "frame_000.png", "30000 x 30000")
def _(root):
    (root / "zoom" / "s1_000" / "frame_000.png").write_bytes(bomb_png(30000, 30000))


def record_case(name: str, extra: list[str], *parts: str):
    """``haptable gestures record`` options that name or size what is written."""

    @case("dataset", f"record-{name}")
    def build(tmp: Path, fx):
        base = ["gestures", "record", "--gesture", "drag", "--out", tmp / "rec"]
        return [*base, *extra], list(parts)


record_case("frames-huge", ["--subject", "s1", "--frames", "100000000"], "--frames", "100000000")
record_case("subject-path", ["--subject", "../../outside"], "--subject", "../../outside")
record_case("name-path", ["--subject", "s1", "--name", "../x"], "--name", "'../x'")
record_case("subject-newline", ["--subject", "s1\nrm"], "--subject", "\\n")


def synth_case(name: str, extra: list[str], *parts: str):
    @case("dataset", f"synth-{name}")
    def build(tmp: Path, fx):
        return ["gestures", "synth", "--out", tmp / "syn", *extra], list(parts)


synth_case("reps-huge", ["--reps", "1000000000"], "--reps", "1000000000")
synth_case("subjects-zero", ["--subjects", "0"], "--subjects", "0")


# ---------------------------------------------------------------------------- touch calibration
GOOD_CAL = {
    "format": "haptable-touch-calibration/1",
    "homography": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    "centers_px": [[100, 100], [500, 100], [100, 400], [500, 400]],
    "residuals_mm": [[0, 0]] * 4,
    "smoothing": None,
    "inliers": [True] * 4,
    "rms_mm": 0.5,
    "max_mm": 1.0,
    "loo_rms_mm": 1.0,
    "loo_rms_homography_mm": 1.0,
    "image_px": [640, 480],
}


def calibration_case(name: str, *parts: str):
    """The profile's ``[vision] calibration`` file, read when the frame loop starts
    (``haptable tuio``): ``make(path)`` writes it."""

    def deco(make):
        @case("dataset", f"calibration-{name}")
        def build(tmp: Path, fx):
            prof = tmp / "cal.toml"
            prof.write_text(SIM + '\n[vision]\ncalibration = "cal.json"\n')
            make(tmp / "cal.json")
            return ["--profile", prof, "tuio", "--seconds", "0.2"], ["cal.json", *parts]

        return make

    return deco


def cal_with(**kw) -> str:
    return json.dumps({**GOOD_CAL, **kw})


@calibration_case("a-list", "list")
def _(p):
    p.write_text("[1, 2]")


@calibration_case("deep", "nest")
def _(p):
    p.write_text("[" * 100000 + "]" * 100000)


@calibration_case("not-utf8", "UTF-8")
def _(p):
    p.write_bytes(b'{"format": "\xff"}')


@calibration_case("too-large", "MB")
def _(p):
    with open(p, "wb") as f:
        f.truncate(40 * 1024 * 1024)


@calibration_case("no-homography", "homography")
def _(p):
    d = dict(GOOD_CAL)
    del d["homography"]
    p.write_text(json.dumps(d))


@calibration_case("homography-2x2", "homography")
def _(p):
    p.write_text(cal_with(homography=[[1, 0], [0, 1]]))


@calibration_case("residuals-mismatch", "residuals_mm")
def _(p):
    p.write_text(cal_with(residuals_mm=[[0, 0]] * 3))


@calibration_case("centers-nan", "centers_px")
def _(p):
    p.write_text(cal_with(centers_px=[[float("nan"), 1]] * 4))


@calibration_case("smoothing-negative", "smoothing")
def _(p):
    p.write_text(cal_with(smoothing=-1.0))


@calibration_case("image-px-zero", "image_px")
def _(p):
    p.write_text(cal_with(image_px=[0, 480]))


# ---------------------------------------------------------------------------- models
def model_case(name: str, *parts: str):
    def deco(make):
        @case("model", name)
        def build(tmp: Path, fx):
            p = tmp / "bad.skops"
            make(p, fx)
            return ["gestures", "classify", p, fx.sample], ["bad.skops", *parts]

        return make

    return deco


def rewrite_zip(src: Path, dst: Path, edit: Callable[[str, bytes], bytes | None]) -> None:
    with zipfile.ZipFile(src) as zi, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zo:
        for info in zi.infolist():
            data = edit(info.filename, zi.read(info))
            if data is not None:
                zo.writestr(info.filename, data)


def load_parts(fx):
    from plugins.gestures.model import GestureModel

    return None, GestureModel.load(fx.model)


def dump_model(p: Path, m, **changes) -> None:
    """Save ``m`` with fields replaced (bypassing nothing: skops writes what it is given)."""
    import skops.io as sio

    from plugins.gestures.model import MODEL_FORMAT

    obj = {
        "format": MODEL_FORMAT,
        "static_svm": m.static_svm,
        "dynamic_svm": m.dynamic_svm,
        "kind_svm": m.kind_svm,
        "settings": json.dumps(
            {
                "motion_threshold": m.motion_threshold,
                "n_harmonics": m.n_harmonics,
                "n_frames": m.n_frames,
                "meta": m.meta,
            }
        ),
    }
    obj.update(changes)
    sio.dump(obj, p)


@model_case("not-a-zip", "skops")
def _(p, fx):
    p.write_text("hello")


@model_case("empty-file", "skops")
def _(p, fx):
    p.write_bytes(b"")


@model_case("truncated", "skops")
def _(p, fx):
    b = fx.model.read_bytes()
    p.write_bytes(b[: len(b) // 2])


@model_case("no-schema", "schema.json")
def _(p, fx):
    rewrite_zip(fx.model, p, lambda n, b: None if n == "schema.json" else b)


@model_case("schema-not-json", "schema.json")
def _(p, fx):
    rewrite_zip(fx.model, p, lambda n, b: b"{oops" if n == "schema.json" else b)


@model_case("schema-deep", "nest")
def _(p, fx):
    rewrite_zip(
        fx.model, p, lambda n, b: (b"[" * 100000 + b"]" * 100000) if n == "schema.json" else b
    )


@model_case("schema-zip-bomb", "MB")
def _(p, fx):
    def edit(n, b):
        return b + b" " * (64 * 1024 * 1024) if n == "schema.json" else b

    rewrite_zip(fx.model, p, edit)


@model_case("array-truncated", "skops")
def _(p, fx):
    def edit(n, b):
        return b[: len(b) // 2] if n.endswith(".npy") else b

    rewrite_zip(fx.model, p, edit)


@model_case("array-header-huge", "declares shape")
def _(p, fx):
    """An array member whose .npy header declares 10^10 floats in a few bytes."""
    from numpy.lib import format as npformat

    def edit(n, b):
        if not n.endswith(".npy") or b"(6, 35)" not in b and b"'shape': (" not in b:
            return b
        import io

        out = io.BytesIO()
        npformat.write_array_header_1_0(
            out, {"descr": "<f8", "fortran_order": False, "shape": (10**10,)}
        )
        return out.getvalue() + b"\0" * 64

    rewrite_zip(fx.model, p, edit)


@model_case("untrusted-type", "allow-list")
def _(p, fx):
    from sklearn.linear_model import LogisticRegression

    sio, m = load_parts(fx)
    x = np.random.default_rng(0).normal(size=(20, 35))
    y = np.array(["one_finger", "two_finger"] * 10)
    dump_model(p, m, static_svm=LogisticRegression().fit(x, y))


@model_case("no-settings", "settings")
def _(p, fx):
    import skops.io as sio

    from plugins.gestures.model import MODEL_FORMAT

    _, m = load_parts(fx)
    sio.dump({"format": MODEL_FORMAT, "static_svm": m.static_svm}, p)


@model_case("settings-missing-key", "n_frames")
def _(p, fx):
    _, m = load_parts(fx)
    dump_model(p, m, settings=json.dumps({"motion_threshold": 0.1, "n_harmonics": 2}))


@model_case("settings-not-json", "settings")
def _(p, fx):
    _, m = load_parts(fx)
    dump_model(p, m, settings="{oops")


@model_case("settings-n-frames-99", "n_frames", "99")
def _(p, fx):
    _, m = load_parts(fx)
    s = {"motion_threshold": 0.1, "n_harmonics": 2, "n_frames": 99}
    dump_model(p, m, settings=json.dumps(s))


@model_case("settings-harmonics-50", "n_harmonics", "50")
def _(p, fx):
    _, m = load_parts(fx)
    s = {"motion_threshold": 0.1, "n_harmonics": 50, "n_frames": 4}
    dump_model(p, m, settings=json.dumps(s))


@model_case("settings-threshold-nan", "motion_threshold")
def _(p, fx):
    _, m = load_parts(fx)
    s = {"motion_threshold": float("nan"), "n_harmonics": 2, "n_frames": 4}
    dump_model(p, m, settings=json.dumps(s))


@model_case("svm-not-a-pipeline", "static_svm")
def _(p, fx):
    _, m = load_parts(fx)
    dump_model(p, m, static_svm="an svm")


@model_case("no-classifiers", "static_svm")
def _(p, fx):
    _, m = load_parts(fx)
    dump_model(p, m, static_svm=None, dynamic_svm=None, kind_svm=None)


@model_case("other-feature-length", "static_svm", "features")
def _(p, fx):
    from plugins.gestures.model import make_pipeline

    _, m = load_parts(fx)
    rng = np.random.default_rng(0)
    x = rng.normal(size=(20, 6))
    y = np.array(["one_finger", "two_finger"] * 10)
    dump_model(p, m, static_svm=make_pipeline().fit(x, y))


@model_case("scaler-mean-wrong-length", "dynamic_svm", "mean_")
def _(p, fx):
    _, m = load_parts(fx)
    m.dynamic_svm.named_steps["scale"].mean_ = m.dynamic_svm.named_steps["scale"].mean_[:5]
    dump_model(p, m)


@model_case("support-vectors-wrong-width", "kind_svm", "support_vectors_")
def _(p, fx):
    _, m = load_parts(fx)
    svc = m.kind_svm.named_steps["svc"]
    svc.support_vectors_ = np.ascontiguousarray(svc.support_vectors_[:, :7])
    dump_model(p, m)


@model_case("support-vectors-nan", "static_svm", "finite")
def _(p, fx):
    _, m = load_parts(fx)
    svc = m.static_svm.named_steps["svc"]
    sv = svc.support_vectors_.copy()
    sv[0, 0] = np.nan
    svc.support_vectors_ = sv
    dump_model(p, m)


@model_case("dual-coef-wrong-shape", "static_svm", "dual_coef_")
def _(p, fx):
    _, m = load_parts(fx)
    svc = m.static_svm.named_steps["svc"]
    svc._dual_coef_ = np.ascontiguousarray(svc._dual_coef_[:, :3])
    svc.dual_coef_ = svc._dual_coef_
    dump_model(p, m)


@model_case("unknown-class", "static_svm", "wave")
def _(p, fx):
    _, m = load_parts(fx)
    svc = m.static_svm.named_steps["svc"]
    svc.classes_ = np.array(["wave", *svc.classes_[1:]])
    dump_model(p, m)


@model_case("a-directory", "bad.skops")
def _(p, fx):
    p.mkdir()


# ---------------------------------------------------------------------------- plan lengths
@pytest.fixture(scope="module")
def vmap_file(tmp_path_factory):
    from console.files.vibration_map import save_map
    from plugins.vibrotactile.analytic_plate import SSPlate, analytic_map

    return save_map(tmp_path_factory.mktemp("map") / "map.npz", analytic_map(SSPlate()))


def flow_case(name: str, k: str, *parts: str):
    @case("plan", name)
    def build(tmp: Path, fx):
        argv = ["flow", fx.vmap, "--from", "51", "--to", "52", "--ringdown-k", k]
        return [*argv, "--out", tmp / "f.wav"], list(parts)


flow_case("ringdown-k-nan", "nan", "--ringdown-k", "nan")
flow_case("ringdown-k-inf", "inf", "--ringdown-k", "inf")
flow_case("ringdown-k-huge", "1e9", "--ringdown-k 1e9")
# beyond the profile key's range (what [vibrotactile] ringdown_gap_k takes): refused as
# typed, before a plan longer than [limits] max_plan_s could be asked for
flow_case("ringdown-k-over-key-range", "1000", "--ringdown-k 1000", "from 0 to 20")


def seconds_case(name: str, argv: list[str], *parts: str):
    @case("plan", name)
    def build(tmp: Path, fx):
        return argv, list(parts)


seconds_case("demo-seconds-nan", ["demo", "flow", "--seconds", "nan"], "--seconds", "nan")
seconds_case("demo-seconds-negative", ["demo", "flow", "--seconds", "-5"], "--seconds", "-5")
seconds_case("demo-minutes-inf", ["demo", "soak", "--minutes", "inf"], "--minutes", "inf")
seconds_case("bench-minutes-nan", ["bench", "soak", "--minutes", "nan"], "--minutes", "nan")
seconds_case("knob-trials-huge", ["knob", "--trials", "1000000000"], "--trials", "1000000000")
seconds_case("knob-distance-nan", ["knob", "--distance", "nan"], "--distance", "nan")
seconds_case("tuio-seconds-nan", ["tuio", "--seconds", "nan"], "--seconds", "nan")
seconds_case("knob-max-time-nan", ["knob", "--input", "live", "--max-time", "nan"], "--max-time")


@case("plan", "play-longer-than-max-plan")
def _play_long(tmp: Path, fx):
    p = tmp / "short.toml"
    p.write_text(SIM.replace("ramp_min_ms = 5.0", "ramp_min_ms = 5.0\nmax_plan_s = 1.0"))
    return ["--profile", p, "play", "sweep", "--dry-run"], ["play sweep", "3 s", "max_plan_s = 1"]


# ---------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def fx(tmp_path_factory, vmap_file):
    """A tiny model with the pipeline's real feature widths and a good 'drag' sample."""
    from plugins.gestures import sketch
    from plugins.gestures.dataset import write_background, write_sample
    from plugins.gestures.features import (
        N_HARMONICS_MAX,
        record_features,
        select_dynamic,
        select_kind,
        select_static,
    )
    from plugins.gestures.model import GestureModel

    base = tmp_path_factory.mktemp("gfx")
    xs, xk, xd, _ = record_features([None] * 4, (4,), N_HARMONICS_MAX)
    ws = select_static(xs[4], 2, N_HARMONICS_MAX).shape[1]
    wd = select_dynamic(xd[4], 2, N_HARMONICS_MAX).shape[1]
    wk = select_kind(xk[4]).shape[1]
    rng = np.random.default_rng(1)
    labels = np.array([g for g in sketch.STATIC + sketch.DYNAMIC for _ in range(4)])
    n = len(labels)
    dyn = np.isin(labels, sketch.DYNAMIC)
    model = GestureModel.fit(
        rng.normal(size=(n, ws)),
        rng.normal(size=(n, wd)),
        rng.normal(size=(n, wk)) + dyn[:, None],
        np.where(dyn, 0.5, 0.05),
        labels,
        n_harmonics=2,
        n_frames=4,
    )
    mpath = model.save(base / "good.skops")
    root = base / "set"
    bg = sketch.background()
    write_background(root, bg)
    poses = sketch.gesture_poses("drag", 5, pos_px=(320, 240), theta_deg=0, left=False)
    frames = [sketch.draw([p], bg, rng=rng) for p in poses]
    sample = write_sample(root, "drag", "s1_000", frames, subject="s1", hand="right", fps=60)
    ds = base / "ds"
    write_background(ds, bg)
    write_sample(ds, "zoom", "s1_000", frames, subject="s1", hand="right", fps=60)
    write_sample(ds, "zoom", "s2_000", frames, subject="s2", hand="left", fps=60)
    f = Fixtures(mpath, sample, ds)
    f.vmap = vmap_file
    return f


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(tmp_path / "cache"))


@pytest.mark.parametrize("name", sorted(CASES))
def test_malformed_input_one_clear_line(name, fx, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _kind, build = CASES[name]
    argv, parts = build(tmp_path, fx)
    code, out, err = run_cli(capsys, argv)
    lines = err.strip().splitlines()
    tally(name, code, len(lines) == 1 and all(p in lines[0] for p in parts), err.strip())
    assert code == 2, f"exit {code}: {err.strip()[:300]!r} out={out[:200]!r}"
    assert len(lines) == 1, err[:600]
    assert lines[0].startswith("haptable: error: "), lines[0][:300]
    assert "Traceback" not in err
    for part in parts:
        assert part in lines[0], (part, lines[0][:400])


# ---------------------------------------------------------------------------- frames a camera makes
def frame_sample(fx, tmp: Path, frame: np.ndarray, bg: np.ndarray | None) -> Path:
    d = fx.copy_sample(tmp)
    for p in d.glob("frame_*.png"):
        p.write_bytes(png_bytes(frame))
    if bg is not None:
        (d.parent.parent / "background.png").write_bytes(png_bytes(bg))
    return d


_RNG = np.random.default_rng(3)
WHITE = np.full((480, 640), 255, np.uint8)
BLACK = np.zeros((480, 640), np.uint8)
NOISE = np.where(_RNG.random((480, 640)) < 0.5, 0, 255).astype(np.uint8)
GREY_NOISE = _RNG.integers(0, 256, (480, 640)).astype(np.uint8)

FRAMES = {
    "all-white": (WHITE, None),
    "all-black": (BLACK, None),
    "white-on-black-background": (WHITE, BLACK),
    "black-on-white-background": (BLACK, WHITE),
    "saturated-noise": (NOISE, None),
    "saturated-noise-on-black": (NOISE, BLACK),
    "grey-noise": (GREY_NOISE, None),
    "white-on-white": (WHITE, WHITE),
}


@pytest.mark.parametrize("name", sorted(FRAMES))
def test_extreme_frames_are_answered(name, fx, tmp_path, capsys):
    """Frames a camera can produce (lamp blinding it, lens cap on, sensor noise) are
    answered: a gesture or "no hand", never an internal error."""
    frame, bg = FRAMES[name]
    d = frame_sample(fx, tmp_path, frame, bg)
    code, out, err = run_cli(capsys, ["gestures", "classify", fx.model, d, "--json"])
    assert code == 0, err
    res = json.loads(out)
    assert res["gesture"] in (*GESTURES, "none")
    if name in ("all-white", "all-black", "white-on-white"):
        assert res["gesture"] == "none" and res["hands_seen"] == 0


@pytest.mark.parametrize("name", sorted(FRAMES))
def test_extreme_frames_through_the_live_classifier(name, fx):
    """The frame loop's classifier (the console's path) takes them too."""
    from console.core.types import Frame
    from plugins.gestures.classifier import SvmClassifier
    from plugins.gestures.model import GestureModel

    frame, bg = FRAMES[name]
    clf = SvmClassifier(GestureModel.load(fx.model), background=bg)
    frames = [Frame(frame.copy(), i, i / 60) for i in range(4)]
    g = clf.classify([clf.process(f) for f in frames], frames[-1].t_capture_s)
    assert g is None or g.name in GESTURES
    res = clf.process(Frame(frame.copy(), 9, 9 / 60))
    assert isinstance(res.hands, tuple)


def test_palm_of_a_mask_without_edges_is_bounded_by_the_image():
    """A mask with no background pixel (a saturated frame) has its palm radius bounded
    by the image (the distance transform alone gives ~1e38 and the wrist search then
    fails building a structuring element of that size)."""
    from plugins.gestures.hand_shape import palm

    (cx, cy), r = palm(np.full((60, 100), 255, np.uint8))
    assert 25 <= r <= 31 and 20 <= cx <= 80 and 25 <= cy <= 35


@pytest.mark.parametrize("dur_s", [float("nan"), float("inf"), -1.0, 1e12])
def test_signal_lengths_are_refused_before_any_array(dur_s):
    """A tone or sweep of a NaN, infinite, negative or huge duration is one line, and
    nothing is allocated for it (1e12 s would be 4.8e16 samples)."""
    import tracemalloc

    from console.core.errors import UserError
    from console.signals.waveforms import linear_chirp, tone

    tracemalloc.start()
    try:
        for make in (
            lambda: tone(250.0, 1.0, dur_s, 48000),
            lambda: linear_chirp(10.0, 625.0, 1.0, dur_s, 48000),
        ):
            with pytest.raises(UserError, match="duration|max_plan_s"):
                make()
        assert tracemalloc.get_traced_memory()[1] < 1_000_000
    finally:
        tracemalloc.stop()


def test_a_stimulus_is_refused_unbuilt_when_longer_than_max_plan(monkeypatch):
    from console.core.errors import UserError
    from console.signals import stimuli

    def never(fs):
        raise AssertionError("the sweep was built")

    monkeypatch.setitem(stimuli.STIMULI, "sweep", (stimuli.STIMULI["sweep"][0], never))
    with pytest.raises(
        UserError, match=r"play sweep: 3 s is longer than \[limits\] max_plan_s = 1 s"
    ):
        stimuli.make_stimulus("sweep", 48000, 1.0)
