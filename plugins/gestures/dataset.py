"""The gesture dataset folder format: read, check and write samples.

Layout (real recordings and synthetic sets alike)::

    DATASET/
      background.png                  optional: empty table, used by samples without one
      <gesture>/                      one of GESTURES
        <sample>/                     any folder name, e.g. s1_007
          sample.json                 {"subject": "s1", "gesture": "<gesture>",
                                       "hand": "left"|"right", "fps": 60}
          frame_000.png, frame_001.png, ...   8-bit greyscale, numbered from 000, no gaps
          background.png              optional: this sample's empty table
          truth.json                  optional: ground truth (synthetic sets)

Static gestures need at least 1 frame, dynamic ones at least 4 (the classifier reads
the first four). Other keys in sample.json are kept in ``Sample.meta``; other files and
files in the root are ignored. Every problem is a one-line ``UserError`` naming the
sample (``DATASET/drag/s1_007``) and the fix.
"""

from __future__ import annotations

import json
import math
import re
import stat
import struct
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import AT_CLI, AT_CONSOLE, Placed, UserError

STATIC: tuple[str, ...] = ("one_finger", "two_finger", "l_shape", "closed_hand", "open_hand")
DYNAMIC: tuple[str, ...] = ("drag", "rotate", "spread_pile", "wipe", "zoom")
GESTURES: tuple[str, ...] = STATIC + DYNAMIC
HANDS: tuple[str, ...] = ("left", "right")
MIN_FRAMES = {"static": 1, "dynamic": 4}
IMAGE_SIZE_PX = (640, 480)  # width, height of the PS3 Eye frames (paper Sec. 2)
FRAME_RE = re.compile(r"^frame_(\d{3,})\.png$")
REQUIRED_KEYS = {
    "subject": "a name like 's1'",
    "gesture": "the gesture",
    "hand": "'left' or 'right'",
    "fps": "frames per second, e.g. 60",
}
JSON_EXAMPLE = '{"subject": "s1", "gesture": "<gesture>", "hand": "right", "fps": 60}'
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
MAX_FRAME_PX = 8192 * 8192  # the largest camera frame a profile allows ([camera])
MAX_PNG_BYTES = 256 * 1024 * 1024
MAX_JSON_BYTES = 16 * 1024 * 1024
MAX_FPS = 10000.0
#: how to make a dataset, where the user is
MAKE_DATASET = {
    AT_CLI: "make one with `haptable gestures synth --out DIR` or record into it with "
    "`haptable gestures record`",
    AT_CONSOLE: "s synthesizes one here",
}


def kind_of(gesture: str) -> str:
    """``"static"`` or ``"dynamic"``."""
    return "static" if gesture in STATIC else "dynamic"


@dataclass(frozen=True)
class Sample:
    """One recorded gesture: its folder, labels and frame files (images load lazily)."""

    path: Path
    name: str  # "<gesture>/<sample>" inside the dataset
    gesture: str
    subject: str
    hand: str
    fps: float
    frame_paths: tuple[Path, ...]
    background_path: Path | None
    meta: dict[str, Any] = field(default_factory=dict, compare=False)

    @property
    def kind(self) -> str:
        return kind_of(self.gesture)

    @property
    def n_frames(self) -> int:
        return len(self.frame_paths)

    def frames(
        self, limit: int | None = None, size_px: tuple[int, int] | None = IMAGE_SIZE_PX
    ) -> np.ndarray:
        """(n, H, W) uint8 frames (the first ``limit`` if given), checked."""
        paths = self.frame_paths[:limit] if limit else self.frame_paths
        imgs = [read_png(p, self._where(p), size_px) for p in paths]
        shape = imgs[0].shape
        for p, im in zip(paths, imgs, strict=True):
            if im.shape != shape:
                raise UserError(
                    f"{self._where(p)}: {im.shape[1]} x {im.shape[0]} px but "
                    f"{paths[0].name} is {shape[1]} x {shape[0]} px; all frames of a "
                    "sample must have one size"
                )
        return np.stack(imgs)

    def background(self, size_px: tuple[int, int] | None = IMAGE_SIZE_PX) -> np.ndarray | None:
        """The sample's background (its own, else the dataset's), or None if neither."""
        if self.background_path is None:
            return None
        return read_png(self.background_path, self._where(self.background_path), size_px)

    def truth(self) -> dict | None:
        """Ground truth written by the synthesiser (``truth.json``), if present."""
        p = self.path / "truth.json"
        if not p.is_file():
            return None
        return read_json(p, self._where(p), "delete or rewrite it")

    def _where(self, p: Path) -> str:
        return _show(p)


def _show(p: Path) -> str:
    return str(p)


def read_png(
    path: Path, where: str | None = None, size_px: tuple[int, int] | None = IMAGE_SIZE_PX
) -> np.ndarray:
    """An 8-bit greyscale PNG as (H, W) uint8, or a one-line UserError saying why not."""
    import cv2

    where = where or str(path)
    data = _read_bytes(Path(path), where, MAX_PNG_BYTES, "frame")
    if not data.size:
        raise UserError(f"{where}: empty file (0 bytes); record or export the frame again")
    width, height = png_size(data[:33].tobytes(), where)
    if size_px is not None and (width, height) != tuple(size_px):
        raise UserError(
            f"{where}: {width} x {height} px; expected {size_px[0]} x {size_px[1]} px "
            "(the camera's frame size)"
        )
    if width * height > MAX_FRAME_PX:
        raise UserError(
            f"{where}: {width} x {height} px is larger than any camera frame (at most "
            f"{MAX_FRAME_PX} pixels); not decoding it"
        )
    img = cv2.imdecode(data, cv2.IMREAD_UNCHANGED)
    if img is None:
        raise UserError(f"{where}: not a readable PNG image; re-export it as 8-bit greyscale PNG")
    if img.ndim != 2:
        raise UserError(
            f"{where}: has {img.shape[2]} channels; frames must be 8-bit greyscale "
            "(convert with e.g. cv2.cvtColor(img, cv2.COLOR_BGR2GRAY))"
        )
    if img.dtype != np.uint8:
        raise UserError(
            f"{where}: {img.dtype} pixels; frames must be 8-bit (uint8) greyscale "
            "(scale to 0-255 and save as 8-bit)"
        )
    if size_px is not None and (img.shape[1], img.shape[0]) != tuple(size_px):
        raise UserError(
            f"{where}: {img.shape[1]} x {img.shape[0]} px; expected "
            f"{size_px[0]} x {size_px[1]} px (the camera's frame size)"
        )
    return img


def png_size(head: bytes, where: str) -> tuple[int, int]:
    """(width, height) from a PNG's signature and IHDR chunk, without decoding it."""
    if not head.startswith(PNG_SIGNATURE):
        raise UserError(
            f"{where}: not a readable PNG image (it starts with {head[:8]!r}); save frames "
            "as 8-bit greyscale PNG"
        )
    if len(head) < 24 or head[12:16] != b"IHDR":
        raise UserError(f"{where}: a PNG without its header (IHDR); export the frame again")
    width, height = struct.unpack(">II", head[16:24])
    return width, height


def _read_bytes(path: Path, where: str, max_bytes: int, what: str) -> np.ndarray:
    """A regular file's bytes, refused (one line) when it is not a regular file or
    is larger than ``max_bytes``."""
    try:
        st = path.stat()
        if not stat.S_ISREG(st.st_mode):
            raise UserError(f"{where}: not a regular file; the {what} must be a file")
        if st.st_size > max_bytes:
            raise UserError(
                f"{where}: {st.st_size / 1e6:.0f} MB is too large for a {what} "
                f"(at most {max_bytes / 1e6:.0f} MB)"
            )
        return np.fromfile(path, dtype=np.uint8)
    except OSError as exc:
        raise UserError(f"{where}: cannot read ({exc.strerror or exc}); check the file") from None


def read_json(path: Path, where: str, fix: str) -> Any:
    """A small JSON file, or a one-line UserError (too large, not UTF-8, malformed,
    nested too deeply) ending with ``fix``."""
    data = _read_bytes(path, where, MAX_JSON_BYTES, "JSON file").tobytes()
    try:
        return json.loads(data.decode("utf-8"))
    except UnicodeDecodeError:
        raise UserError(f"{where}: not UTF-8 text; {fix}") from None
    except json.JSONDecodeError as exc:
        raise UserError(f"{where}: malformed JSON (line {exc.lineno}: {exc.msg}); {fix}") from None
    except RecursionError:
        raise UserError(f"{where}: JSON nested too deeply to read; {fix}") from None


def write_png(path: str | Path, img: np.ndarray) -> None:
    """Write an (H, W) uint8 image as PNG. Camera frames are noisy, so the fastest
    settings compress best per millisecond: Huffman-only coding after the SUB filter
    (about 5 ms and 145 kB for a 640 x 480 frame, against 15 ms and 160 kB by default)."""
    import cv2

    img = np.asarray(img)
    if img.ndim != 2 or img.dtype != np.uint8:
        raise ValueError(f"{path}: need an (H, W) uint8 image, got {img.dtype} {img.shape}")
    path = Path(path)
    params = [
        cv2.IMWRITE_PNG_COMPRESSION,
        1,
        cv2.IMWRITE_PNG_STRATEGY,
        cv2.IMWRITE_PNG_STRATEGY_HUFFMAN_ONLY,
        cv2.IMWRITE_PNG_FILTER,
        cv2.IMWRITE_PNG_FILTER_SUB,
    ]
    ok, buf = cv2.imencode(".png", img, params)
    if not ok:
        raise UserError(f"{path}: could not encode PNG")
    path.write_bytes(buf.tobytes())


def _read_meta(folder: Path, where: str) -> dict[str, Any]:
    p = folder / "sample.json"
    if not p.is_file():
        raise UserError(f"{where}: no sample.json; add one like {JSON_EXAMPLE}")
    meta = read_json(p, f"{where}/sample.json", f"it should look like {JSON_EXAMPLE}")
    if not isinstance(meta, dict):
        raise UserError(
            f"{where}/sample.json: holds a {type(meta).__name__}, not an object; "
            f"it should look like {JSON_EXAMPLE}"
        )
    missing = [k for k in REQUIRED_KEYS if k not in meta]
    if missing:
        what = ", ".join(f"{k!r} ({REQUIRED_KEYS[k]})" for k in missing)
        raise UserError(f"{where}/sample.json: missing {what}; e.g. {JSON_EXAMPLE}")
    return meta


def read_sample(folder: str | Path, root: str | Path | None = None) -> Sample:
    """Read and check one sample folder (labels, frame numbering and count)."""
    folder = Path(folder)
    where = _show(folder)
    if not folder.is_dir():
        raise UserError(f"{where}: no such sample folder")
    meta = _read_meta(folder, where)
    gesture, subject, hand, fps = meta["gesture"], meta["subject"], meta["hand"], meta["fps"]
    if gesture not in GESTURES:
        raise UserError(
            f"{where}/sample.json: unknown gesture {gesture!r}; use one of {', '.join(GESTURES)}"
        )
    if folder.parent.name in GESTURES and folder.parent.name != gesture:
        raise UserError(
            f"{where}/sample.json: gesture {gesture!r} but the sample is in the "
            f"{folder.parent.name!r} folder; move it or fix the label"
        )
    if not isinstance(subject, str) or not subject.strip() or not subject.isprintable():
        raise UserError(
            f"{where}/sample.json: subject {subject!r} must be a non-empty string on one line "
            "like 's1'"
        )
    if hand not in HANDS:
        raise UserError(f"{where}/sample.json: hand {hand!r} must be 'left' or 'right'")
    if (
        isinstance(fps, bool)
        or not isinstance(fps, (int, float))
        or not math.isfinite(fps)
        or not 0 < fps <= MAX_FPS
    ):
        raise UserError(
            f"{where}/sample.json: fps {fps!r} must be a positive number up to {MAX_FPS:g}, e.g. 60"
        )
    ppm = meta.get("px_per_mm")
    if ppm is not None and (
        isinstance(ppm, bool)
        or not isinstance(ppm, (int, float))
        or not math.isfinite(ppm)
        or not 0.05 <= ppm <= 100
    ):
        raise UserError(
            f"{where}/sample.json: px_per_mm {ppm!r} must be the camera's pixels per mm "
            "on the glass, 0.05 to 100 (e.g. 0.86), or left out"
        )
    numbered = []
    for p in folder.iterdir():
        m = FRAME_RE.match(p.name)
        if m:
            numbered.append((int(m.group(1)), p))
    numbered.sort()
    for i, (n, p) in enumerate(numbered):
        if n != i:
            raise UserError(
                f"{where}: frame_{i:03d}.png is missing (found {p.name}); frames "
                "must be numbered from frame_000.png without gaps"
            )
    kind = kind_of(gesture)
    need = MIN_FRAMES[kind]
    if len(numbered) < need:
        raise UserError(
            f"{where}: {len(numbered)} frame(s) but a {kind} gesture needs at least "
            f"{need} (frame_000.png ...)"
        )
    bg = folder / "background.png"
    if not bg.is_file():
        rb = (Path(root) if root is not None else folder.parent.parent) / "background.png"
        bg = rb if rb.is_file() else None
    name = f"{folder.parent.name}/{folder.name}"
    extra = {k: v for k, v in meta.items() if k not in REQUIRED_KEYS}
    return Sample(
        folder,
        name,
        gesture,
        subject.strip(),
        hand,
        float(fps),
        tuple(p for _, p in numbered),
        bg,
        extra,
    )


def load_dataset(
    root: str | Path,
    *,
    gestures: Iterable[str] | None = None,
    check_images: bool = False,
    size_px: tuple[int, int] | None = IMAGE_SIZE_PX,
) -> list[Sample]:
    """All samples of a dataset, sorted by name. ``check_images`` also decodes every
    PNG (slow on big sets; otherwise images are checked when loaded)."""
    root = Path(root)
    if not root.is_dir():
        raise Placed(f"{root}: no such dataset folder", MAKE_DATASET)
    want = set(GESTURES if gestures is None else gestures)
    samples: list[Sample] = []
    for d in sorted(p for p in root.iterdir() if p.is_dir() and not p.name.startswith(".")):
        if d.name not in GESTURES:
            raise UserError(
                f"{d}: unknown gesture folder {d.name!r}; gesture folders are "
                f"{', '.join(GESTURES)} (move other folders out of the dataset)"
            )
        if d.name not in want:
            continue
        for s in sorted(p for p in d.iterdir() if p.is_dir() and not p.name.startswith(".")):
            sample = read_sample(s, root)
            if check_images:
                sample.frames(size_px=size_px)
                sample.background(size_px=size_px)
            samples.append(sample)
    if not samples:
        raise Placed(
            f"{root}: no samples found (expected {root}/<gesture>/<sample>/sample.json)",
            MAKE_DATASET,
        )
    return samples


def next_sample_name(root: Path, gesture: str, subject: str) -> str:
    """``<subject>_NNN`` not yet used in ``root/<gesture>``."""
    d = root / gesture
    used = {p.name for p in d.iterdir()} if d.is_dir() else set()
    i = 0
    while f"{subject}_{i:03d}" in used:
        i += 1
    return f"{subject}_{i:03d}"


def write_sample(
    root: str | Path,
    gesture: str,
    name: str,
    frames: np.ndarray | Iterable[np.ndarray],
    *,
    subject: str,
    hand: str,
    fps: float,
    background: np.ndarray | None = None,
    truth: dict | None = None,
    extra: dict | None = None,
) -> Path:
    """Write one sample in the dataset format; returns its folder."""
    if gesture not in GESTURES:
        raise UserError(f"gesture {gesture!r}: unknown; use one of {', '.join(GESTURES)}")
    if hand not in HANDS:
        raise UserError(f"hand {hand!r}: must be 'left' or 'right'")
    folder = Path(root) / gesture / name
    folder.mkdir(parents=True, exist_ok=True)
    n = 0
    for n, img in enumerate(frames, start=1):
        write_png(folder / f"frame_{n - 1:03d}.png", img)
    if n < MIN_FRAMES[kind_of(gesture)]:
        raise UserError(
            f"{folder}: only {n} frame(s) for a {kind_of(gesture)} gesture (needs "
            f"{MIN_FRAMES[kind_of(gesture)]})"
        )
    if background is not None:
        write_png(folder / "background.png", background)
    meta = {
        "subject": subject,
        "gesture": gesture,
        "hand": hand,
        "fps": int(fps) if float(fps).is_integer() else float(fps),
        **(extra or {}),
    }
    (folder / "sample.json").write_text(json.dumps(meta) + "\n", encoding="utf-8")
    if truth is not None:
        (folder / "truth.json").write_text(json.dumps(truth, separators=(",", ":")) + "\n")
    return folder


def write_background(root: str | Path, image: np.ndarray) -> Path:
    """The dataset-wide ``background.png``."""
    p = Path(root) / "background.png"
    p.parent.mkdir(parents=True, exist_ok=True)
    write_png(p, image)
    return p


def summary(samples: list[Sample]) -> dict[str, Any]:
    """Counts per gesture and subject (for reports)."""
    per_g: dict[str, int] = {}
    per_s: dict[str, int] = {}
    for s in samples:
        per_g[s.gesture] = per_g.get(s.gesture, 0) + 1
        per_s[s.subject] = per_s.get(s.subject, 0) + 1
    return {"samples": len(samples), "per_gesture": per_g, "per_subject": per_s}
