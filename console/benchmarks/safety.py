"""``haptable bench safety``: what a client can send the kernel, and how fast an e-stop
silences.

- ``cases``: random cases of everything a process can hand its table's kernel, on a
  private fast-forward twin table of the bench's own (it resets its own e-stops there and
  never an operator's): plans with injected faults (NaN, steps, object arrays, wrong
  lengths), live streams with random and broken parameters and posts, relay command
  sequences with e-stops and resets, malformed messages on a raw connection, e-stops at
  random moments. Each case's recording, relay log and gate events are checked by
  ``console.safety.audit``. Cases per second and the problems found (0 expected).
- ``estop``: ``shell_ms``: `haptable estop` from a shell with nothing running, wall time
  (interpreter start-up included); ``demo_silence_ms``: from running `haptable estop`
  to the last non-zero sample at the twin's DAC, a demo playing on the table and (with
  ``console``) the console open on the Camera screen in a terminal; each trial in a fresh
  runtime directory of its own (the e-stop latches; only an operator resets).
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from console.core.bench_stats import machine_info, summarize_s
from console.core.errors import SafetyRefusal
from console.core.types import OutputPlan, Segment
from console.kernel.client import RemoteStream, open_outputs
from console.kernel.line_server import request
from console.kernel.tables import table_key
from console.safety.audit import Window, received_problems
from console.signals.waveforms import ramp_envelope, tone

FAULTS = ("none", "nan", "step", "object", "wrong_len", "inf")
ROUTES = {"PA": frozenset({"PA"}), "PALL": frozenset({"PA", "PB", "PC", "PD"})}
ROOT = Path(__file__).resolve().parents[2]


# ---------------------------------------------------------------------- the cases
def fresh_window(out) -> Window:
    """A clean table (its own e-stop reset, nothing queued); where the next case's
    records begin."""
    if out.estopped:
        out.wait_safe(5)
        out.reset("the safety bench, on its own table")
    t = time.monotonic() + 5
    while out.status()["busy"] and time.monotonic() < t:
        time.sleep(0.001)
    return Window(out.recording().shape[0], len(out.relay_log()), time.monotonic())


def _finish(out) -> None:
    """Let a case end: the queue empty, the relays safe."""
    t_end = time.monotonic() + 10
    while out.status()["busy"] and time.monotonic() < t_end:
        time.sleep(0.001)
    if out.estopped:
        out.wait_safe(5)


def _estop_after(out, delay_s: float | None) -> None:
    if delay_s is not None:
        time.sleep(delay_s)
        out.estop("case")


def plan_case(out, route, amp, f, fault, nan_at, step_at, step_v, estop_s) -> None:
    """A ramped sine plan, broken by ``fault`` (a NaN or inf at ``nan_at``, a ``step_v``
    step from ``step_at``, object dtype, channels of different lengths), e-stopped
    ``estop_s`` after it is asked for."""
    fs, n = out.limits.sample_rate_hz, 4800
    x = amp * np.sin(2 * np.pi * f * np.arange(n) / fs) * ramp_envelope(n, 480)
    screen = np.zeros(n)
    if fault in ("nan", "inf"):
        x[nan_at % n] = np.nan if fault == "nan" else np.inf
    elif fault == "step":
        x[step_at:] += step_v
        x[-1] = 0.0
    elif fault == "object":
        x = x.astype(object)
    elif fault == "wrong_len":
        screen = np.zeros(n - 1)
    with contextlib.suppress(SafetyRefusal):
        report = out.play(OutputPlan(fs, (Segment(x, screen, route),), name="case"), wait=False)
        _estop_after(out, estop_s)
        report.wait(10)
    _finish(out)


def stream_spec(route, rng: np.random.Generator, fs: int) -> dict[str, Any]:
    """A live stream's parameters as a client sends them: a knob-like carrier and pulse,
    sometimes out of the limits or broken (NaN, negative, huge, wrong types)."""
    spec: dict[str, Any] = {
        "sample_rate_hz": fs,
        "patches": sorted(route),
        "screen": True,
        "carrier_max_v": float(rng.uniform(0, 120)),
        "carrier_min_hz": 60.0,
        "carrier_max_hz": 400.0,
        "start_hz": 180.0,
        "glide_ms": float(rng.uniform(0, 30)),
        "ramp_ms": float(rng.uniform(5, 30)),
        "pulse": {
            "shape": "burst",
            "channel": "piezo",
            "peak_v": float(rng.uniform(0, 300)),
            "freq_hz": 250.0,
            "length_ms": 20.0,
            "edge_ms": 0,
        },
    }
    bad = rng.integers(0, 8)
    if bad == 1:
        spec["carrier_max_v"] = float("nan")
    elif bad == 2:
        spec["ramp_ms"] = 0.5  # too short a ramp
    elif bad == 3:
        spec["pulse"]["peak_v"] = 1e6
    elif bad == 4:
        spec["sample_rate_hz"] = 44100
    elif bad == 5:
        spec["patches"] = ["PZ"]
    return spec


def stream_case(out, route, rng: np.random.Generator, estop_s) -> None:
    """A live stream from random parameters, posted to with garbage among good targets,
    then stopped (or e-stopped)."""
    fs = out.limits.sample_rate_hz
    spec = stream_spec(route, rng, fs)
    try:
        h, _ = out._call("stream", spec=spec, name="case")
    except SafetyRefusal:
        return
    report = out._register(int(h["job"]), "case")
    sink = RemoteStream(out, int(h["job"]))
    junk = (float("nan"), float("inf"), -1e300, 1e300, -5.0, 0.0, 123.0)
    t_end = time.monotonic() + float(rng.uniform(0.01, 0.06))
    k = 0
    while time.monotonic() < t_end and not report.done.is_set():
        with contextlib.suppress(SafetyRefusal):
            sink.post(
                [k] if rng.random() < 0.3 else [],
                float(rng.choice(junk)) if rng.random() < 0.3 else float(rng.uniform(60, 400)),
                float(rng.choice(junk)) if rng.random() < 0.3 else float(rng.uniform(0, 120)),
            )
        k += 1
        time.sleep(0.002)
    if estop_s is not None:
        _estop_after(out, estop_s)
    else:
        with contextlib.suppress(SafetyRefusal):
            sink.request_stop()
    report.done.wait(10)
    _finish(out)


def relay_case(out, cmds: list[tuple[str, frozenset[int]]]) -> None:
    """Relay commands, plays, e-stops and resets in the given order (on PA); refusals
    are outcomes."""
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
                out.wait_safe(5)
                out.reset("the safety bench, on its own table")
        except SafetyRefusal:
            continue
    _finish(out)


def _raw_frames(rng: np.random.Generator) -> bytes:
    """A malformed message a broken or hostile client could send the kernel."""
    pick = int(rng.integers(0, 7))
    if pick == 0:
        return struct.pack("!II", 9, 0) + b"{not json"
    if pick == 1:
        return struct.pack("!II", 2**31 - 1, 0)  # a header over the bound
    if pick == 2:
        head = b'{"op":"plan","id":1}'
        return struct.pack("!II", len(head), 2**31 - 1) + head  # a payload over it
    if pick == 3:
        head = json.dumps(
            {
                "op": "plan",
                "id": 1,
                "arrays": [["<f8", [100]], ["<f8", [100]]],
                "fs": 48000,
                "segments": [{"patches": ["PA"], "screen": False, "own": []}],
            }
        ).encode()
        return struct.pack("!II", len(head), 800) + head + b"\x00" * 800  # short payload
    if pick == 4:
        head = b'{"op":"play","id":1,"plan":999999}'
        return struct.pack("!II", len(head), 0) + head
    if pick == 5:
        return bytes(rng.integers(0, 256, int(rng.integers(1, 64)), dtype=np.uint8))
    head = json.dumps({"op": "relays", "id": 1, "closed": ["1", None, 1e9]}).encode()
    return struct.pack("!II", len(head), 0) + head


def wire_case(out, rng: np.random.Generator) -> None:
    """A raw connection sends a malformed message: the kernel drops it (or refuses the
    request) and keeps serving; nothing plays from it."""
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.settimeout(2.0)
    try:
        s.connect(str(out.table.kernel_sock))
        with contextlib.suppress(OSError):
            s.sendall(_raw_frames(rng))
            s.shutdown(socket.SHUT_WR)
            while s.recv(65536):
                pass
    finally:
        s.close()
    _finish(out)


def _one_case(out, rng: np.random.Generator) -> tuple[str, frozenset[str]]:
    """A random case of one kind; its kind and the routing it played on."""
    route = ROUTES[str(rng.choice(sorted(ROUTES)))]
    estop_s = float(rng.uniform(0, 0.02)) if rng.random() < 0.3 else None
    kind = str(rng.choice(["plan", "stream", "relays", "wire"], p=[0.4, 0.25, 0.2, 0.15]))
    if kind == "plan":
        fault = str(rng.choice(FAULTS))
        amp, f = float(rng.uniform(0.5, 95)), float(rng.uniform(20, 700))
        step_v = float(rng.uniform(0, 200))
        at = int(rng.integers(0, 6000))
        plan_case(out, route, amp, f, fault, at, int(rng.integers(4800)), step_v, estop_s)
    elif kind == "stream":
        stream_case(out, route, rng, estop_s)
    elif kind == "relays":
        ops = ["set", "play", "estop", "reset"]
        cmds = [
            (
                str(rng.choice(ops)),
                frozenset(int(c) for c in rng.choice(np.arange(1, 9), int(rng.integers(0, 4)))),
            )
            for _ in range(int(rng.integers(1, 12)))
        ]
        relay_case(out, cmds)
        route = ROUTES["PA"]
    else:
        wire_case(out, rng)
    return kind, route


def fuzz_cases(ctx, seconds: float, seed: int = 0) -> dict[str, Any]:
    """Random faulty cases on a private fast-forward twin for ``seconds``; each audited."""
    rng = np.random.default_rng(seed)
    per_kind: dict[str, int] = {}
    problems: list[str] = []
    with open_outputs(ctx.profile, ctx.pm, fast=True) as out:  # a private table
        latency = int(out.status()["latency_samples"])
        t0 = time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            start = fresh_window(out)
            kind, route = _one_case(out, rng)
            per_kind[kind] = per_kind.get(kind, 0) + 1
            if out.lost:
                problems.append(f"{kind}: the kernel went away ({out.lost})")
                break
            found = received_problems(
                out.limits,
                out.recording(),
                out.relay_log(),
                out.events(),
                start,
                route,
                latency,
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
        "table": "private twin (fast-forward): the bench's own; never an operator's",
    }


# ---------------------------------------------------------------------- e-stop timings
def _sandbox_env(run_dir: Path, **extra: str) -> dict[str, str]:
    """The environment of a trial: a runtime directory of its own (its own tables, its
    own latches), the project on the path."""
    env = {**os.environ, "XDG_RUNTIME_DIR": str(run_dir), "PYTHONPATH": str(ROOT)}
    env.pop("HAPTABLE_TWIN_LOG", None)
    env.update(extra)
    return env


def _haptable() -> list[str]:
    """`haptable` as a user runs it: the installed script, else the entry module."""
    script = Path(sys.executable).with_name("haptable")
    return [str(script)] if script.exists() else [sys.executable, "-m", "console.cli.entry"]


def shell_estop_ms(trials: int) -> dict[str, Any]:
    """`haptable estop` with nothing running: its wall time from a shell."""
    times = []
    with tempfile.TemporaryDirectory() as d:
        run = Path(d) / "run"
        run.mkdir(mode=0o700)
        env = _sandbox_env(run)
        for _ in range(trials):
            t0 = time.perf_counter()
            subprocess.run([*_haptable(), "estop"], env=env, capture_output=True, timeout=30)
            times.append(time.perf_counter() - t0)
    return summarize_s(times)


def _last_nonzero(rec: np.ndarray) -> int:
    nz = np.flatnonzero(np.any(np.asarray(rec) != 0, axis=1))
    return int(nz[-1]) if nz.size else -1


def _from_log(path: Path, t_command: float) -> tuple[float | None, float | None]:
    """(command -> last sample at the DAC, the kernel's own request -> silence), from a
    demo's twin log; the DAC sample at the e-stop is the gate's clock less the device
    latency (errs late by up to one block)."""
    data = json.loads(path.read_text())
    fs = int(data["sample_rate_hz"])
    stops = [e for e in data.get("gate_events", []) if e["kind"] == "estop"]
    if not stops:
        return None, None
    rec = np.load(path.with_suffix(".npz"))["recording_v"]
    at_dac = stops[0]["clock"] - int(data.get("latency_samples", 0))
    ramp_s = max(0, _last_nonzero(rec) + 1 - at_dac) / fs
    t_event = stops[0].get("t_s")
    if t_event is None:
        return None, ramp_s
    return (float(t_event) - t_command) + ramp_s, ramp_s


def _wait(cond, timeout_s: float) -> bool:
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        if cond():
            return True
        time.sleep(0.02)
    return False


def demo_silence_ms(profile_path: str, trials: int, *, console: bool) -> dict[str, Any]:
    """`haptable estop` -> silence at the twin's DAC while `haptable demo knob` plays
    (with ``console``: beside a console on the Camera screen in tmux, where tmux is)."""
    lat, confirm, command, failed = [], [], [], []
    camera_seen = 0  # trials whose console showed the Camera screen's IR view
    use_tmux = console and shutil.which("tmux") is not None
    for i in range(trials):
        with tempfile.TemporaryDirectory() as d:
            run = Path(d) / "run"
            run.mkdir(mode=0o700)
            log = Path(d) / f"demo{i}.json"
            env = _sandbox_env(run, HAPTABLE_TWIN_LOG=str(log))
            tmux_sock = str(Path(d) / "tmux.sock")
            procs = []
            try:
                if use_tmux:
                    subprocess.run(
                        [
                            "tmux",
                            "-S",
                            tmux_sock,
                            "new-session",
                            "-d",
                            "-x",
                            "120",
                            "-y",
                            "40",
                            " ".join([*_haptable(), "--profile", profile_path]),
                        ],
                        env=_sandbox_env(run),
                        check=True,
                        timeout=30,
                    )
                demo = subprocess.Popen(
                    [*_haptable(), "--profile", profile_path, "demo", "knob", "--seconds", "60"],
                    env=env,
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.PIPE,
                    text=True,
                )
                procs.append(demo)
                sock = run / "haptable" / "tables" / table_key(profile_path) / "control.sock"

                def playing(sock=sock) -> bool:
                    with contextlib.suppress(OSError, ValueError):
                        return any(json.loads(request(sock, "status", timeout_s=1)[0])["level_v"])
                    return False

                if not _wait(playing, 120):
                    failed.append(f"trial {i}: the demo did not play")
                    continue
                if use_tmux:
                    subprocess.run(["tmux", "-S", tmux_sock, "send-keys", "F2"], timeout=10)
                    time.sleep(2.0)  # the Camera screen open and drawing
                    pane = subprocess.run(
                        ["tmux", "-S", tmux_sock, "capture-pane", "-p"],
                        capture_output=True,
                        text=True,
                        timeout=10,
                    ).stdout
                    camera_seen += "IR " in pane and "E-STOP" in pane
                time.sleep(0.5)
                t0_wall = time.perf_counter()
                t0 = time.monotonic()
                stop = subprocess.run(
                    [*_haptable(), "estop", "--json"],
                    env=_sandbox_env(run),
                    capture_output=True,
                    text=True,
                    timeout=30,
                )
                command.append(time.perf_counter() - t0_wall)
                with contextlib.suppress(ValueError, KeyError):
                    for t in json.loads(stop.stdout)["tables"]:
                        if t.get("server_ms") is not None:
                            confirm.append(t["server_ms"] * 1e-3)
                demo.wait(60)
                got, _ = _from_log(log, t0) if log.exists() else (None, None)
                if got is None:
                    failed.append(f"trial {i}: no twin log with an e-stop ({demo.returncode})")
                else:
                    lat.append(got)
            finally:
                for p in procs:
                    if p.poll() is None:
                        p.kill()
                if use_tmux:
                    subprocess.run(
                        ["tmux", "-S", tmux_sock, "kill-server"], capture_output=True, timeout=10
                    )
    return {
        **summarize_s(lat),
        "trials": trials,
        "console_on_camera_screen": use_tmux,
        "trials_camera_screen_seen": camera_seen,
        "estop_command_ms": summarize_s(command),
        "kernel_confirm_ms": summarize_s(confirm),
        "failed": failed[:5],
    }


def run(ctx, quick: bool) -> dict[str, Any]:
    result: dict[str, Any] = {"machine": machine_info(), "quick": quick}
    result["cases"] = fuzz_cases(ctx, 5.0 if quick else 30.0)
    prof = str(ctx.profile.path)
    result["estop_ms"] = {
        "shell_nothing_running": shell_estop_ms(5 if quick else 20),
        "demo_to_silence": demo_silence_ms(prof, 2 if quick else 10, console=True),
    }
    result["goals"] = {
        "shell_p50_ms": 150,
        "demo_to_silence_p99_ms": 300,
        "problems": 0,
    }
    return result
