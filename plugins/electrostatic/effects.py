"""Effect renderers: a single electrovibration stimulus and the knob (finite or live)."""

from __future__ import annotations

from typing import Any

import numpy as np

from console.plugin_api import Limits, OutputPlan, Segment, UserError

from .force import Material, expected_force, threshold_check
from .session import KnobSession
from .settings import audio, electrostatic_settings, knob_settings, limits
from .simulate import canned_rotation, run_pipeline
from .synth import KnobStream, parse_condition, smooth_square
from .task import SimFinger, make_trials, run_live_trial, run_trial


def raised_cosine_ramps(n: int, ramp_n: int) -> np.ndarray:
    """Gain 0 -> 1 -> 0 with raised-cosine ends of ``ramp_n`` samples; exactly 0 at both ends."""
    g = np.ones(n)
    r = min(ramp_n, n // 2)
    if r > 0:
        up = 0.5 - 0.5 * np.cos(np.pi * np.arange(r) / r)
        g[:r] = up
        g[n - r :] = up[::-1]
    elif n:
        g[0] = g[-1] = 0.0
    return g


def friction_stimulus(
    vpp: float,
    freq_hz: float,
    duration_s: float,
    *,
    waveform: str = "sine",
    sample_rate_hz: int = 48000,
    ramp_ms: float = 10.0,
    edge_ms: float = 0.5,
) -> np.ndarray:
    """Screen voltage of a plain electrovibration stimulus with start/stop ramps."""
    n = max(int(round(duration_s * sample_rate_hz)), 1)
    x = unit_wave(n, freq_hz, waveform, sample_rate_hz, edge_ms)
    return (vpp / 2) * x * raised_cosine_ramps(n, int(round(ramp_ms * sample_rate_hz / 1000)))


def unit_wave(
    n: int, freq_hz: float, waveform: str, sample_rate_hz: int, edge_ms: float = 0.5
) -> np.ndarray:
    """``n`` samples of a sine or (smoothed-edge) square of amplitude 1, no ramps."""
    ph = 2 * np.pi * freq_hz * np.arange(n) / sample_rate_hz
    if waveform == "sine":
        return np.sin(ph)
    if waveform == "square":
        return smooth_square(ph, edge_ms * 1e-3 * freq_hz)
    raise UserError(f"waveform {waveform!r}: unknown; use sine or square")


def slew_max_vpp(profile: Any, freq_hz: float, waveform: str = "sine") -> float:
    """The largest Vpp of a ``waveform`` at ``freq_hz`` that stays inside the screen's
    slew limit (``Limits.slew_v_per_s("screen")``: [amplifiers] screen_peak_current_ma /
    [screen] capacitance_nf): the stimulus's steepest step per volt, without its start
    and stop ramps (they only make it gentler). A sine's is pi f Vpp; a square's is set by
    its edges (``edge_ms``), whatever the frequency."""
    fs = audio(profile)["sample_rate_hz"]
    slew = Limits.from_profile(profile).slew_v_per_s("screen")
    n = int(round(2.0 / max(freq_hz, 1.0) * fs)) + 2  # two periods
    x = unit_wave(n, freq_hz, waveform, fs) / 2  # 1 Vpp
    per_vpp = float(np.abs(np.diff(x)).max(initial=0.0)) * fs
    return slew / per_vpp if per_vpp > 0 else float("inf")


def stimulus_report(
    vpp: float, freq_hz: float, profile: Any = None, waveform: str = "sine"
) -> dict[str, Any]:
    """Expected force and threshold margin of a stimulus (what the console shows)."""
    es = electrostatic_settings(profile)
    fs = audio(profile)["sample_rate_hz"]
    v = friction_stimulus(vpp, freq_hz, 0.2, waveform=waveform, sample_rate_hz=fs, ramp_ms=0)
    out = expected_force(v, fs, Material.from_settings(es), freq_hz=freq_hz)
    try:
        th = threshold_check(vpp, freq_hz, es, waveform)
    except ValueError as exc:
        key = "threshold_square_vpp" if waveform == "square" else "threshold_vpp"
        raise UserError(f"[electrostatic] threshold_freq_hz / {key}: {exc}") from None
    return {"vpp": vpp, "waveform": waveform, **out, **th}


def condition_report(condition: str, profile: Any = None) -> list[dict[str, Any]]:
    """The signals a knob condition plays, each with expected force and threshold check."""
    c = parse_condition(condition)
    k = knob_settings(profile)
    rows = []
    if c.detent == "screen":
        # a rectangular pulse of +-vpp/2 (polarity alternates) is judged as the square
        # wave whose half period is the pulse (or as the burst's own square wave)
        f = k["detent_freq_hz"] or 1000.0 / (2 * k["detent_ms"])
        r = stimulus_report(k["detent_vpp"], f, profile, "square")
        r["note"] = (
            f"{k['detent_ms']:g} ms square burst at {f:g} Hz"
            if k["detent_freq_hz"]
            else f"{k['detent_ms']:g} ms pulses of +-{k['detent_vpp'] / 2:g} V, alternating (judged as a {f:.0f} Hz square)"
        )
        rows.append(("detent", r))
    if c.friction == "constant":
        rows.append(("friction", stimulus_report(k["carrier_vpp"], k["cf_freq_hz"], profile)))
    if c.friction == "velocity":
        for key in ("vf_freq_at_rest_hz", "vf_freq_at_speed_hz"):
            rows.append((key, stimulus_report(k["carrier_vpp"], k[key], profile)))
    if c.friction == "boundary":
        for key in ("bf_min_vpp", "bf_max_vpp"):
            rows.append((key, stimulus_report(k[key], k["cf_freq_hz"], profile)))
    return [{"signal": name, **r} for name, r in rows]


class ElectrostaticEffect:
    """``render(vpp=, freq_hz=, duration_s=, waveform=)`` -> OutputPlan on the screen."""

    def __init__(self, profile: Any = None) -> None:
        self.profile = profile

    def render(
        self,
        vpp: float = 100.0,
        freq_hz: float = 180.0,
        duration_s: float = 1.0,
        waveform: str = "sine",
    ) -> OutputPlan:
        lim = limits(self.profile)
        if vpp > lim["screen_max_vpp"]:
            raise UserError(
                f"electrostatic vpp = {vpp:g}: above [limits] screen_max_vpp = "
                f"{lim['screen_max_vpp']:g}; lower it"
            )
        fs = audio(self.profile)["sample_rate_hz"]
        if not 0 < freq_hz < fs / 4:
            raise UserError(
                f"electrostatic freq_hz = {freq_hz:g}: must be between 0 and {fs / 4:g} Hz"
            )
        if not 0 < duration_s <= 60:
            raise UserError(f"electrostatic duration_s = {duration_s:g}: must be in (0, 60] s")
        # a raised cosine stays under the gate's linear ramp when it is pi/2 times longer
        ramp_ms = max(knob_settings(self.profile)["ramp_ms"], np.pi / 2 * lim["ramp_min_ms"])
        v = friction_stimulus(
            vpp, freq_hz, duration_s, waveform=waveform, sample_rate_hz=fs, ramp_ms=ramp_ms
        )
        if self.profile is not None:
            slew_v_per_s = Limits.from_profile(self.profile).slew_v_per_s("screen")
            fastest = float(np.abs(np.diff(v)).max(initial=0.0)) * fs
            if fastest > slew_v_per_s:
                raise UserError(
                    f"electrostatic {waveform} {vpp:g} Vpp at {freq_hz:g} Hz changes at "
                    f"{fastest / 1e3:.0f} V/ms, faster than the screen's slew limit of "
                    f"{slew_v_per_s / 1e3:.0f} V/ms ([amplifiers] screen_peak_current_ma / "
                    f"[screen] capacitance_nf); lower vpp or freq_hz"
                )
        seg = Segment(
            np.zeros_like(v), v, frozenset(), True, f"{waveform} {vpp:g} Vpp {freq_hz:g} Hz"
        )
        meta = stimulus_report(vpp, freq_hz, self.profile, waveform)
        return OutputPlan(fs, (seg,), name="electrostatic", meta=meta)


class KnobEffect:
    """The knob: ``render(condition=)`` plays a canned rotation as a finite plan;
    ``stream(condition=, sectors=)`` returns the live ``KnobStream``."""

    def __init__(self, profile: Any = None) -> None:
        self.profile = profile

    def stream(self, condition: str = "HD+VF", sectors: int | None = None) -> KnobStream:
        k = knob_settings(self.profile)
        return KnobStream(
            condition,
            audio(self.profile)["sample_rate_hz"],
            k,
            limits(self.profile),
            sectors=sectors or k["sectors"],
        )

    def session(self, condition: str = "HD+VF", sectors: int | None = None) -> Any:
        """A live ``KnobSession``: ``feed(t_s, contacts)`` per camera frame drives
        ``.stream`` (the StreamSource to give ``out.stream``) and ``.knob.item``."""
        k = knob_settings(self.profile)
        a = audio(self.profile)
        return KnobSession(
            parse_condition(condition).name,
            sectors=sectors or k["sectors"],
            settings=k,
            limits=limits(self.profile),
            sample_rate_hz=a["sample_rate_hz"],
            block=a["block_size"],
            record=False,
        )

    def knob_trial(
        self, *, condition: str, sectors: int, distance_deg: float, seed: int
    ) -> dict[str, Any]:
        """One trial of the paper's knob task (``task.run_trial``) with the simulated
        finger (``contracts.KnobTrials``): its measures as a dict."""
        from dataclasses import asdict

        c = parse_condition(condition).name
        (trial,) = make_trials([c], [int(sectors)], [float(distance_deg)], 1, seed=0)
        res = run_trial(
            trial,
            settings=knob_settings(self.profile),
            limits=limits(self.profile),
            finger=SimFinger(),
            rng=np.random.default_rng(int(seed)),
            sample_rate_hz=audio(self.profile)["sample_rate_hz"],
            block=audio(self.profile)["block_size"],
        )
        return asdict(res)

    def knob_live_trial(
        self,
        *,
        condition: str,
        sectors: int,
        distance_deg: float,
        outputs: Any,
        attach: Any,
        max_time_s: float = 30.0,
    ) -> dict[str, Any]:
        """One trial of the knob task with a person (``task.run_live_trial``): the trial's
        knob session streams through ``outputs`` and is handed to ``attach(session)``,
        which feeds it the camera's contacts (``session.feed(t_capture_s, contacts)``),
        then ``attach(None)``. Its measures as a dict."""
        from dataclasses import asdict

        c = parse_condition(condition).name
        (trial,) = make_trials([c], [int(sectors)], [float(distance_deg)], 1, seed=0)
        a = audio(self.profile)
        res = run_live_trial(
            trial,
            settings=knob_settings(self.profile),
            outputs=outputs,
            attach=attach,
            limits=limits(self.profile),
            sample_rate_hz=a["sample_rate_hz"],
            block=a["block_size"],
            max_time_s=float(max_time_s),
        )
        return asdict(res)

    def render(
        self, condition: str = "HD+VF", sectors: int | None = None, seed: int = 0
    ) -> OutputPlan:
        k = knob_settings(self.profile)
        a = audio(self.profile)
        c = parse_condition(condition)
        r = run_pipeline(
            canned_rotation(seed=seed),
            c.name,
            sample_rate_hz=a["sample_rate_hz"],
            block=a["block_size"],
            settings=k,
            limits=limits(self.profile),
            sectors=sectors or k["sectors"],
        )
        patches = KnobStream(c, a["sample_rate_hz"], k, limits(self.profile)).patches
        seg = Segment(
            r.piezo_v,
            r.screen_v,
            patches,
            c.detent == "screen" or c.friction != "none",
            f"knob {c.name}",
        )
        return OutputPlan(
            a["sample_rate_hz"], (seg,), name=f"knob {c.name}", meta={"crossings": len(r.crossings)}
        )
