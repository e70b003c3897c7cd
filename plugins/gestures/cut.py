"""``haptable gestures cut FILE --out DIR``: labelled samples cut out of a recording
(``haptable demo ... --record FILE``) into the dataset folder format (``dataset.py``).

Each run of consecutive recorded frames that the recording's gesture stage decided as
one gesture of the dataset (its per-frame ``gesture`` decision) becomes a sample of that
gesture with those frames; or, with ``--labels CSV``, each line ``start_frame,
end_frame, gesture`` (the recording's frame numbers, both included; a header line is
allowed) becomes one. The recording's learned empty table is the dataset's
``background.png``; each ``sample.json`` says where its frames came from (``source``,
``start_frame``, ``end_frame``, ``labels``: ``decisions`` or the CSV).

The recording is read as the documented file (``plugins/recording``'s format: ``frames``,
``seq``, ``t_capture_s``, ``decisions`` with ``decisions_index``, ``background``), not
through the recorder's code: plugins meet through formats and contracts."""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import UserError

from .dataset import GESTURES, MIN_FRAMES, kind_of, write_background, write_sample

FIX = "give a file written by `haptable demo ... --record FILE`"
#: fewest frames of a cut sample (the classifier decides from the first 2 to 6 frames)
MIN_CUT_FRAMES = 2


def configure_cut(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", type=Path, help="a recording (haptable demo ... --record FILE)")
    parser.add_argument("--out", required=True, type=Path, help="the dataset folder to write")
    parser.add_argument(
        "--labels",
        type=Path,
        default=None,
        help="CSV of start_frame,end_frame,gesture (recorded frame numbers, inclusive) "
        "instead of the recorded gesture decisions",
    )
    parser.add_argument("--subject", default="rec", help="the samples' subject (default rec)")
    parser.add_argument("--hand", choices=("right", "left"), default="right")
    parser.add_argument("--json", action="store_true", help="print the samples as JSON")


class _Recording:
    """The parts of a recording a cut reads (one ``UserError`` line naming the file)."""

    def __init__(self, path: Path) -> None:
        import h5py  # lazy: only when cutting

        p = Path(path).expanduser()
        if not p.is_file():
            raise UserError(
                f"recording {p}: {'is a folder' if p.is_dir() else 'no such file'}; {FIX}"
            )
        try:
            self.f = h5py.File(p, "r", swmr=True)
        except OSError:
            raise UserError(f"recording {p}: not an HDF5 file (or unreadable); {FIX}") from None
        self.path = p
        try:
            fmt = self.f.attrs.get("format")
            if (fmt.decode() if isinstance(fmt, bytes) else fmt) != "haptable-recording":
                raise UserError(f"recording {p}: an HDF5 file but not a HapTable recording; {FIX}")
            f = self.f
            keys = ("frames", "seq", "t_capture_s", "decisions_index")
            self.n = int(min(f[k].shape[0] for k in keys))
            self.seq = f["seq"][: self.n].astype(np.int64)
            self.t_s = f["t_capture_s"][: self.n]
            self._index = f["decisions_index"][: self.n]
            self._blob = f["decisions"][:]
            bg = f["background"][()] if "background" in f else np.zeros((0, 0))
            self.background = bg if bg.size else None
        except UserError:
            self.f.close()
            raise
        except (KeyError, OSError, ValueError) as exc:
            self.f.close()
            raise UserError(f"recording {p}: damaged ({exc}); {FIX}") from None

    def gesture(self, k: int) -> str | None:
        start, n = self._index[k]
        try:
            g = json.loads(self._blob[start : start + n].tobytes()).get("gesture")
        except ValueError:
            raise UserError(f"recording {self.path}: frame {k}'s decisions are damaged") from None
        return g[0] if g else None

    def fps(self) -> float:
        if self.n < 2 or self.t_s[-1] <= self.t_s[0]:
            return 60.0
        # the camera's rate: the median step between recorded frames' seq over time
        step_s = np.median(np.diff(self.t_s) / np.maximum(np.diff(self.seq), 1))
        return round(float(1.0 / step_s), 1) if step_s > 0 else 60.0

    def close(self) -> None:
        self.f.close()


def runs_from_decisions(rec: _Recording) -> tuple[list[tuple[int, int, str]], int]:
    """(first index, last index, gesture) of each run of frames decided as one dataset
    gesture, and the runs too short to be a sample."""
    runs, short = [], 0
    k = 0
    while k < rec.n:
        g = rec.gesture(k)
        j = k
        while j + 1 < rec.n and rec.gesture(j + 1) == g:
            j += 1
        if g in GESTURES:
            if j - k + 1 >= max(MIN_CUT_FRAMES, MIN_FRAMES[kind_of(g)]):
                runs.append((k, j, g))
            else:
                short += 1
        k = j + 1
    return runs, short


def runs_from_labels(rec: _Recording, path: Path) -> list[tuple[int, int, str]]:
    """The CSV's lines as (first index, last index, gesture); one line per problem."""
    p = Path(path).expanduser()
    if not p.is_file():
        raise UserError(f"--labels {p}: no such file; give a CSV of start_frame,end_frame,gesture")
    where = {int(s): k for k, s in enumerate(rec.seq)}
    out = []
    with open(p, newline="", encoding="utf-8", errors="replace") as fh:
        for line_no, row in enumerate(csv.reader(fh), start=1):
            cells = [c.strip() for c in row]
            if not any(cells) or cells[0].startswith("#"):
                continue
            if line_no == 1 and cells[0].lower() in ("start_frame", "start"):
                continue
            at = f"--labels {p} line {line_no}"
            if len(cells) != 3:
                raise UserError(f"{at}: {','.join(cells)!r}: give start_frame,end_frame,gesture")
            a, b, g = cells
            if not (a.isdigit() and b.isdigit()):
                raise UserError(f"{at}: frames {a!r}, {b!r}: give the recording's frame numbers")
            if g not in GESTURES:
                raise UserError(f"{at}: gesture {g!r}: use one of {', '.join(GESTURES)}")
            missing = [x for x in (int(a), int(b)) if x not in where]
            if missing:
                raise UserError(
                    f"{at}: frame {missing[0]} is not in the recording (its frames are "
                    f"{int(rec.seq[0])}..{int(rec.seq[-1])}, some skipped); give recorded ones"
                )
            k0, k1 = where[int(a)], where[int(b)]
            need = max(MIN_CUT_FRAMES, MIN_FRAMES[kind_of(g)])
            if k1 - k0 + 1 < need:
                raise UserError(
                    f"{at}: frames {a}..{b} hold {max(k1 - k0 + 1, 0)} recorded frame(s); a "
                    f"{kind_of(g)} gesture needs at least {need}"
                )
            out.append((k0, k1, g))
    if not out:
        raise UserError(f"--labels {p}: no label lines; give start_frame,end_frame,gesture lines")
    return out


def cut(
    path: Path,
    out: Path,
    *,
    labels: Path | None = None,
    subject: str = "rec",
    hand: str = "right",
) -> dict[str, Any]:
    """Cut the samples (see the module); returns what was written."""
    rec = _Recording(path)
    try:
        if labels is not None:
            runs, short = runs_from_labels(rec, labels), 0
        else:
            runs, short = runs_from_decisions(rec)
            if not runs:
                raise UserError(
                    f"recording {rec.path}: no gesture of the dataset was recognised on "
                    f"{MIN_CUT_FRAMES} or more frames in a row; label it with --labels CSV"
                )
        for k0, _, g in runs:
            d = Path(out) / g / f"{subject}_{int(rec.seq[k0]):06d}"
            if d.exists():
                raise UserError(f"{d}: already there (cut before?); give a new --out")
        if rec.background is not None:
            write_background(out, _to_uint8(rec.background))
        fps = rec.fps()
        samples = []
        for k0, k1, g in runs:
            s0, s1 = int(rec.seq[k0]), int(rec.seq[k1])
            frames = (np.asarray(rec.f["frames"][k], dtype=np.uint8) for k in range(k0, k1 + 1))
            folder = write_sample(
                out,
                g,
                f"{subject}_{s0:06d}",
                frames,
                subject=subject,
                hand=hand,
                fps=fps,
                extra={
                    "source": str(rec.path),
                    "start_frame": s0,
                    "end_frame": s1,
                    "labels": "decisions" if labels is None else str(labels),
                },
            )
            samples.append({"sample": str(folder), "gesture": g, "frames": k1 - k0 + 1})
        return {"out": str(out), "samples": samples, "too_short": short, "fps": fps}
    finally:
        rec.close()


def _to_uint8(img: np.ndarray) -> np.ndarray:
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def run_cut(args: argparse.Namespace, ctx: Any = None) -> int:
    s = args.subject
    if not s.strip() or s in (".", "..") or "/" in s or "\\" in s or not s.isprintable():
        raise UserError(
            f"--subject {s!r}: give a plain name like s1 (it names the samples' folders)"
        )
    res = cut(args.file, args.out, labels=args.labels, subject=args.subject, hand=args.hand)
    if args.json:
        print(json.dumps(res, indent=1))
        return 0
    per: dict[str, int] = {}
    for s in res["samples"]:
        per[s["gesture"]] = per.get(s["gesture"], 0) + 1
    counts = ", ".join(f"{g} {n}" for g, n in sorted(per.items()))
    tail = f"; {res['too_short']} runs too short to cut" if res["too_short"] else ""
    print(f"cut {len(res['samples'])} samples into {res['out']} ({counts}){tail}")
    if res["too_short"] and not res["samples"]:
        print("nothing cut", file=sys.stderr)
    return 0
