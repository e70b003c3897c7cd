"""The console's side of a demo running in its own process (``console.runtime.demo_host``).

``DemoProcess(profile, name, ...)`` spawns the host; ``wait_started`` follows its
preparation; ``snapshot()`` is the newest status it sent (the demo's latency, watchdog,
state, plus its outputs and what its camera saw), ``status_lines(snapshot)`` what the
operator reads of one (the demo plugin formats it); ``stop``/``estop``/``set_target`` send
commands. The process is a client of the table's outputs kernel, as the console is
(``table_dir``: the console's table; without it, the profile's own).
"""

from __future__ import annotations

import contextlib
import json
import os
import pickle
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from typing import Any

from console.core.errors import UserError
from console.runtime.start_clock import StartClock


class DemoCancelled(Exception):
    """The operator cancelled the demo's preparation."""


class DemoProcess:
    """A demo run in a child process. ``stop()`` is safe to call twice."""

    def __init__(
        self,
        profile: Any,
        name: str,
        *,
        params: dict | None = None,
        on_scene: Callable[[dict], Any] | None = None,
        twin_log: str | os.PathLike | None = None,
        plugins: Any = None,
        table_dir: str | os.PathLike | None = None,
        fast: bool = False,
    ) -> None:
        self.name = name
        self._plugins = plugins  # whose demo registration formats the snapshots
        self.on_scene = on_scene
        self.scene_name: str | None = None
        self.touchable = False
        self.stopped = False
        self.exit_reason: str | None = None  # why it ended (stopped, e-stop, error ...)
        self.estop_reason: str | None = None
        self.final: dict | None = None  # the stopped message
        self.error: str | None = None
        self._stop_reason: str | None = None  # why the console asked it to end
        self._status: dict | None = None
        self._progress: tuple[float, str] | None = None
        self._started = threading.Event()
        self._ended = threading.Event()
        self._lock = threading.Lock()
        # the process's stderr (its traceback if it fails), kept while it lives
        self._log = tempfile.TemporaryFile(mode="w+", prefix="haptable-demo-")  # noqa: SIM115
        self.twin_log = str(twin_log) if twin_log else None
        request = {
            "profile": profile,
            "demo": name,
            "params": params or {},
            "table_dir": str(table_dir) if table_dir else None,
            "fast": bool(fast),
        }
        if self.twin_log:
            request["twin_log"] = self.twin_log
        blob = pickle.dumps(request)
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "console.runtime.demo_host"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self._log,
        )
        self.proc.stdin.write(f"{len(blob)}\n".encode() + blob)
        self.proc.stdin.flush()
        self._reader = threading.Thread(
            target=self._read, name=f"haptable-demo-{name}-link", daemon=True
        )
        self._reader.start()

    # ---------------------------------------------------------------- messages
    def _read(self) -> None:
        for raw in self.proc.stdout:
            try:
                msg = json.loads(raw)
            except ValueError:
                continue
            for kind, value in msg.items():
                self._on(kind, value)
        code = self.proc.wait()
        with self._lock:
            if self.exit_reason is None and self._stop_reason is not None and not self.error:
                self.exit_reason = self._stop_reason  # it ended because it was told to
            if self.exit_reason is None:
                self.exit_reason = self.error or f"the demo process exited (code {code})" + (
                    f": {self.stderr_tail()}" if self.stderr_tail() else ""
                )
            self.stopped = True
        self._started.set()
        self._ended.set()

    def _on(self, kind: str, value: Any) -> None:
        if kind == "status":
            with self._lock:
                self._status = value
            if self.scene_name is not None:
                self._started.set()  # running, and its first status is here
        elif kind == "scene":
            if self.on_scene is not None:
                with contextlib.suppress(Exception):  # the projector never stops haptics
                    self.on_scene(value)
        elif kind == "step":
            self._progress = (0.0, str(value))  # how far: ``StartClock``
        elif kind == "progress":
            done, total = int(value[0]), max(int(value[1]), 1)
            self._progress = (
                0.1 + 0.9 * done / total,
                f"preparing {value[2]} ({done + 1}/{total})",
            )
        elif kind == "started":
            self.scene_name = value.get("scene_name")
            self.touchable = bool(value.get("touchable"))
        elif kind == "error":
            self.error = str(value)
            self.exit_reason = self.error
        elif kind == "stopped":
            with self._lock:
                self.final = value
                if value.get("final"):
                    self._status = value["final"]
                gate = ((value.get("final") or {}).get("outputs") or {}).get("gate") or {}
                self.estop_reason = (
                    value.get("estop") or gate.get("estop_reason") or self.estop_reason
                )
                self.exit_reason = (
                    "e-stopped" if self.estop_reason else value.get("reason", "stopped")
                )

    def stderr_tail(self) -> str:
        """The last line the process wrote to its stderr (its error, if it crashed)."""
        with contextlib.suppress(OSError, ValueError):
            self._log.seek(0)
            lines = [ln.strip() for ln in self._log.read().splitlines() if ln.strip()]
            self._log.seek(0, 2)
            return lines[-1] if lines else ""
        return ""

    def _send(self, msg: dict) -> bool:
        try:
            self.proc.stdin.write((json.dumps(msg) + "\n").encode())
            self.proc.stdin.flush()
            return True
        except (BrokenPipeError, ValueError, OSError):
            return False

    # ---------------------------------------------------------------- control
    def wait_started(
        self,
        progress: Callable[[float, str], None] | None = None,
        cancelled: Callable[[], bool] | None = None,
        timeout_s: float = 600.0,
    ) -> None:
        """Block until the demo runs. ``progress(fraction, text)`` follows its
        preparation; ``cancelled()`` true stops it (``DemoCancelled``); a failure raises
        ``UserError`` with the process's one line."""
        t_end = time.monotonic() + timeout_s
        clock, last = StartClock(self.name), (-1.0, "")
        while not self._started.wait(0.05):
            if cancelled is not None and cancelled():
                self.stop("cancelled")
                raise DemoCancelled(self.name)
            if progress is not None:  # (its process says nothing while it loads)
                floor, step = self._progress or (0.0, "starting its process")
                frac, text = clock.fraction_text(step, floor)
                if text != last[1] or frac - last[0] >= 0.02:  # moves on with the time
                    last = (frac, text)
                    progress(frac, text)
            if time.monotonic() > t_end:
                self.stop("did not start")
                raise UserError(f"demo {self.name}: did not start in {timeout_s:.0f} s")
        if not self.stopped and self.scene_name is not None:
            clock.done()  # the next start's estimate
        if self.stopped or self.scene_name is None:
            self._ended.wait(5.0)
            raise UserError(self.exit_reason or f"demo {self.name}: ended before it started")

    def stop(self, reason: str = "stopped", timeout_s: float = 20.0, now: bool = False) -> None:
        """Stop the demo: the playing plan ends by its ramps (``now``: the kernel ramps
        it down at once, as at quit), the process closes its outputs and exits (killed
        after ``timeout_s``; its outputs' e-stop hook silences them on the signal)."""
        with self._lock:
            if self._stop_reason is None:
                self._stop_reason = reason
        self._send({"cmd": "stop", "now": now})
        if self._progress is None and self.scene_name is None:
            # still starting its interpreter (it hears no command before its imports) or
            # loading plugins: it holds nothing of the table yet, so it ends now
            self.proc.terminate()
        if not self._ended.wait(timeout_s):
            self.proc.terminate()  # SIGTERM: the host leaves the table (its plans ramp down)
            if not self._ended.wait(5.0):
                self.proc.kill()
                self._ended.wait(5.0)
        with self._lock:
            self.stopped = True
            if self.exit_reason is None:
                self.exit_reason = reason
        with contextlib.suppress(OSError):
            self.proc.stdin.close()  # safe when already closed
        with contextlib.suppress(OSError):
            self._log.close()

    def estop(self, reason: str) -> None:
        """Silence the demo's outputs now (the process then stops)."""
        self.estop_reason = self.estop_reason or reason
        if not self._send({"cmd": "estop", "reason": reason}):
            with contextlib.suppress(OSError):
                self.proc.terminate()

    def set_target(self, pos_mm: tuple[float, float] | None) -> None:
        """The operator's finger on the twin (``None`` lifts it)."""
        self._send({"cmd": "target", "pos_mm": None if pos_mm is None else list(pos_mm)})

    # ---------------------------------------------------------------- state
    @property
    def crashed(self) -> bool:
        """It ended without saying so (killed, or died): its outputs were not closed by
        it, so the console takes them back e-stopped."""
        return self._ended.is_set() and self.final is None and self.error is None

    @property
    def running(self) -> bool:
        return self._started.is_set() and not self.stopped

    @property
    def camera(self):
        """Something with ``set_target`` when the operator can touch the twin, else None."""
        return self if self.touchable and not self.stopped else None

    def snapshot(self) -> dict:
        """The newest status (``running`` false once it ended)."""
        with self._lock:
            snap = dict(self._status or {"demo": self.name, "latency": {}, "camera": {}})
            if self.stopped:
                snap["running"] = False
                if self.error:
                    snap["last_error"] = self.error
        return snap

    def status_lines(self, snapshot: dict) -> list[str]:
        """``snapshot`` as the operator reads it: the demo registration's own
        ``status_lines`` (``console.core.contracts.DemoFactory``), here in the console's
        process (the run's last snapshot stays readable after the process ended)."""
        if self._plugins is None:
            # lazy: plugins load on first use
            from console.config.plugins import load_plugins

            self._plugins = load_plugins()
        return list(self._plugins.get("demo", self.name).factory.status_lines(snapshot))

    def wait_ended(self, timeout_s: float) -> bool:
        return self._ended.wait(timeout_s)
