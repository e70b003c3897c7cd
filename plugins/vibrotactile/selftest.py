"""A technician's self-test: every relay path chirped through the gate, compared with a baseline.

With the sensor at the profile's reference point (``[selftest] reference_point``, a grid
point off the table's symmetry lines, where PA and PC, PB and PD differ; the twin moves its
sensor there), each path (each patch alone, then PALL) plays a short exponential chirp
through the safety gate (a plain plan: the gate closes that path's relays in silence and
opens the others), and the inputs give the acceleration H1 per volt and its coherence
(``plugins.vibrotactile.roving``; the loopback's delay removed). Each single path's H1 is
then fitted, by complex least squares over the band, as a mix of the baseline's four
single-path H1s: ``H_p = sum_q c_pq B_q``. A healthy table gives c = I (within its drift);

- a row of c near 0: that path moves nothing. Every path silent on a bus profile: the
  amplifier channel is dead; one path: its relay stuck open (or its cable cut), or, on a
  channel-per-patch card, its amplifier channel dead;
- a column q near 1 in every other row: patch q moves while its relay is commanded open
  (each other path plays with it open): relay q stuck closed;
- c_pq and c_qp near 1, the diagonal near 0: the wires of p and q swapped;
- c_pp well below 1 but the response still there, its shape kept: the patch detached;
- the path's level against its fit differing from band to band (``selftest_shape``): the
  patch cracked (its FRF shifted, not gone);
- c_pp off by more than the drift, or the fit leaving a residual: the bond or the
  amplifier's gain changed, or the FRF shifted.

The baseline is the last self-test saved (``--save-baseline``), or, on a table without
one, the stored vibration map at the reference point (``selftest_map``: a first self-test
already finds faults; a healthy first run saves its baseline). Thresholds
(``Thresholds``) come from 20 healthy twin tables with their noise and drift (``haptable
bench selftest``: each is the largest value those tables showed, times a margin, see the
bench's ``thresholds`` entry).
"""

from __future__ import annotations

import json
import math
import os
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import (
    EXCITATIONS,
    PATCHES,
    ChannelLayout,
    UserError,
    data_dir,
)
from plugins.vibrotactile.roving import RovingSettings, delay_samples, h1
from plugins.vibrotactile.selftest_chirp import path_plan
from plugins.vibrotactile.selftest_shape import SILENT, kept_db, on_freqs, spread_db

#: the default reference point: row 5, column 4 of the 7 x 12 grid (off both symmetry lines)
DEFAULT_POINT = 52
BASELINE_VERSION = 1


@dataclass(frozen=True)
class Thresholds:
    """When a mix coefficient or a fit says fault (see the module's docstring). On 20
    healthy twin tables (``haptable bench selftest``: own noise, sensor re-glued within
    1 mm at 6.7-7.3 g, gains drifted 1.5 %; one chirp per path) the worst were 0.36 dB of
    gain, a residual of 0.025, an off-diagonal mix of 0.03, a diagonal of 0.962 and a band
    spread of 0.55 dB (against the map: 0.36 dB, 0.017, 0.026, 0.96, 0.37 dB): each
    threshold sits about 4x (cross: 10x, crack: 10x) beyond, and still inside the faults'
    own values (a cracked patch spreads 8-15 dB and keeps a band within -5 dB; a detached
    one is 20 dB and more down in every band)."""

    silent: float = SILENT  # |c| below: no response (-46 dB; noise alone gives ~1e-4)
    weak: float = 0.5  # c_pp below (and above ``silent``): detached or cracked (-6 dB)
    cross: float = 0.3  # |c_pq|, p != q, above: patch q moves when p plays
    gain_db: float = 1.5  # |20 log10 |c_pp|| above: the path's gain drifted
    residual: float = 0.1  # fit residual / baseline norm above: the FRF changed shape
    crack_db: float = 6.0  # band levels against the fit spread more: the patch cracked
    crack_kept_db: float = -12.0  # ... with one band above this (a detached one: all below)
    pall_db: float = 1.5  # PALL's level against the baseline's


@dataclass(frozen=True)
class SelftestSettings:
    """The chirp of each path (volts at the patches, seconds, hertz). One chirp per path:
    at 10 V the sensor's SNR is high (the healthy tables' worst values sit far inside the
    thresholds with one, ``haptable bench selftest``), and a second one only doubled the
    audio (10 s to 5 s for the five paths); the tail lets the plate ring out (zeta f at 40
    Hz: 0.4 s decay time), so it stays."""

    level_v: float = 10.0
    sweep_s: float = 0.5
    tail_s: float = 0.5
    repeats: int = 1
    band_hz: tuple[float, float] = (40.0, 625.0)
    pall: bool = True

    def roving(self) -> RovingSettings:
        return RovingSettings(
            level_v=self.level_v,
            f_start_hz=20.0,
            f_stop_hz=700.0,
            sweep_s=self.sweep_s,
            tail_s=self.tail_s,
            repeats=self.repeats,
            band_hz=self.band_hz,
        )


FULL = SelftestSettings()
QUICK = SelftestSettings(pall=False)  # the same bins as a full run's baseline


@dataclass(frozen=True)
class Finding:
    kind: str  # dead_channel | relay_stuck_open | relay_stuck_closed | swapped | detached | ...
    subject: str  # the patch, relay or channel it names
    line: str  # one line with the fix

    def to_json(self) -> dict:
        return asdict(self)


@dataclass
class Layout:
    """What a path goes through: each patch's relay (0: none) and amplifier channel."""

    relay: dict[str, int]
    channel: dict[str, str]  # patch -> its output channel's name ('piezo' on a bus)
    card_output: dict[str, int] = field(default_factory=dict)  # channel -> 1-based output

    @classmethod
    def from_profile(cls, profile: Any) -> Layout:
        names = list(ChannelLayout.from_profile(profile).names)
        relay = {p: int(profile.get(f"patches.{p}.relay_channel") or 0) for p in PATCHES}
        channel = {p: (p if p in names else "piezo") for p in PATCHES}
        return cls(relay, channel, {n: i + 1 for i, n in enumerate(names)})

    @property
    def bus(self) -> bool:
        return len(set(self.channel.values())) == 1


# ------------------------------------------------------------------ the reference point
def reference_point(profile: Any) -> tuple[int, float, float]:
    """``[selftest] reference_point`` (a grid number) -> (number, x_mm, y_mm)."""
    g = profile.section("grid")
    rows, cols, pitch = int(g["rows"]), int(g["columns"]), float(g["pitch_mm"])
    n = profile.get("selftest.reference_point")
    n = DEFAULT_POINT if n is None else int(n)
    if not 1 <= n <= rows * cols:
        raise UserError(
            f"{profile.path}: [selftest] reference_point = {n}: the grid has points "
            f"1..{rows * cols}; name one off the table's symmetry lines, e.g. {DEFAULT_POINT}"
        )
    k = n - 1
    ox, oy = g["origin_mm"]
    return n, float(ox + (k % cols) * pitch), float(oy + (k // cols) * pitch)


def baseline_path(profile: Any, given: str | os.PathLike | None = None) -> Path:
    if given:
        return Path(given)
    p = profile.get("selftest.baseline")
    if p:
        return Path(p)
    return data_dir("selftest", f"{Path(str(profile.path)).stem}-baseline.npz")


# ------------------------------------------------------------------ measuring
def measure_paths(outputs: Any, s: SelftestSettings) -> dict[str, Any]:
    """Each path's acceleration H1 (m/s^2 per volt, delay removed) and coherence."""
    # lazy: the runtime part loads on first use
    from console.plugin_api.runtime import capture

    rs = s.roving()
    fs = int(outputs.limits.sample_rate_hz)
    paths = tuple(EXCITATIONS if s.pall else EXCITATIONS[:4])
    hs, cohs, freqs = [], [], None
    for exc in paths:
        plan, record = path_plan(exc, rs, fs)  # NumPy: no scipy.signal import
        cap = capture(outputs, plan)
        n = record.size
        y = cap.physical("accelerometer")[: n * rs.repeats].reshape(rs.repeats, n)
        delay = 0.0
        if any(sp.kind == "loopback" for sp in cap.specs):
            delay = delay_samples(record, cap.physical("loopback")[:n])
        f, h, coh = h1(np.broadcast_to(record, y.shape), y, fs)
        keep = (f >= s.band_hz[0]) & (f <= s.band_hz[1])
        hs.append(h[keep] * np.exp(2j * math.pi * f[keep] * delay / fs))
        cohs.append(coh[keep])
        freqs = f[keep]
    return {"paths": paths, "freqs_hz": freqs, "h": np.array(hs), "coherence": np.array(cohs)}


def planned_s(profile: Any, quick: bool = False) -> tuple[float, int]:
    """(seconds of chirp and ring-out a run plays, paths) of a self-test on ``profile``:
    what it takes at least, said before it starts (nothing plays here)."""
    s = QUICK if quick else FULL
    fs = int(profile.get("audio.sample_rate_hz"))
    paths = EXCITATIONS if s.pall else EXCITATIONS[:4]
    return sum(path_plan(exc, s.roving(), fs)[0].duration_s for exc in paths), len(paths)


def save_baseline(path: Path, got: dict[str, Any], ref: tuple[int, float, float]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp.npz")
    np.savez(
        tmp,
        version=BASELINE_VERSION,
        paths=np.array(got["paths"]),
        freqs_hz=got["freqs_hz"],
        h=got["h"],
        coherence=got["coherence"],
        reference=np.array(ref, float),
    )
    os.replace(tmp, path)


def load_baseline(path: Path) -> dict[str, Any] | None:
    if not path.exists():
        return None
    try:
        with np.load(path) as z:
            if int(z["version"]) != BASELINE_VERSION:
                raise ValueError("another version")
            return {k: z[k] for k in ("paths", "freqs_hz", "h", "coherence", "reference")}
    except (OSError, ValueError, KeyError) as exc:
        raise UserError(
            f"{path}: not a self-test baseline ({exc}); remove it and run "
            "`haptable selftest --save-baseline` on a healthy table"
        ) from None


# ------------------------------------------------------------------ comparing
def mix(got: dict[str, Any], base: dict[str, Any]) -> dict[str, np.ndarray]:
    """c (4, 4): each single path as a mix of the baseline's; residual (4,); PALL's dB."""
    freqs = got["freqs_hz"]
    b = on_freqs(freqs, base["freqs_hz"], base["h"])
    bp = {str(p): b[i] for i, p in enumerate(base["paths"])}
    basis = np.array([bp[p] for p in PATCHES])  # (4, F)
    h = {str(p): got["h"][i] for i, p in enumerate(got["paths"])}
    c = np.zeros((4, 4), complex)
    residual = np.zeros(4)
    for i, p in enumerate(PATCHES):
        c[i], *_ = np.linalg.lstsq(basis.T, h[p], rcond=None)
        residual[i] = np.linalg.norm(h[p] - basis.T @ c[i]) / np.linalg.norm(basis[i])
    pall_db = None
    if "PALL" in h and "PALL" in bp:
        pall_db = 20 * math.log10(np.linalg.norm(h["PALL"]) / np.linalg.norm(bp["PALL"]))
    hs = np.array([h[p] for p in PATCHES])
    spread = spread_db(freqs, hs, c @ basis)
    kept = kept_db(freqs, hs, basis)
    return {"c": c, "residual": residual, "pall_db": pall_db, "spread_db": spread, "kept_db": kept}


def _db(x: float) -> float:
    return 20 * math.log10(max(abs(x), 1e-6))


def findings(m: dict[str, Any], lay: Layout, th: Thresholds = Thresholds()) -> list[Finding]:
    """What the mix says, one line each with the fix (empty: healthy)."""
    a = np.abs(m["c"])
    out: list[Finding] = []
    silent = [i for i in range(4) if a[i].max() < th.silent]
    explained: set[int] = set()
    if len(silent) == 4 and lay.bus:
        ch = lay.channel["PA"]
        k = lay.card_output.get(ch, 1)
        return [
            Finding(
                "dead_channel",
                ch,
                f"amplifier channel '{ch}' (card output {k}): no path moves the glass: check "
                "the amplifier (power, mute, gain) and the cable from the card's output "
                f"{k}",
            )
        ]
    for i in silent:
        p = PATCHES[i]
        r, ch = lay.relay[p], lay.channel[p]
        if r:
            out.append(
                Finding(
                    "relay_stuck_open",
                    f"relay {r}",
                    f"{p}: no response on amplifier channel '{ch}' with relay {r} closed: "
                    f"relay {r} stuck open (or {p}'s cable cut): check relay {r} and the "
                    "cable to the patch",
                )
            )
        else:
            out.append(
                Finding(
                    "dead_channel",
                    ch,
                    f"{p}: no response on amplifier channel '{ch}' (card output "
                    f"{lay.card_output.get(ch, '?')}): check the amplifier channel and its cable",
                )
            )
        explained.add(i)
    # swapped wires: p's drive moves q as the baseline had it and the other way round
    for i in range(4):
        for j in range(i + 1, 4):
            if (
                a[i, j] > 1 - th.cross
                and a[j, i] > 1 - th.cross
                and a[i, i] < th.cross
                and a[j, j] < th.cross
            ):
                p, q = PATCHES[i], PATCHES[j]
                out.append(
                    Finding(
                        "swapped",
                        f"{p}/{q}",
                        f"{p} and {q}: wires swapped ({p}'s path moves the glass as {q} did "
                        f"in the baseline, and {q}'s as {p}): swap the two cables at the "
                        "patches' terminals",
                    )
                )
                explained |= {i, j}
    # a patch moving while its relay was commanded open (the other paths played)
    for j in range(4):
        q = PATCHES[j]
        others = [i for i in range(4) if i != j and i not in silent and i not in explained]
        if j in explained or not others or not all(a[i, j] > th.cross for i in others):
            continue
        r = lay.relay[q]
        if r:
            line = (
                f"relay {r} stuck closed: {q} moves while relay {r} is commanded open "
                f"(paths {', '.join(PATCHES[i] for i in others)} played): replace relay {r}"
            )
            out.append(Finding("relay_stuck_closed", f"relay {r}", line))
        else:
            line = f"{q} moves when the other patches play: check {q}'s wiring for a short"
            out.append(Finding("crosstalk", q, line))
    for i in range(4):
        if i in explained:
            continue
        p, c = PATCHES[i], a[i, i]
        if m["spread_db"][i] > th.crack_db and m["kept_db"][i] > th.crack_kept_db:
            out.append(
                Finding(
                    "cracked",
                    p,
                    f"{p}: its FRF shifted (level {m['spread_db'][i]:.0f} dB apart between "
                    "bands, not gone): the patch is cracked: replace it",
                )
            )
        elif c < th.weak:
            out.append(
                Finding(
                    "detached",
                    p,
                    f"{p}: response {-_db(c):.0f} dB below the baseline, its shape kept: the "
                    "patch is detached: check its bond to the glass and re-glue it",
                )
            )
        elif m["residual"][i] > th.residual:
            out.append(
                Finding(
                    "shifted",
                    p,
                    f"{p}: its FRF changed shape ({m['residual'][i]:.0%} left by the fit): "
                    "the patch cracked or its bond loosened, or the sensor is off the "
                    "reference point: check both",
                )
            )
        elif abs(_db(c)) > th.gain_db:
            out.append(
                Finding(
                    "gain",
                    p,
                    f"{p}: response {_db(c):+.1f} dB from the baseline: check the amplifier "
                    "channel's gain and the patch's bond",
                )
            )
    if not out and m["pall_db"] is not None and abs(m["pall_db"]) > th.pall_db:
        out.append(
            Finding(
                "gain",
                "PALL",
                f"PALL: response {m['pall_db']:+.1f} dB from the baseline though each patch "
                "alone is healthy: check the patches' parallel wiring",
            )
        )
    return out


# ------------------------------------------------------------------ the whole test
def _place_twin(outputs: Any, x_mm: float, y_mm: float) -> None:
    # lazy: the runtime part loads on first use
    from console.plugin_api.runtime import move_sensor

    move_sensor(outputs, x_mm, y_mm)


def run_selftest(
    outputs: Any,
    profile: Any,
    *,
    quick: bool = False,
    baseline: str | os.PathLike | None = None,
    save: bool = False,
    place: Callable[[Any, float, float], None] | None = None,
    thresholds: Thresholds = Thresholds(),
    vmap: Any = None,
    against: str = "auto",
) -> dict[str, Any]:
    """Measure every path at the reference point and compare with the baseline: a report
    (``findings``: lines; ``ok``; ``c``; ``elapsed_s``). Without a baseline the stored
    map ``vmap`` is the reference (``against="map"``: always), a healthy run then kept as
    the baseline; without either the first run saves the baseline."""
    # lazy: the map's comparison loads only when it is asked for
    from plugins.vibrotactile.selftest_map import map_baseline, mix_with_sensor

    t0 = time.perf_counter()
    ref = reference_point(profile)
    lay = Layout.from_profile(profile)
    path = baseline_path(profile, baseline)
    base = None if save or against == "map" else load_baseline(path)
    had_baseline = base is not None or (against == "map" and path.exists())
    s = QUICK if quick else FULL
    if against == "map" and vmap is None:
        raise UserError("selftest --against-map: no vibration map; measure or load one first")
    if not save and vmap is not None and base is None:
        base = map_baseline(vmap, ref, s.band_hz)  # a bad map is said before anything plays
    if (
        base is not None
        and "point_id" not in base
        and np.hypot(*(base["reference"][1:] - np.array(ref[1:]))) > 1.0
    ):
        raise UserError(
            f"{path}: a baseline taken at point {int(base['reference'][0])}, not at "
            f"[selftest] reference_point {ref[0]}; run `haptable selftest --save-baseline`"
        )
    if place is None and profile.get("audio.driver") == "twin":
        place = _place_twin
    if place is not None:
        place(outputs, ref[1], ref[2])
    got = measure_paths(outputs, s)
    report: dict[str, Any] = {
        "reference_point": ref[0],
        "reference_mm": [ref[1], ref[2]],
        "baseline": str(path),
        "quick": quick,
        "paths": list(got["paths"]),
        "coherence_median": [round(float(np.median(c)), 3) for c in got["coherence"]],
    }
    if base is None:
        _check_distinct(got, ref, profile)
        save_baseline(path, got, ref)
        report.update(ok=True, saved=True, findings=[], lines=[f"baseline saved to {path}"])
    else:
        on_map = "point_id" in base
        m = mix_with_sensor(got, base) if on_map else mix(got, base)
        found = findings(m, lay, thresholds)
        healthy = "all paths healthy" + (" against the vibration map" if on_map else "")
        lines = [f.line for f in found] or [healthy]
        saved = on_map and not found and not had_baseline
        if saved:  # the map vouched for this table: its next tests compare with this run
            save_baseline(path, got, ref)
            lines.append(f"baseline saved to {path}")
        report.update(
            ok=not found,
            saved=saved,
            against=f"vibration map (point {base['point_id']})" if on_map else "baseline",
            findings=[f.to_json() for f in found],
            lines=lines,
            c=np.abs(m["c"]).round(3).tolist(),
            residual=m["residual"].round(3).tolist(),
            pall_db=None if m["pall_db"] is None else round(m["pall_db"], 2),
            spread_db=m["spread_db"].round(2).tolist(),
        )
    report["elapsed_s"] = time.perf_counter() - t0
    return report


def _check_distinct(got: dict[str, Any], ref: tuple[int, float, float], profile: Any) -> None:
    """A baseline must tell the patches apart: two single paths alike there refuse it."""
    h = {str(p): got["h"][i] for i, p in enumerate(got["paths"])}
    for i, p in enumerate(PATCHES):
        for q in PATCHES[i + 1 :]:
            a, b = h[p], h[q]
            sim = abs(np.vdot(a, b)) / (np.linalg.norm(a) * np.linalg.norm(b) + 1e-30)
            if sim > 0.95:
                raise UserError(
                    f"{profile.path}: [selftest] reference_point = {ref[0]}: {p} and {q} move "
                    f"it alike ({sim:.0%}), so swapped wires would not show; name a point off "
                    f"the table's symmetry lines, e.g. {DEFAULT_POINT}"
                )


def summary_lines(report: dict[str, Any]) -> list[str]:
    return list(report["lines"])


def to_json(report: dict[str, Any]) -> str:
    return json.dumps(report, indent=1)
