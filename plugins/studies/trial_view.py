"""A study's trial file (``trial_recording``) as the console shows a recorded run
(``console.core.contracts.RecordedRun``): its plans on the Scope screen (``o``), its
camera frames, when the trial saw the camera, on the Camera screen. Registered as the
recording reader ``study_trial``: the console opens what ``haptable replay`` replays."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import GATE_EVENTS, UserError, load_map, read_gate_events

from .trial_recording import FORMAT, FORMAT_VERSION, MAP_FILE

FIX = "type a trial file of a study run with 'record trials' (recording/trial_NNNN.h5)"


def _text(value: Any) -> str:
    return value.decode() if isinstance(value, bytes) else str(value)


class StudyTrialRun:
    """An open trial file: its frames (none when the trial did not see the camera), no
    per-frame decisions, its plans (``outputs``), the map they were rendered on, and
    gate events; ``close()`` when done."""

    def __init__(self, path: Path, f: Any) -> None:
        self.path, self.f = path, f
        self.attrs = {k: (_text(v) if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
        self.n_frames = int(f["frames"].shape[0]) if "frames" in f else 0
        times = f["t_capture_s"][: self.n_frames] if "t_capture_s" in f else np.zeros(0)
        self.t_capture_s = np.asarray(times, dtype=np.float64)
        self.n_frames = min(self.n_frames, len(self.t_capture_s))
        self.seq = np.arange(self.n_frames, dtype=np.int64)
        self._plans = [json.loads(x) for x in _text(f["outputs"][()]).splitlines() if x.strip()]

    def frame(self, k: int) -> np.ndarray:
        return self.f["frames"][k]

    def decisions(self, k: int) -> dict:
        """A trial keeps no per-frame decisions: no contacts, no hands."""
        return {"contacts": [], "hands": []}

    def plans(self) -> list[dict]:
        return list(self._plans)

    def vibration_map(self) -> Any:
        """The vibration map the trial's plans were rendered on (``recording/map.npz``
        beside it, as ``haptable replay`` takes it), None without one."""
        path = self.path.parent / MAP_FILE
        return load_map(path, require_all=False) if path.is_file() else None

    def gate_events(self) -> list[dict]:
        return read_gate_events(self.f[GATE_EVENTS][:]) if GATE_EVENTS in self.f else []

    def close(self) -> None:
        self.f.close()


def trial_format(path: str | Path) -> str:
    """The ``format`` attribute of the HDF5 file at ``path`` ("" when none or unreadable)."""
    p = Path(path).expanduser()
    if not p.is_file():
        return ""
    try:
        import h5py  # lazy: only when a recording is opened

        with h5py.File(p, "r") as f:
            return _text(f.attrs.get("format", ""))
    except OSError:
        return ""


class StudyTrialReader:
    """``reads(path)``: whether ``path`` is a study's trial file; ``open_recording(path)``
    opens it (one ``UserError`` line naming the file otherwise)."""

    def reads(self, path: str) -> bool:
        return trial_format(path) == FORMAT

    def open_recording(self, path: str) -> StudyTrialRun:
        import h5py  # lazy: only when a recording is opened

        p = Path(path).expanduser()
        try:
            f = h5py.File(p, "r")
        except OSError:
            raise UserError(f"study trial {p}: not an HDF5 file (or unreadable); {FIX}") from None
        try:
            if _text(f.attrs.get("format", "")) != FORMAT:
                raise UserError(f"study trial {p}: an HDF5 file but not a study trial; {FIX}")
            if int(f.attrs.get("format_version", 0)) > FORMAT_VERSION:
                raise UserError(f"study trial {p}: a newer format than this HapTable; update it")
            return StudyTrialRun(p, f)
        except UserError:
            f.close()
            raise
        except (KeyError, OSError, ValueError) as exc:
            f.close()
            raise UserError(f"study trial {p}: damaged ({exc}); {FIX}") from None


def make_reader(profile: Any) -> StudyTrialReader:
    """The recording reader ``study_trial`` (the profile does not change it)."""
    return StudyTrialReader()
