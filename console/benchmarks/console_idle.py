"""``haptable bench console-idle``: the console's CPU while it does nothing, per screen.

As an operator runs it: ``haptable`` started in a private tmux server at 120 x 40 on the
profile, the screens opened one after the other with their function keys
(``tmux send-keys``), and on each, after a settling pause, the console's CPU read from
``/proc/<pid>/stat`` once a second for ``seconds`` (10; quick: 4): the console process
and every process it started for itself (the twin camera rendering apart ...), summed;
the median of those one-second readings in % of one core, their mean and max, each
process's share, and the console process's threads (``/proc/<pid>/task``: the UI's main
thread, the camera loop ...).
Goal: <= 3 % on every screen but Camera, <= 20 % on Camera. Then, on Devices, ctrl+e
five times: the delay from the key to the E-STOP on the terminal's safety bar (ctrl+r
resets in between); and headless, in this process, the delay from the e-stop's session
event to the bar drawn with it (goal: 100 ms).

The console gets its own runtime directory (its own table kernel and control socket: a
console already running elsewhere does not change what is measured); the kernel is
another process (in a session of its own: it serves every client of the table and
outlives the console) and is not counted, its CPU is reported beside (``kernel_pct``). Without tmux the console runs headless in this
process (Textual's ``run_test``) and its CPU is this process's, which the report says.
"""

from __future__ import annotations

import asyncio
import os
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from console.session.events import Stopped

#: the goals in % of one core: every screen, and the Camera screen
GOAL_PCT = 3.0
GOAL_CAMERA_PCT = 20.0
#: seconds a screen is left to settle after its key (its first build, a doctor run)
SETTLE_S = 3.0
#: the terminal size an operator's tmux has in the audit
SIZE = (120, 40)
#: the safety bar after ctrl+e (the toast says "E-STOP: outputs silenced")
BAR_ESTOP = "E-STOP: operator e-stop (console)"


def _ticks() -> float:
    return float(os.sysconf("SC_CLK_TCK"))


def cpu_s(pid: int, tid: int | None = None) -> float:
    """User + system CPU seconds of process ``pid`` (or its thread ``tid``)."""
    path = f"/proc/{pid}/stat" if tid is None else f"/proc/{pid}/task/{tid}/stat"
    text = Path(path).read_text()
    fields = text[text.rindex(")") + 2 :].split()  # after "pid (comm) "
    return (int(fields[11]) + int(fields[12])) / _ticks()


def threads(pid: int) -> dict[int, tuple[str, float]]:
    """``{tid: (name, cpu seconds)}`` of the threads of ``pid`` alive now."""
    out = {}
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            name = (task / "comm").read_text().strip()
            out[int(task.name)] = (name, cpu_s(pid, int(task.name)))
        except (OSError, ValueError):
            continue
    return out


def _children(pid: int) -> list[int]:
    out: list[int] = []
    try:
        tasks = list(Path(f"/proc/{pid}/task").iterdir())
    except OSError:
        return out
    for task in tasks:
        try:
            out += [int(c) for c in (task / "children").read_text().split()]
        except (OSError, ValueError):
            continue
    return out


def process_tree(pid: int) -> tuple[list[int], list[int]]:
    """(``pid`` and the processes it started for itself, the ones it started in a
    session of their own: the table's kernel), with their descendants each."""
    mine, apart, todo = [], [], [(pid, True)]
    while todo:
        p, own = todo.pop()
        if p != pid:
            try:
                own = own and os.getsid(p) != p
            except OSError:
                continue
        (mine if own else apart).append(p)
        todo += [(c, own) for c in _children(p)]
    return mine, apart


def _name(pid: int) -> str:
    try:
        argv = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
    except OSError:
        return "?"
    words = [a.decode(errors="replace") for a in argv if a]
    if len(words) > 2 and words[1] in ("-m", "-c"):
        return " ".join(words[1:3])[:60]
    return " ".join(words[:2])[:60]


def _tree_cpu(pids: list[int]) -> dict[int, float]:
    out = {}
    for p in pids:
        try:
            out[p] = cpu_s(p)
        except (OSError, ValueError):
            continue  # ended meanwhile
    return out


def sample(pid: int, seconds: float) -> dict:
    """The CPU of ``pid`` and the processes it started for itself over ``seconds``:
    per-second readings of their sum (% of one core), their median, mean and max, each
    process's share, and the threads of ``pid`` that used the most."""
    t0, before, load0 = time.monotonic(), threads(pid), os.getloadavg()[0]
    own0 = cpu_s(pid)
    mine, apart = process_tree(pid)
    first = _tree_cpu(mine)
    first_apart = _tree_cpu(apart)
    readings, last_t, last = [], t0, dict(first)
    while time.monotonic() - t0 < seconds:
        time.sleep(1.0)
        now_t = time.monotonic()
        now = _tree_cpu(process_tree(pid)[0])
        # a process started meanwhile counts from 0; one that ended loses its last second
        used = sum(c - last.get(p, 0.0) for p, c in now.items())
        readings.append(100.0 * used / (now_t - last_t))
        last_t, last = now_t, {**last, **now}
    span = time.monotonic() - t0
    own = cpu_s(pid) - own0
    per_process = {
        f"{p} {_name(p)}": round(100.0 * (c - first.get(p, 0.0)) / span, 2) for p, c in last.items()
    }
    kernel = _tree_cpu(apart)
    kernel_pct = sum(c - first_apart.get(p, 0.0) for p, c in kernel.items())
    after = threads(pid)
    main_s = after.get(pid, ("", 0.0))[1] - before.get(pid, ("", 0.0))[1]
    others = {
        tid: (name, cpu - before.get(tid, (name, 0.0))[1])
        for tid, (name, cpu) in after.items()
        if tid != pid
    }
    busiest = sorted(others.items(), key=lambda tnc: -tnc[1][1])[:6]
    return {
        "median_pct": round(statistics.median(readings), 2),
        "mean_pct": round(statistics.fmean(readings), 2),
        "max_pct": round(max(readings), 2),
        "readings_pct": [round(r, 1) for r in readings],
        # the console process alone: CPU seconds it used per 10 s (what it did, whatever
        # else ran on the machine) and the machine's 1-minute load average before, after
        "console_cpu_s_per_10s": round(10.0 * own / span, 3),
        "load_avg_1min": [round(load0, 2), round(os.getloadavg()[0], 2)],
        # the console and the processes it started for itself, each (% of one core)
        "processes_pct": per_process,
        # the table's kernel (not counted above: another session, every client's)
        "kernel_pct": round(100.0 * kernel_pct / span, 2),
        # the console process: the UI (Textual's loop) runs on the main thread; the
        # camera loop, the kernel link and the workers on the others (threads that
        # ended meanwhile are missed)
        "main_thread_pct": round(100.0 * main_s / span, 2),
        "other_threads_pct": round(100.0 * sum(c for _n, c in others.values()) / span, 2),
        # the busiest of them by name (% of one core)
        "busiest_threads_pct": {f"{t} {n}": round(100.0 * c / span, 2) for t, (n, c) in busiest},
        "threads": len(after),
    }


# ---------------------------------------------------------------------- tmux
class Tmux:
    """A private tmux server (its own socket, no config) running one command."""

    def __init__(self, command: str, size: tuple[int, int]) -> None:
        self.socket = f"haptable-idle-{os.getpid()}"
        self._run("new-session", "-d", "-s", "idle", "-x", str(size[0]), "-y", str(size[1]),
                  command)  # fmt: skip

    def _run(self, *args: str) -> str:
        cmd = ["tmux", "-L", self.socket, "-f", "/dev/null", *args]
        return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout

    def pid(self) -> int:
        return int(self._run("display-message", "-p", "-t", "idle", "#{pane_pid}").strip())

    def keys(self, *keys: str) -> None:
        self._run("send-keys", "-t", "idle", *keys)

    def screen(self) -> str:
        return self._run("capture-pane", "-p", "-t", "idle")

    def close(self) -> None:
        subprocess.run(["tmux", "-L", self.socket, "kill-server"], capture_output=True, check=False)


def _console_command(profile: str | None, runtime: str) -> str:
    """``haptable [--profile P]`` with this interpreter, this code (``PYTHONPATH``) and a
    private runtime directory."""
    env = {"XDG_RUNTIME_DIR": runtime, "TERM": "tmux-256color"}
    if os.environ.get("PYTHONPATH"):
        env["PYTHONPATH"] = os.environ["PYTHONPATH"]
    argv = [
        sys.executable,
        "-c",
        "import sys; from console.cli.entry import main; sys.exit(main())",
    ]
    if profile:
        argv += ["--profile", profile]
    pairs = " ".join(f"{k}={shlex.quote(v)}" for k, v in env.items())
    return f"exec env {pairs} {shlex.join(argv)}"


def _wait_screen(tmux: Tmux, cond, timeout_s: float, poll_s: float = 0.2) -> str:
    t_end = time.monotonic() + timeout_s
    text = ""
    while time.monotonic() < t_end:
        text = tmux.screen()
        if cond(text):
            return text
        time.sleep(poll_s)
    raise RuntimeError(f"the console did not get there in {timeout_s:g} s; its screen:\n{text}")


def _estop_to_bar(tmux: Tmux, times: int) -> dict:
    """ctrl+e pressed in the console -> the bar on the terminal says E-STOP (read with
    ``capture-pane`` every few ms), ``times`` times; ctrl+r resets in between."""
    delays = []
    for _ in range(times):
        t0 = time.monotonic()
        tmux.keys("C-e")
        _wait_screen(tmux, lambda s: BAR_ESTOP in s, 10, poll_s=0.002)
        delays.append(time.monotonic() - t0)
        time.sleep(0.5)
        tmux.keys("C-r")
        _wait_screen(
            tmux, lambda s: BAR_ESTOP not in s and "| idle |" in s.replace("outputs ", ""), 10
        )
        time.sleep(0.5)
    # lazy: bench_stats brings NumPy; this module loads none
    from console.core.bench_stats import summarize_s

    return summarize_s(delays)


def _in_tmux(profile: str | None, tabs: dict, seconds: float) -> dict:
    runtime = tempfile.mkdtemp(prefix="hi-")  # short: socket paths have a length limit
    os.chmod(runtime, 0o700)
    tmux = Tmux(_console_command(profile, runtime), SIZE)
    out: dict = {}
    try:
        pid = tmux.pid()
        # open: the safety bar shows the outputs' state (idle or e-stopped), not "starting"
        _wait_screen(tmux, lambda s: "E-STOP |" in s or "E-STOP:" in s, 90)
        _wait_screen(tmux, lambda s: "not open" not in s, 60)
        for tab, (title, key, _reg) in tabs.items():
            tmux.keys(key.upper())
            time.sleep(SETTLE_S)
            got = sample(pid, seconds)
            lines = tmux.screen().splitlines()
            bar = [ln for ln in lines if "E-STOP |" in ln or "E-STOP:" in ln]
            got["safety_bar"] = bar[-1].strip() if bar else ""
            out[tab] = {"title": title, "key": key, **got}
        tmux.keys("F1")
        time.sleep(1.0)
        estop = _estop_to_bar(tmux, 5)
        tmux.keys("C-q")
        time.sleep(2.0)
    finally:
        tmux.close()
        shutil.rmtree(runtime, ignore_errors=True)
    return out, estop


# ---------------------------------------------------------------------- headless
async def _headless(ctx, tabs: dict, seconds: float) -> dict:
    """Textual's pilot in this process; CPU from ``time.process_time`` (the process)."""
    # lazy: Textual loads only when the console opens
    from console.tui.app import HapTableApp

    app = HapTableApp(ctx, initial="devices")
    out: dict = {}
    async with app.run_test(size=SIZE) as pilot:
        t_end = time.monotonic() + 60
        while app.session.outputs is None and time.monotonic() < t_end:
            await pilot.pause(0.1)
        for tab, (title, key, _reg) in tabs.items():
            await pilot.press(key)
            await pilot.pause(SETTLE_S)
            readings = []
            for _ in range(max(1, round(seconds))):
                c0, t0 = time.process_time(), time.monotonic()
                await pilot.pause(1.0)
                readings.append(100.0 * (time.process_time() - c0) / (time.monotonic() - t0))
            out[tab] = {
                "title": title,
                "key": key,
                "median_pct": round(statistics.median(readings), 2),
                "mean_pct": round(statistics.fmean(readings), 2),
                "max_pct": round(max(readings), 2),
                "readings_pct": [round(r, 1) for r in readings],
            }
    return out


async def _event_to_bar(ctx, times: int) -> dict:
    """The e-stop's session event -> the safety bar drawn with it, in this process
    (Textual's pilot, the bar read every millisecond), ``times`` times; from another
    thread, as `haptable estop` in a shell or a demo's watchdog."""
    # lazy: Textual and NumPy load only when this bench runs
    import threading

    from console.core.bench_stats import summarize_s
    from console.tui.app import HapTableApp
    from console.tui.safety_bar import SafetyBar

    app = HapTableApp(ctx, fast=True, initial="devices")
    seen: list[float] = []
    app.session.subscribe(
        lambda ev: (
            seen.append(time.monotonic())
            if isinstance(ev, Stopped) and ev.topic == "estop"
            else None
        )
    )
    delays = []
    async with app.run_test(size=SIZE) as pilot:
        t_end = time.monotonic() + 60
        bar = app.query_one("#safety", SafetyBar)
        while "idle" not in str(bar.render()) and time.monotonic() < t_end:
            await pilot.pause(0.05)
        for _ in range(times):
            seen.clear()
            threading.Thread(target=app.session.estop, args=("bench",)).start()
            t_end = time.monotonic() + 10
            while not str(bar.render()).startswith(" E-STOP:") and time.monotonic() < t_end:
                await pilot.pause(0.001)
            t_bar = time.monotonic()
            while not seen and time.monotonic() < t_end:  # the event follows the kernel's
                await pilot.pause(0.001)  # answer: a bar reading the kernel may be earlier
            if seen:
                delays.append(max(0.0, t_bar - seen[0]))
            app.session.reset_estop()
            while "idle" not in str(bar.render()) and time.monotonic() < t_end:
                await pilot.pause(0.05)
    return summarize_s(delays)


def _goal(tab: str) -> float:
    return GOAL_CAMERA_PCT if tab == "camera" else GOAL_PCT


def run(ctx, quick: bool) -> dict:
    """Each screen ``seconds`` (10; quick 4) idle: the console's CPU (its process and
    the processes it started for itself, summed)."""
    # lazy: Textual and NumPy load only when this bench runs
    from console.core.bench_stats import machine_info
    from console.tui.app import panel_tabs

    seconds = 4.0 if quick else 10.0
    tabs = {t: v for t, v in panel_tabs(ctx.pm).items() if v[1]}  # the screens with a key
    load0 = os.getloadavg()
    runtime = tempfile.mkdtemp(prefix="hi-")  # the e-stops below: on a table of our own
    os.chmod(runtime, 0o700)
    old = os.environ.get("XDG_RUNTIME_DIR")
    os.environ["XDG_RUNTIME_DIR"] = runtime
    try:
        event_to_bar = asyncio.run(_event_to_bar(ctx, 3 if quick else 10))
    finally:
        if old is None:
            os.environ.pop("XDG_RUNTIME_DIR", None)
        else:
            os.environ["XDG_RUNTIME_DIR"] = old
        shutil.rmtree(runtime, ignore_errors=True)
    if shutil.which("tmux") and sys.platform.startswith("linux"):
        how = (
            f"haptable in tmux {SIZE[0]}x{SIZE[1]}, /proc/<pid>/stat once a second, summed "
            "over the console's process and the processes it started (not the kernel)"
        )
        screens, estop = _in_tmux(ctx.profile_arg, tabs, seconds)
    else:
        how = "headless (no tmux): Textual run_test in this process, time.process_time"
        screens, estop = asyncio.run(_headless(ctx, tabs, seconds)), None
    return {
        "how": how,
        "seconds_per_screen": seconds,
        "settle_s": SETTLE_S,
        "screens": screens,
        "median_pct": {t: s["median_pct"] for t, s in screens.items()},
        # the console process alone, CPU seconds per 10 s (tmux only)
        "console_cpu_s_per_10s": {
            t: s["console_cpu_s_per_10s"]
            for t, s in screens.items()
            if "console_cpu_s_per_10s" in s
        },
        "goals_pct": {t: _goal(t) for t in screens},
        "meets_goals": all(s["median_pct"] <= _goal(t) for t, s in screens.items()),
        # ctrl+e in the console -> E-STOP on the terminal's safety bar (tmux only)
        "estop_key_to_bar": estop,
        # the e-stop's session event -> the bar drawn with it (headless; goal 100 ms)
        "estop_event_to_bar": event_to_bar,
        "estop_goal_ms": 100,
        "load_avg_start": load0,
        "load_avg_end": os.getloadavg(),
        "machine": machine_info(),
    }
