"""What the twin outputs recorded during a console session or a command, written on exit
for outside inspection (``HAPTABLE_TWIN_LOG=path.json haptable [command]``).

``path.json`` holds the bursts found in the twin recording (non-silent stretches: start
sample, length, peak volts and dominant frequency per channel), the relay switch log and
the plans the console played (name, segments with their patches, label, peak and meta).
``path.npz`` beside it holds the raw recording (``recording_v``, (n, channels) volts, a
column per ``[audio] channels`` name) and each played segment's waveforms
(``plan{i}_seg{j}_piezo_v`` / ``_screen_v``, and ``_PA_v`` ... for a patch with a drive of
its own) so a test can check sample by sample that what was auditioned is what the
amplifiers received. The
gate's events (e-stops, switches, with their sample clock) are listed too. Both files are
written without following a symlink (``console.kernel.private_dir``).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

from console.kernel.private_dir import open_private, write_private

ENV = "HAPTABLE_TWIN_LOG"


def bursts(
    rec_v: np.ndarray,
    sample_rate_hz: int,
    min_gap: int = 16,
    channels: tuple[str, ...] = ("piezo", "screen"),
) -> list[dict[str, Any]]:
    """Non-silent stretches of a (n, channels) recording, split where every channel is
    exactly zero for at least ``min_gap`` samples; peak and frequency per channel name."""
    rec = np.asarray(rec_v, float).reshape(-1, len(channels))
    on = np.any(rec != 0.0, axis=1)
    idx = np.flatnonzero(on)
    out: list[dict[str, Any]] = []
    if idx.size == 0:
        return out
    breaks = np.flatnonzero(np.diff(idx) > min_gap)
    starts = np.concatenate([[idx[0]], idx[breaks + 1]])
    ends = np.concatenate([idx[breaks], [idx[-1]]]) + 1
    for a, b in zip(starts, ends, strict=True):
        seg = rec[a:b]
        item: dict[str, Any] = {"start": int(a), "n_samples": int(b - a)}
        for ch, name in enumerate(channels):
            x = seg[:, ch]
            item[f"{name}_peak_v"] = float(np.abs(x).max())
            item[f"{name}_freq_hz"] = dominant_hz(x, sample_rate_hz)
        out.append(item)
    return out


def dominant_hz(x: np.ndarray, sample_rate_hz: int) -> float | None:
    """Frequency of the largest spectral peak (parabolic interpolation), None if silent."""
    x = np.asarray(x, float)
    if x.size < 8 or not np.any(x):
        return None
    n = 1 << int(np.ceil(np.log2(4 * x.size)))
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size), n))
    k = int(np.argmax(spec[1:])) + 1
    if 1 <= k < spec.size - 1:
        a, b, c = spec[k - 1], spec[k], spec[k + 1]
        den = a - 2 * b + c
        k = k + (0.5 * (a - c) / den if den else 0.0)
    return float(k * sample_rate_hz / n)


def _plan_entry(plan, i: int, arrays: dict[str, np.ndarray]) -> dict[str, Any]:
    segs = []
    for j, s in enumerate(plan.segments):
        arrays[f"plan{i}_seg{j}_piezo_v"] = np.asarray(s.piezo_v, float)
        arrays[f"plan{i}_seg{j}_screen_v"] = np.asarray(s.screen_v, float)
        for patch, v in s.patch_v.items():  # a drive of its own
            arrays[f"plan{i}_seg{j}_{patch}_v"] = np.asarray(v, float)
        segs.append(
            {
                "label": s.label,
                "patches": sorted(s.patches),
                "screen": bool(s.screen),
                "own_drives": sorted(s.patch_v),
                "n_samples": s.n_samples,
                "piezo_peak_v": float(np.abs(s.piezo_v).max()) if s.n_samples else 0.0,
                "screen_peak_v": float(np.abs(s.screen_v).max()) if s.n_samples else 0.0,
            }
        )
    return {"name": plan.name, "segments": segs, "meta": plan.meta}


def write_twin_log(path: str | os.PathLike, outputs, played: list) -> Path | None:
    """Write the JSON summary (and the .npz of samples) for ``outputs``: open ones, or
    closed ones that kept their ``record`` (``close(keep_record=True)``); ``played`` lists
    the ``OutputPlan``s the console sent. Returns the JSON path (None on real hardware, or
    when nothing was kept)."""
    record = outputs.record
    if record is None:
        if outputs.closed or outputs.lost:
            return None
        record = outputs.snapshot()
    rec, log = record.recording_v, record.relay_log
    if rec is None and log is None:
        return None
    fs = int(outputs.limits.sample_rate_hz)
    arrays: dict[str, np.ndarray] = {}
    data = {
        "sample_rate_hz": fs,
        "recorded_samples": 0 if rec is None else int(len(rec)),
        "channels": list(outputs.limits.channels),
        "bursts": [] if rec is None else bursts(rec, fs, channels=outputs.limits.channels),
        "relay_log": [
            {
                "clock": int(r.clock),
                "channel": int(r.channel),
                "closed": bool(r.closed),
                "level_v": [float(v) for v in r.level_v],
            }
            for r in (log or [])
        ],
        "played": [_plan_entry(p, i, arrays) for i, p in enumerate(played)],
        "estop_reason": record.estop_reason,
        "latency_samples": int(record.latency_samples),
        # the DAC starved before these clocks: the samples after each (until the
        # slew-limited follower caught up with the gate) differ from what was sent
        "underruns": [{"clock": c, "samples": n} for c, n in record.underruns],
        "gate_events": [
            {
                "kind": e.kind,
                "clock": int(e.clock),
                "t_s": float(e.t_s),
                "message": e.message,
                "cut": e.cut,
            }
            for e in record.events
        ],
    }
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    write_private(p, json.dumps(data, indent=2, default=_jsonable))
    if rec is not None:
        arrays["recording_v"] = np.asarray(rec, float)
    with os.fdopen(open_private(p.with_suffix(".npz")), "wb") as f:
        np.savez_compressed(f, **arrays)
    return p


def copy_twin_log(src: Path, dst: Path) -> None:
    """Copy a written log (``.json`` and ``.npz``) to ``dst``, never through a symlink."""
    dst.parent.mkdir(parents=True, exist_ok=True)
    write_private(dst, src.read_bytes())
    write_private(dst.with_suffix(".npz"), src.with_suffix(".npz").read_bytes())


def write_env_twin_log(outputs) -> Path | None:
    """Write the log to ``$HAPTABLE_TWIN_LOG`` when it is set (a command's closed outputs);
    a failure is one line on stderr, never an exception (the outputs are closed already)."""
    path = os.environ.get(ENV)
    if not path:
        return None
    try:
        return write_twin_log(path, outputs, [])
    except Exception as exc:
        print(f"haptable: twin log: {exc}", file=sys.stderr)
        return None


def _jsonable(o: Any) -> Any:
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, (set, frozenset, tuple)):
        return list(o)
    return str(o)
