"""Meta Haptics Studio's ``.haptic`` files read into and written from the shared model
(``console.signals.haptic_files``: the mapping onto the patches).

A ``.haptic`` file is JSON::

    {"version": {"major": 1, "minor": 0, "patch": 0},
     "metadata": {"editor": ..., "author": ..., "source": ..., "project": ..., "tags": [],
                  "description": ...},
     "signals": {"continuous": {"envelopes": {
         "amplitude": [{"time": 0.0, "amplitude": 0.5,
                        "emphasis": {"amplitude": 0.9, "frequency": 0.7}}, ...],
         "frequency": [{"time": 0.0, "frequency": 0.3}, ...]}}}}

Amplitude and frequency are breakpoint envelopes in 0..1, linear between breakpoints (two
at one time, a step, become an edge of ``EDGE_S``); an emphasis on an amplitude breakpoint
is a transient there (its amplitude and frequency). Without a frequency envelope the
carrier sits at frequency 0.5. Keys this reader does not use are dropped and listed.
As Meta's own reader does, an amplitude envelope needs two breakpoints and a frequency
breakpoint may not lie after the amplitude envelope's end. Checked against the files of
facebook/meta-haptics-sdk ``core/haptic_data/test_files/`` (``multiple_emphasis.haptic``,
``long_clip.haptic``, ``invalid_single_amplitude_breakpoint.haptic``,
``invalid_freq_bp_outside_amp_env.haptic``): the same keys.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from console.core.plain_numbers import plain_s
from console.signals.haptic_files import (
    MAX_TIME_S,
    Exported,
    Pattern,
    bad,
    load_json,
    make_grid,
    need,
    num,
    strictly,
)

_EXAMPLE = '{"version": {"major": 1}, "signals": {"continuous": {"envelopes": {...}}}}'


def _points(path: Path, env: dict, key: str, value: str, required: bool) -> list[dict]:
    where = f"signals.continuous.envelopes.{key}"
    if key not in env:
        if required:
            raise bad(path, where, "missing", f'give [{{"time": 0, "{value}": 0.5}}, ...]')
        return []
    pts = need(path, env[key], list, where, f'[{{"time": 0, "{value}": 0.5}}, ...]')
    if required and not pts:
        raise bad(path, where, "empty", "give at least two breakpoints (a start and an end)")
    last = 0.0
    for i, p in enumerate(pts):
        need(path, p, dict, f"{where}[{i}]", f'{{"time": 0.1, "{value}": 0.5}}')
        t = num(path, p, "time", f"{where}[{i}]", 0.0, MAX_TIME_S)
        if t < last:
            raise bad(path, f"{where}[{i}].time", f"{plain_s(t)} comes before the breakpoint above",
                      "give breakpoints in time order")  # fmt: skip
        num(path, p, value, f"{where}[{i}]", 0.0, 1.0)
        last = t
    if required and len(pts) < 2:  # as Meta's reader: a start and an end
        raise bad(path, where, "holds one breakpoint", "give at least two (a start and an end)")
    return pts


def read(path: str | Path) -> Pattern:
    """The pattern a ``.haptic`` file holds (one ``UserError`` line for anything malformed)."""
    path = Path(path)
    doc = need(path, load_json(path, ".haptic"), dict, "the top level", _EXAMPLE)
    if "version" not in doc:
        raise bad(path, "version", "missing", f"a .haptic file holds {_EXAMPLE}")
    ver = need(path, doc["version"], dict, "version", '{"major": 1, "minor": 0, "patch": 0}')
    major = ver.get("major")
    if major != 1 or isinstance(major, bool):
        raise bad(path, "version.major", f"{major!r} is not a version this reader knows",
                  "save the file as .haptic version 1")  # fmt: skip
    dropped = [f"key {k}" for k in doc if k not in ("version", "metadata", "signals")]
    sig = need(path, doc.get("signals"), dict, "signals", '{"continuous": {...}}')
    dropped += [f"signals.{k}" for k in sig if k != "continuous"]
    cont = need(path, sig.get("continuous"), dict, "signals.continuous", '{"envelopes": {...}}')
    env = need(path, cont.get("envelopes"), dict, "signals.continuous.envelopes",
               '{"amplitude": [...], "frequency": [...]}')  # fmt: skip
    dropped += [f"envelope {k}" for k in env if k not in ("amplitude", "frequency")]
    amp_pts = _points(path, env, "amplitude", "amplitude", True)
    freq_pts = _points(path, env, "frequency", "frequency", False)
    transients = []
    for i, p in enumerate(amp_pts):
        if "emphasis" in p:
            w = f"signals.continuous.envelopes.amplitude[{i}].emphasis"
            e = need(path, p["emphasis"], dict, w, '{"amplitude": 0.9, "frequency": 0.7}')
            transients.append((float(p["time"]), num(path, e, "amplitude", w, 0.0, 1.0),
                               num(path, e, "frequency", w, 0.0, 1.0)))  # fmt: skip
    if freq_pts and freq_pts[-1]["time"] > amp_pts[-1]["time"]:
        raise bad(path, f"signals.continuous.envelopes.frequency[{len(freq_pts) - 1}].time",
                  f"{plain_s(freq_pts[-1]['time'])} is after the amplitude envelope's end "
                  f"({plain_s(amp_pts[-1]['time'])})", "end the frequency envelope by then")  # fmt: skip
    ta, va = strictly([p["time"] for p in amp_pts], [p["amplitude"] for p in amp_pts])
    tf, vf = strictly([p["time"] for p in freq_pts], [p["frequency"] for p in freq_pts])
    end = max(ta[-1], (tf[-1] if tf else 0.0), max((t for t, _a, _f in transients), default=0))
    end = max(end, 1e-3)
    grid = make_grid(end, ta + tf)
    amp = np.interp(grid, ta, va, left=va[0], right=0.0 if end > ta[-1] else va[-1])
    sharp = np.interp(grid, tf, vf) if tf else np.full(grid.size, 0.5)
    mapped = [f"{len(amp_pts)} amplitude breakpoints", f"{len(freq_pts)} frequency breakpoints",
              f"{len(transients)} emphases"]  # fmt: skip
    return Pattern(".haptic", path, grid, amp, sharp, transients, mapped, dropped)


def write(e: Exported, description: str) -> str:
    """A ``.haptic`` file's text for the exported signal ``e``."""
    amp = [{"time": round(float(t), 6), "amplitude": round(float(a), 5)}
           for t, a in zip(e.amp_t_s, e.amp, strict=True)]  # fmt: skip
    freq = [{"time": round(float(t), 6), "frequency": round(float(s), 5)}
            for t, s in zip(e.sharp_t_s, e.sharp, strict=True)]  # fmt: skip
    doc = {
        "version": {"major": 1, "minor": 0, "patch": 0},
        "metadata": {
            "editor": "HapTable",
            "author": "",
            "source": "",
            "project": "",
            "tags": [],
            "description": description,
        },  # fmt: skip
        "signals": {"continuous": {"envelopes": {"amplitude": amp, "frequency": freq}}},
    }
    return json.dumps(doc, indent=1) + "\n"
