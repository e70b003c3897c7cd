"""``haptable bench safety``: how fast the gate is checked, and how fast an e-stop silences.

- ``cases``: random plans, streams, attached sources and relay command sequences with
  injected faults (NaN, steps, exceptions, wrong dtypes and lengths, stalls, e-stops at
  random moments) played on the fast-forward twin; each case's recording and relay log
  checked by ``console.safety_audit``. Cases per second and the problems found (0 expected).
- ``estop``: e-stop latency, the request to the last non-zero sample at the driver (the
  twin's DAC, paced in real time; the sample at the DAC when the request came is taken as
  the gate's clock less the device latency, which errs late by up to one block), for the gate in the console's own process, for a demo
  in its own process (the console's Scenes screen) and for a CLI demo stopped by
  ``haptable estop`` from another process (there also the whole command's time, Python's
  start-up included, and the demo's own request -> confirmed silent).
"""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from console.bench import machine_info, summarize_s
from console.errors import SafetyRefusal
from console.safety import Source
from console.safety_audit import Window, received_problems
from console.signals import ramp_envelope, tone
from console.types import OutputPlan, Segment

FAULTS = ("none", "nan", "step", "raise", "object", "stall", "wrong_len")
ROUTES = {"PA": frozenset({"PA"}), "PALL": frozenset({"PA", "PB", "PC", "PD"})}


class FaultyStream:
    """A ramped sine that misbehaves (``fault``) from sample ``at`` on."""

    def __init__(self, route, amp, f, fault, at, n_total, fs=48000):
        self.patches, self.screen = route, False
        self.amp, self.f, self.fault, self.at = amp, f, fault, at
        self.n_total, self.fs, self.k = n_total, fs, 0

    def next_block(self, n):
        if self.k >= self.n_total:
            return None
        k = self.k + np.arange(n)
        x = self.amp * np.sin(2 * np.pi * self.f * k / self.fs) * np.minimum(1.0, k / 480)
        if self.k >= self.at:
            if self.fault == "nan":
                x[0] = np.nan
            elif self.fault == "step":
                x = x + 60.0
            elif self.fault == "raise":
                raise RuntimeError("effect crashed")
            elif self.fault == "object":
                x = x.astype(object)
            elif self.fault == "stall":
                time.sleep(0.15)
            elif self.fault == "wrong_len":
                x = x[:-1]
        self.k += n
        return x, np.zeros(len(x))

    def request_stop(self):
        self.n_total = self.k


class FaultySource(Source, FaultyStream):
    @property
    def idle(self):
        return False

    def abort(self, reason):
        pass

    def next_block(self, n):
        out = FaultyStream.next_block(self, n)
        return out if out is not None else (np.zeros(n), np.zeros(n))


def fresh_window(out) -> Window:
    """A clean, attached, reset gate; where the next case's records begin."""
    if out.gate.estopped:
        out.gate.wait_safe(5)
        out.reset()
    out.scheduler.attach_to_gate()
    t = time.monotonic() + 5
    while out.scheduler.busy and time.monotonic() < t:
        time.sleep(0.001)
    return Window(out.recording().shape[0], len(out.relay_log()), time.monotonic())


def _estop_later(out, delay_s: float | None) -> threading.Thread | None:
    if delay_s is None:
        return None
    th = threading.Thread(target=lambda: (time.sleep(delay_s), out.estop("case")), daemon=True)
    th.start()
    return th


def _finish(out, th: threading.Thread | None) -> None:
    """Let a case end: its e-stop thread joined, the queue empty, the relays safe."""
    if th is not None:
        th.join()
    t_end = time.monotonic() + 10
    while out.scheduler.busy and time.monotonic() < t_end:
        time.sleep(0.001)
    out.gate.wait_safe(5)


def plan_case(out, route, amp, f, fault, nan_at, step_at, step_v, estop_s) -> None:
    """A ramped sine plan, broken by ``fault`` (a NaN at ``nan_at``, a ``step_v`` step from
    ``step_at``, object dtype), e-stopped ``estop_s`` after it is asked for."""
    fs, n = out.limits.sample_rate_hz, 4800
    x = amp * np.sin(2 * np.pi * f * np.arange(n) / fs) * ramp_envelope(n, 480)
    if fault == "nan":
        x[nan_at % n] = np.nan
    elif fault == "step":
        x[step_at:] += step_v
        x[-1] = 0.0
    elif fault == "object":
        x = x.astype(object)
    th = _estop_later(out, estop_s)
    with contextlib.suppress(SafetyRefusal):
        out.play(OutputPlan(fs, (Segment(x, np.zeros(n), route),), name="case"), timeout_s=10)
    _finish(out, th)


def source_case(out, route, amp, f, fault, at, estop_s, attach) -> None:
    """A live stream (or, with ``attach``, a source attached to the gate directly) that
    misbehaves from sample ``at``; an attached one is always e-stopped in the end."""
    fs = out.limits.sample_rate_hz
    if attach:
        with contextlib.suppress(SafetyRefusal):  # a refused command is an outcome too
            # a patch without a relay (a channel of its own) is always connected
            out.set_relays({c for p in route if (c := out.gate.relay_channels.get(p))})
        out.gate.attach(FaultySource(route, amp, f, fault, at, 9600, fs))
        th = _estop_later(out, estop_s if estop_s is not None else 0.03)
        t_end = time.monotonic() + 5
        while not out.gate.estopped and time.monotonic() < t_end:
            time.sleep(0.001)
    else:
        th = _estop_later(out, estop_s)
        with contextlib.suppress(SafetyRefusal):
            out.stream(FaultyStream(route, amp, f, fault, at, 9600, fs)).wait(10)
    _finish(out, th)


def relay_case(out, cmds: list[tuple[str, frozenset[int]]]) -> None:
    """Relay commands, plays, e-stops, resets and direct gate switches in the given order
    (on PA); refusals are outcomes."""
    fs = out.limits.sample_rate_hz
    x = tone(250, 20.0, 0.05, fs, 0.01)
    plan = OutputPlan(fs, (Segment(x, np.zeros_like(x), ROUTES["PA"]),), name="p")
    for op, chans in cmds:
        try:
            if op == "set":
                out.set_relays(chans, wait=False)
            elif op == "play":
                out.play(plan, wait=False)
            elif op == "estop":
                out.estop("case")
            elif op == "reset":
                out.gate.wait_safe(5)
                out.reset()
            else:
                out.gate.switch_relays(frozenset(chans))
        except SafetyRefusal:
            continue
    _finish(out, None)


def _one_case(out, rng: np.random.Generator) -> tuple[str, frozenset[str]]:
    """A random case of one of the three kinds; its kind and the routing it played on."""
    route = ROUTES[str(rng.choice(sorted(ROUTES)))]
    fault = str(rng.choice(FAULTS))
    amp, f = float(rng.uniform(0.5, 95)), float(rng.uniform(20, 700))
    estop_s = float(rng.uniform(0, 0.02)) if rng.random() < 0.4 else None
    at = int(rng.integers(0, 6000))
    kind = str(rng.choice(["plan", "stream", "attach", "relays"]))
    if kind == "plan":
        step_v = float(rng.uniform(0, 200))
        plan_case(out, route, amp, f, fault, at, int(rng.integers(4800)), step_v, estop_s)
    elif kind in ("stream", "attach"):
        source_case(out, route, amp, f, fault, at, estop_s, kind == "attach")
    else:
        ops = ["set", "play", "estop", "reset", "switch"]
        cmds = [
            (
                str(rng.choice(ops)),
                frozenset(int(c) for c in rng.choice(np.arange(1, 9), int(rng.integers(0, 4)))),
            )
            for _ in range(int(rng.integers(1, 12)))
        ]
        relay_case(out, cmds)
        route = ROUTES["PA"]
    return kind, route


def fuzz_cases(ctx, seconds: float, seed: int = 0) -> dict[str, Any]:
    """Random faulty cases on the fast-forward twin for ``seconds``; each one audited."""
    from console.runtime.outputs import open_outputs

    rng = np.random.default_rng(seed)
    per_kind: dict[str, int] = {}
    problems: list[str] = []
    with open_outputs(ctx.profile, ctx.pm, fast=True) as out:
        t0 = time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            start = fresh_window(out)
            kind, route = _one_case(out, rng)
            per_kind[kind] = per_kind.get(kind, 0) + 1
            found = received_problems(
                out.limits,
                out.recording(),
                out.relay_log(),
                list(out.gate.events),
                start,
                route,
                int(out.gate.latency_samples),
            )
            problems += [f"{kind}: {p}" for p in found]
        elapsed = time.perf_counter() - t0
    n = sum(per_kind.values())
    return {
        "cases": n,
        "seconds": round(elapsed, 2),
        "cases_per_s": round(n / elapsed, 1),
        "per_kind": per_kind,
        "problems": problems[:20],
        "problem_count": len(problems),
    }


def _last_nonzero(rec: np.ndarray) -> int:
    nz = np.flatnonzero(np.any(np.asarray(rec) != 0, axis=1))
    return int(nz[-1]) if nz.size else -1


def estop_in_process(ctx, trials: int, seed: int = 1) -> dict[str, Any]:
    """The console's case: the gate in this process, the paced twin, a long tone playing."""
    from console.runtime.outputs import open_outputs

    rng = np.random.default_rng(seed)
    lat: list[float] = []
    with open_outputs(ctx.profile, ctx.pm, fast=False) as out:
        fs = out.limits.sample_rate_hz
        x = tone(250, 50.0, 2.0, fs, 0.01)
        plan = OutputPlan(fs, (Segment(x, np.zeros_like(x), frozenset({"PA"})),), name="tone")
        for _ in range(trials):
            if out.gate.estopped:
                out.gate.wait_safe(5)
                out.reset()
            time.sleep(0.03)  # the rate limit and the settle time after the last e-stop
            report = out.play(plan, wait=False)
            t_end = time.monotonic() + 5
            while not report.segment_start and time.monotonic() < t_end:
                time.sleep(0.001)
            time.sleep(float(rng.uniform(0.05, 0.2)))
            # the sample at the amplifiers now: handed out, less the device buffer (as
            # for the other rows, from the gate alone)
            at_dac = out.gate.clock - out.gate.latency_samples
            out.estop("bench")
            out.gate.wait_safe(5)
            last = _last_nonzero(out.recording())
            lat.append(max(0, last + 1 - at_dac) / fs)
    return summarize_s(lat)


def _latency_from_log(path: Path) -> float | None:
    data = json.loads(path.read_text())
    fs = int(data["sample_rate_hz"])
    stops = [e for e in data.get("gate_events", []) if e["kind"] == "estop"]
    if not stops:
        return None
    rec = np.load(path.with_suffix(".npz"))["recording_v"]
    at_dac = stops[0]["clock"] - int(data.get("latency_samples", 0))
    return max(0, _last_nonzero(rec) + 1 - at_dac) / fs


def estop_demo_host(ctx, trials: int) -> dict[str, Any]:
    """A demo in its own process (as the Scenes screen starts it), e-stopped by the console."""
    from console.runtime.demo_process import DemoProcess

    lat: list[float] = []
    with tempfile.TemporaryDirectory() as d:
        for i in range(trials):
            log = Path(d) / f"knob{i}.json"
            run = DemoProcess(ctx.profile, "knob", twin_log=log)
            try:
                run.wait_started(lambda f, text: None)
                t_end = time.monotonic() + 30
                while time.monotonic() < t_end:
                    s = run.snapshot()
                    if (s.get("knob") or {}).get("crossings", 0) >= 2:
                        break
                    time.sleep(0.05)
                run.estop("bench")
                run.proc.wait(20)
            finally:
                run.stop()
            got = _latency_from_log(log) if log.exists() else None
            if got is not None:
                lat.append(got)
    return {**summarize_s(lat), "trials": trials}


def estop_cli_demo(ctx, trials: int) -> dict[str, Any]:
    """``haptable demo knob`` from a shell, stopped by ``haptable estop`` from another one."""
    lat: list[float] = []
    command_s: list[float] = []  # `haptable estop` started -> exited (Python start-up included)
    server_s: list[float] = []  # the demo's own e-stop request -> confirmed silent
    failed: list[str] = []
    profile = str(ctx.profile.path)
    with tempfile.TemporaryDirectory() as d:
        for i in range(trials):
            log = Path(d) / f"cli{i}.json"
            env = {**os.environ, "HAPTABLE_TWIN_LOG": str(log)}
            cmd = [sys.executable, "-m", "console.cli", "--profile", profile]
            demo = subprocess.Popen(
                [*cmd, "demo", "knob", "--seconds", "30"],
                env=env,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE,
                text=True,
            )
            try:
                time.sleep(4.0)  # started and turning
                t0 = time.perf_counter()
                stop = subprocess.run(
                    [*cmd, "estop", "--json"], env=env, capture_output=True, text=True, timeout=30
                )
                command_s.append(time.perf_counter() - t0)
                with contextlib.suppress(ValueError, KeyError):
                    for proc in json.loads(stop.stdout)["processes"]:
                        if proc.get("pid") == demo.pid and proc.get("server_ms") is not None:
                            server_s.append(proc["server_ms"] * 1e-3)
                demo.wait(30)
            finally:
                if demo.poll() is None:
                    demo.kill()
            if stop.returncode != 0:
                failed.append(stop.stdout.strip() + stop.stderr.strip())
            got = _latency_from_log(log) if log.exists() else None
            if got is None:
                failed.append(f"trial {i}: no twin log with an e-stop ({demo.returncode})")
            else:
                lat.append(got)
    return {
        **summarize_s(lat),
        "trials": trials,
        "estop_command_ms": summarize_s(command_s),
        "process_confirm_ms": summarize_s(server_s),
        "failed": failed[:5],
    }


def run(ctx, quick: bool) -> dict[str, Any]:
    result: dict[str, Any] = {"machine": machine_info(), "quick": quick}
    result["cases"] = fuzz_cases(ctx, 5.0 if quick else 30.0)
    result["estop_ms"] = {
        "console_process": estop_in_process(ctx, 10 if quick else 50),
        "demo_host": estop_demo_host(ctx, 2 if quick else 8),
        "cli_demo": estop_cli_demo(ctx, 2 if quick else 8),
    }
    return result
