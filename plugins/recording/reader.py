"""Read a recording: ``open_recording(path) -> Recording`` (frames, times, decisions,
plans, the profile and versions), every problem one ``UserError`` line naming the file.

Opened in SWMR read mode: a file still being written, or left by a killed run, gives
every frame flushed before (a frame counts once its decisions' index is on disk)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import GATE_EVENTS, UserError, read_gate_events

from .writer import FORMAT, FORMAT_VERSION

FIX = "give a file written by `haptable demo ... --record FILE` or [recording] enabled"


class Recording:
    """An open recording (a context manager; ``close()`` when done)."""

    def __init__(self, path: Path, f: Any) -> None:
        self.path, self.f = path, f
        lengths = [
            f["frames"].shape[0],
            f["seq"].shape[0],
            f["t_capture_s"].shape[0],
            f["decisions_index"].shape[0],
        ]
        self.n_frames = int(min(lengths))
        self.seq = f["seq"][: self.n_frames]
        self.t_capture_s = f["t_capture_s"][: self.n_frames]
        self._index = f["decisions_index"][: self.n_frames]
        self._blob = f["decisions"][:]
        self.attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
        self.versions = json.loads(self.attrs.get("versions", "{}"))
        self.tunables = json.loads(self.attrs.get("tunables", "{}"))
        self.stats = {"written": int(f["stats"][0]), "dropped": int(f["stats"][1])}
        #: the frames the recorder dropped (its queue full): a replay differs after them
        self.dropped_seq = f["dropped_seq"][:] if "dropped_seq" in f else np.zeros(0, np.int64)

    def frame(self, k: int) -> np.ndarray:
        return self.f["frames"][k]

    def decisions(self, k: int) -> dict:
        start, n = self._index[k]
        raw = self._blob[start : start + n].tobytes()
        try:
            return json.loads(raw)
        except ValueError:
            raise UserError(
                f"{self.path}: frame {k}'s decisions are damaged (not JSON); {FIX}"
            ) from None

    def scene(self, k: int) -> dict | None:
        """The scene's state at frame ``k`` (written when it changed: the last one before)."""
        for j in range(k, -1, -1):
            d = self.decisions(j)
            if "scene" in d:
                return d["scene"]
        return None

    def background(self) -> np.ndarray | None:
        bg = self.f["background"][()]
        return bg if bg.size else None

    def plans(self) -> list[dict]:
        """Plans the run played off the frame loop (computed later), in order."""
        raw = self.f["plans"][:].tobytes()
        return [json.loads(line) for line in raw.splitlines() if line.strip()]

    def gate_events(self) -> list[dict]:
        """The kernel's own events during the run, in its order: ``t_s``, ``clock`` (gate
        samples), ``kind`` (``switch``, ``estop``, ``reset``, ``fault``, ``refused``,
        ``shutdown``), ``message``; none in a recording made before they were kept."""
        if GATE_EVENTS not in self.f:
            return []
        return read_gate_events(self.f[GATE_EVENTS][:])

    def close(self) -> None:
        self.f.close()

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def open_recording(path: str | Path) -> Recording:
    """The recording at ``path`` (``UserError`` naming the file and the fix otherwise)."""
    import h5py  # lazy: only when reading a recording

    p = Path(path).expanduser()
    if not p.is_file():
        raise UserError(f"recording {p}: {'is a folder' if p.is_dir() else 'no such file'}; {FIX}")
    try:
        f = h5py.File(p, "r", swmr=True)
    except OSError:
        raise UserError(f"recording {p}: not an HDF5 file (or unreadable); {FIX}") from None
    try:
        fmt = f.attrs.get("format")
        fmt = fmt.decode() if isinstance(fmt, bytes) else fmt
        if fmt != FORMAT:
            raise UserError(f"recording {p}: an HDF5 file but not a HapTable recording; {FIX}")
        version = int(f.attrs.get("format_version", 0))
        if version > FORMAT_VERSION:
            raise UserError(
                f"recording {p}: format version {version} is newer than this HapTable reads "
                f"({FORMAT_VERSION}); update HapTable"
            )
        return Recording(p, f)
    except UserError:
        f.close()
        raise
    except (KeyError, OSError, ValueError) as exc:
        f.close()
        raise UserError(f"recording {p}: damaged ({exc}); {FIX}") from None
