"""The recorder as a frame sink made from the profile: ``[recording] enabled`` (or
``force``) and ``path`` (empty: a new file in HapTable's data directory)."""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from console.plugin_api import data_dir

from .writer import Recorder


def recording_path(profile: Any) -> Path:
    """``[recording] path`` (relative: to the profile's folder), else a new
    ``recording-<UTC time>.h5`` under ``<data dir>/recordings``."""
    raw = profile.get("recording.path") or ""
    if raw:
        return Path(profile.resolve(raw))
    stamp = datetime.now(UTC).strftime("%Y%m%dT%H%M%S")
    folder = data_dir("recordings")
    folder.mkdir(parents=True, exist_ok=True)
    return folder / f"recording-{stamp}.h5"


def make_recorder(profile: Any, *, force: bool = False) -> Recorder | None:
    """A ``Recorder`` for the profile, or ``None`` when ``[recording] enabled`` is false."""
    if not (force or profile.get("recording.enabled")):
        return None
    return Recorder(
        recording_path(profile),
        profile,
        codec=profile.get("recording.codec") or "gzip1",
        queue_frames=int(profile.get("recording.queue_frames") or 240),
        flush_s=float(profile.get("recording.flush_s") or 0.5),
    )
