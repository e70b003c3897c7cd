"""A simulated study participant on the plate twin (``contracts.SimulatedObserver``).

What it feels: the plan the outputs accepted, played into the twin from rest
(``closed_loop``: every segment's drive per patch, the gaps silent with the relays
open), read in each part's flat stretch as ``amplitude_um`` (sqrt 2 x RMS of everything
that moves: the part's tone and whatever still rings from the part before) at

- experiment 1 (``flow``): the two fingertips, on the pair's ``left`` and ``right`` grid
  points (where the fingers rest; the flow's direction is not read from the trial);
- experiment 2 (``hand_flow``): the 3 x 3 squares of a ``[vibrotactile] hand_mm`` hand
  centred on the region (a square's level is what half its subgrid points reach,
  ``square_levels_um``, as in the paper's section 5.2.2).

Sensation level ``s = max(0, 20 log10(a) - T(f) - o)``: ``T`` the ``[perception]``
threshold (fingertip: + ``fingertip_offset_db``; palm under the hand) at the part's
frequency (the drive's spectral peak), ``o`` the participant's threshold offset; under
threshold nothing is felt. For a candidate answer ``d`` whose first part should be felt
on side ``A_d`` and second on ``B_d`` the evidence is (dB)

    E_d = ((mean s_1[A_d] - mean s_1[B_d]) + (mean s_2[B_d] - mean s_2[A_d])) / 2

and the percept is a direction in the plane: ``z = K (E_right, E_down) / J`` (flows
between two fingers: ``E_left_to_right`` alone) plus independent noise ``N(0, 1/2)`` on
each axis; the answer is the candidate whose unit direction has the largest projection
of it (opposite answers share their axis' noise). ``J`` is one JND in dB,
``20 log10(1 + w(f))`` of the ``[perception]`` Weber curve (mean over the parts) times the
participant's ``jnd_scale``; ``K = 0.477`` makes one JND of evidence 75 % correct
between two opposite answers (``Phi(sqrt 2 K) = 0.75``). A symmetric stimulus (``E_d`` = 0)
is answered at chance. With probability ``lapse * k / (k - 1)`` (``k`` answers) the
observer lapses and answers at random, so a clear stimulus is answered correctly
``1 - lapse`` of the time (Wichmann and Hill's lapse rate).

Response time after the stimulus: ``t_nd + DT``, ``DT = a/(2v) tanh(a v / 2)`` the mean
decision time of a drift-diffusion with boundary separation ``a = 2`` and drift ``v`` =
the chosen candidate's margin in standard deviations (``a^2 / 4`` s at ``v = 0``), times
a log-normal factor (sigma 0.3).

Participants (seeded by ``participant_seed``; ASSUMPTIONS, no measured spread):
threshold offset ``o ~ N(0, 4 dB)``; ``jnd_scale ~ LogNormal(0, 0.25)``; ``lapse ~
Beta(1, 99)`` (mean 1 %: the paper's experiment 1 had every one of its 400 trials right,
so lapses are rare); ``t_nd ~ N(0.45, 0.08)`` s clipped to 0.2..0.9. The same seed and
trial give the same answer.
"""

from __future__ import annotations

import functools
import hashlib
import math
from collections import OrderedDict
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from console.plugin_api import Limits, OutputPlan, UserError

from .closed_loop import PATCHES, hand_subgrid_mm, part_envelopes, square_levels_um, twin_of
from .model import grid_points_mm

#: Candidate answers per stimulus kind, and the sides their parts should be felt on.
FLOW_ANSWERS = ("left_to_right", "right_to_left")
HAND_ANSWERS = ("up", "down", "left", "right")
#: Each answer's unit direction (x right, y down: ``console.core.types.DIRECTIONS_MM``).
AXES = {
    FLOW_ANSWERS: np.array([[1.0], [-1.0]]),
    HAND_ANSWERS: np.array([[0.0, -1.0], [0.0, 1.0], [-1.0, 0.0], [1.0, 0.0]]),
}
#: Evidence in JND -> decision noise units (one JND: 75 % with two answers).
K_JND = 0.4769
#: Drift-diffusion boundary separation (decision noise units).
DDM_BOUNDARY = 2.0
#: Participant distributions (documented in the module docstring).
OFFSET_SD_DB = 4.0
JND_SCALE_SIGMA = 0.25
LAPSE_BETA = (1.0, 99.0)
T_ND_S = (0.45, 0.08)
RT_SIGMA = 0.3
SETTLE_S = 0.2


@dataclass(frozen=True)
class ObserverParams:
    """One simulated participant."""

    threshold_offset_db: float
    jnd_scale: float
    lapse: float
    t_nd_s: float

    def as_dict(self) -> dict[str, Any]:
        return {
            "model": "plate twin psychophysical observer",
            "threshold_offset_db": self.threshold_offset_db,
            "jnd_scale": self.jnd_scale,
            "lapse": self.lapse,
            "t_nd_s": self.t_nd_s,
            "k_jnd": K_JND,
            "distributions": (
                f"offset N(0, {OFFSET_SD_DB} dB), jnd_scale LogNormal(0, {JND_SCALE_SIGMA}), "
                f"lapse Beta{LAPSE_BETA}, t_nd N{T_ND_S} s"
            ),
        }


@functools.lru_cache(maxsize=1024)
def participant(seed: int) -> ObserverParams:
    """The participant drawn from ``seed`` (the documented distributions)."""
    rng = np.random.default_rng([int(seed) % (2**63), 0x0B5E])
    return ObserverParams(
        threshold_offset_db=float(rng.normal(0.0, OFFSET_SD_DB)),
        jnd_scale=float(rng.lognormal(0.0, JND_SCALE_SIGMA)),
        lapse=float(rng.beta(*LAPSE_BETA)),
        t_nd_s=float(np.clip(rng.normal(*T_ND_S), 0.2, 0.9)),
    )


# --------------------------------------------------------------------------- perception data
def _interp_log(f_hz, xs, ys) -> np.ndarray:
    f = np.clip(np.asarray(f_hz, float), 1e-3, None)
    return np.interp(np.log(f), np.log(np.asarray(xs, float)), np.asarray(ys, float))


def threshold_db(perception: Mapping[str, Any], f_hz, site: str) -> np.ndarray:
    """Detection threshold (dB re 1 um peak) of ``[perception]`` at the fingertip or palm."""
    db = _interp_log(f_hz, perception["freq_hz"], perception["threshold_db_re_1um"])
    return db + (float(perception.get("fingertip_offset_db", 6.0)) if site == "fingertip" else 0)


def jnd_db(perception: Mapping[str, Any], f_hz) -> np.ndarray:
    """One intensity JND in dB: ``20 log10(1 + w(f))`` of the Weber curve."""
    w = _interp_log(
        f_hz,
        perception.get("weber_freq_hz", [10.0, 125.0]),
        perception.get("weber_fraction", [0.6, 0.2]),
    )
    return 20 * np.log10(1 + w)


# --------------------------------------------------------------------------- the stimulus
def plan_drive(plan: OutputPlan, guard_s: float) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """(n, 4) volts reaching PA..PD and each segment's (start, stop) samples: the
    segments one after the other with ``plan.gap_s + guard_s`` of silence between."""
    fs = plan.sample_rate_hz
    gap = int(round((plan.gap_s + guard_s) * fs))
    n = sum(s.n_samples for s in plan.segments) + gap * max(0, len(plan.segments) - 1)
    w = np.zeros((n, 4))
    spans, pos = [], 0
    for i, seg in enumerate(plan.segments):
        if i:
            pos += gap
        for name, v in seg.drives().items():
            names = PATCHES if name == "PALL" else (name,)
            for p in names:
                w[pos : pos + seg.n_samples, PATCHES.index(p)] = np.asarray(v, float)
        spans.append((pos, pos + seg.n_samples))
        pos += seg.n_samples
    return w, spans


def tone_hz(v: np.ndarray, fs: float) -> float:
    """The drive's dominant frequency: the spectral peak (Hann window), refined by a
    parabola through the log magnitudes around it."""
    v = np.asarray(v, float)
    if v.size < 8 or not np.any(v):
        return float("nan")
    spec = np.abs(np.fft.rfft(v * np.hanning(v.size)))
    k = int(np.argmax(spec[1:])) + 1
    if 1 <= k < spec.size - 1:
        a, b, c = np.log(np.maximum(spec[k - 1 : k + 2], 1e-300))
        den = a - 2 * b + c
        k = k + (0.5 * (a - c) / den if den else 0.0)
    return float(k * fs / v.size)


def _side_masks(direction: str, squares: int) -> tuple[np.ndarray, np.ndarray]:
    """(first side, second side) square masks [row(y), col(x)] of a flow ``direction``
    (``up`` runs toward -y, ``console.core.types.DIRECTIONS_MM``)."""
    lo = np.zeros((squares, squares), bool)
    hi = np.zeros((squares, squares), bool)
    if direction in ("left", "right"):
        lo[:, 0], hi[:, -1] = True, True
    else:
        lo[0, :], hi[-1, :] = True, True
    return (lo, hi) if direction in ("right", "down") else (hi, lo)


@dataclass(frozen=True)
class Percept:
    """What a trial's stimulus did at the skin: per part the frequency, the amplitude at
    each site (fingertips ``(2,)`` left/right, or squares ``(3, 3)``) and the site."""

    kind: str  # "flow" or "hand_flow"
    freqs_hz: tuple[float, ...]
    amplitude_um: tuple[np.ndarray, ...]
    site: str


class TwinObserver:
    """The simulated participant (module docstring); percepts are cached per plan."""

    def __init__(self, profile: Any) -> None:
        self.profile = profile
        self._twin = None
        self._cache: OrderedDict[str, Percept] = OrderedDict()
        sec = _section(profile, "perception")
        self.perception = {**_perception_defaults(), **sec}

    # -- contract
    def parameters(self, participant_seed: int) -> dict[str, Any]:
        return participant(participant_seed).as_dict()

    def respond(
        self, trial: Mapping[str, Any], played: OutputPlan, *, participant_seed: int
    ) -> tuple[str, float]:
        p = participant(participant_seed)
        answers, evidence, jnd = self.evidence(trial, played, p.threshold_offset_db)
        rng = np.random.default_rng([int(participant_seed) % (2**63), int(trial["index"]), 7])
        units = AXES[answers]  # (k, axes) unit direction of each answer
        z = K_JND * (units.T @ evidence) / 2 / (jnd * p.jnd_scale)  # percept, noise units
        k = len(answers)
        if rng.random() < p.lapse * k / (k - 1):
            choice = int(rng.integers(k))
            noisy = z
        else:
            noisy = z + rng.normal(0.0, math.sqrt(0.5), z.size)
            choice = int(np.argmax(units @ noisy))
        score = units @ z
        others = np.delete(score, choice)
        v = max(abs(float(score[choice] - others.max())) / math.sqrt(2 * 0.5), 1e-6)
        a = DDM_BOUNDARY
        dt = a / (2 * v) * math.tanh(a * v / 2)
        rt = (p.t_nd_s + dt) * float(rng.lognormal(0.0, RT_SIGMA))
        return answers[choice], rt

    # -- model
    def percept(self, trial: Mapping[str, Any], played: OutputPlan) -> Percept:
        """The stimulus at the skin for ``trial`` (cached per plan samples and place)."""
        stim = trial.get("stimulus") or {}
        kind = stim.get("effect")
        if kind not in ("flow", "hand_flow"):
            raise UserError(
                f"trial {int(trial.get('index', 0)) + 1}: the simulated observer answers flow "
                f"and hand-flow trials, not {stim!r}"
            )
        if len(played.segments) != 2:
            raise UserError(
                f"trial {int(trial.get('index', 0)) + 1}: {played.name!r} has "
                f"{len(played.segments)} parts; a flow has two"
            )
        h = hashlib.sha256(repr((kind, self._place(trial, played))).encode())
        h.update(repr((played.sample_rate_hz, played.gap_s)).encode())
        for seg in played.segments:
            for name, v in seg.drives().items():
                h.update(name.encode())
                h.update(np.ascontiguousarray(v, float).tobytes())
        key = h.hexdigest()
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        out = self._percept(kind, trial, played)
        self._cache[key] = out
        if len(self._cache) > 256:
            self._cache.popitem(last=False)
        return out

    def evidence(
        self, trial: Mapping[str, Any], played: OutputPlan, offset_db: float = 0.0
    ) -> tuple[tuple[str, ...], np.ndarray, float]:
        """(answers, evidence E_d in dB per answer, one JND in dB) for a participant whose
        threshold is ``offset_db`` above the curve."""
        pc = self.percept(trial, played)
        sl = [
            np.maximum(
                20 * np.log10(np.maximum(a, 1e-30))
                - threshold_db(self.perception, f, pc.site)
                - offset_db,
                0.0,
            )
            for a, f in zip(pc.amplitude_um, pc.freqs_hz, strict=True)
        ]
        jnd = float(np.mean(jnd_db(self.perception, np.array(pc.freqs_hz))))
        if pc.kind == "flow":
            e = ((sl[0][0] - sl[0][1]) + (sl[1][1] - sl[1][0])) / 2  # left first, right second
            return FLOW_ANSWERS, np.array([e, -e]), jnd
        n = sl[0].shape[0]
        ev = []
        for d in HAND_ANSWERS:
            a, b = _side_masks(d, n)
            ev.append(
                ((sl[0][a].mean() - sl[0][b].mean()) + (sl[1][b].mean() - sl[1][a].mean())) / 2
            )
        return HAND_ANSWERS, np.array(ev), jnd

    def _place(self, trial: Mapping[str, Any], played: OutputPlan) -> tuple:
        stim = trial["stimulus"]
        if stim.get("effect") == "flow":
            return tuple(map(tuple, self._finger_points(stim, played)))
        cx, cy = stim["center_mm"]
        return (float(cx), float(cy), self._hand()[0])

    def _finger_points(self, stim: Mapping[str, Any], played: OutputPlan) -> np.ndarray:
        """The fingertips (left, right) in mm: the pair's grid points (the played plan's
        own point positions when it names them, else the profile's grid)."""
        where: dict[int, list[float]] = {}
        meta = played.meta or {}
        if "from_mm" in meta and "to_mm" in meta and "from_point" in stim:
            where = {int(stim["from_point"]): meta["from_mm"], int(stim["to_point"]): meta["to_mm"]}

        gx, gy = grid_points_mm(self.profile)
        out = []
        for pid in (int(stim["left"]), int(stim["right"])):
            if pid in where:
                out.append([float(v) for v in where[pid]])
            elif 1 <= pid <= gx.size:
                out.append([float(gx[pid - 1]), float(gy[pid - 1])])
            else:
                raise UserError(f"flow pair point {pid}: not on the grid (1..{gx.size})")
        return np.array(out)

    def _hand(self) -> tuple[float, int, int]:
        vt = _section(self.profile, "vibrotactile")
        return (
            float(vt.get("hand_mm", 120.0)),
            int(vt.get("hand_squares", 3)),
            int(vt.get("hand_subgrid", 15)),
        )

    def _ramp_s(self) -> float:
        vt = _section(self.profile, "vibrotactile")
        return float(vt.get("ramp_ms", 100.0)) / 1e3

    def twin(self):
        if self._twin is None:
            self._twin = twin_of(self.profile)
        return self._twin

    def _percept(self, kind: str, trial: Mapping[str, Any], played: OutputPlan) -> Percept:

        fs = float(played.sample_rate_hz)
        guard_s = Limits.from_profile(self.profile).guard_samples / fs if self.profile else 0.0
        w, spans = plan_drive(played, guard_s)
        freqs = []
        for s, e in spans:
            col = int(np.argmax(np.abs(w[s:e]).max(axis=0)))
            freqs.append(tone_hz(w[s:e, col], fs))
        if kind == "flow":
            points: Any = self._finger_points(trial["stimulus"], played)
        else:
            hand_mm, squares, subgrid = self._hand()
            points = hand_subgrid_mm(trial["stimulus"]["center_mm"], hand_mm, squares, subgrid)
        ramp = self._ramp_s()
        settle = SETTLE_S
        shortest = min(e - s for s, e in spans) / fs
        if shortest < 2 * ramp + settle + 0.05:
            settle = 0.0
        env = part_envelopes(
            self.twin(),
            np.ones(w.shape[0]),
            w,
            points,
            fs,
            spans,
            ramp_s=ramp,
            settle_s=settle,
            peak_points=0,
        )
        if kind == "flow":
            amps = tuple(np.asarray(e.amplitude_um, float) for e in env)
            site = "fingertip"
        else:
            amps = tuple(square_levels_um(e.amplitude_um, squares, subgrid) for e in env)
            site = "palm"
        return Percept(kind, tuple(freqs), amps, site)


def _perception_defaults() -> dict[str, Any]:
    """``[perception]`` values when a profile has none (the same as the schema's)."""
    return {
        "freq_hz": [10.0, 40.0, 63.0, 100.0, 160.0, 250.0, 400.0, 500.0, 700.0],
        "threshold_db_re_1um": [12.0, 12.0, 4.0, -4.0, -12.0, -20.0, -15.0, -12.0, -6.0],
        "fingertip_offset_db": 6.0,
        "weber_freq_hz": [10.0, 125.0],
        "weber_fraction": [0.6, 0.2],
    }


def _section(profile: Any, name: str) -> dict[str, Any]:
    if profile is None:
        return {}
    try:
        return dict(profile.section(name) or {})
    except (KeyError, UserError):
        return {}
