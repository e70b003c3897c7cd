"""Start, watch and restart the projector process (``ProjectorSupervisor``).

The projector runs in its own session (so it survives the console), started from the
command its plugin registers (``haptable_register_projectors``: a ``ProjectorLaunch``).
A projector already serving the socket (the console was restarted) is adopted instead of
starting a second one. It is restarted, with a growing back-off, when it exits, when the
link hears nothing from it (hung) and when it never connects.
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import subprocess
import threading
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from console.core.errors import UserError
from console.kernel.private_dir import open_private, pid_alive
from console.runtime.projector.client import ProjectorLink
from console.runtime.projector.protocol import prepare_socket_dir, probe

log = logging.getLogger("haptable.projector")


@dataclass(frozen=True)
class ProjectorLaunch:
    """How to start a projector process: what a registered projector's factory returns.

    ``argv``: the command line (serving the socket it is given); ``env``: variables added
    to the console's environment (none: the console's own)."""

    argv: Sequence[str]
    env: Mapping[str, str] = field(default_factory=dict)

    def environment(self) -> dict[str, str] | None:
        """The projector's whole environment (``None``: inherit the console's)."""
        return {**os.environ, **self.env} if self.env else None


def kill_projector(pid: int, sig: int = signal.SIGKILL) -> None:
    """Signal the projector: its whole process group when it leads one (we started it so)."""
    try:
        if os.getpgid(pid) == pid:
            os.killpg(pid, sig)
        else:
            os.kill(pid, sig)
    except (ProcessLookupError, PermissionError):
        pass


class ProjectorSupervisor:
    """Starts the projector process (own session), restarts it when it dies or hangs.

    If a projector already serves the socket (the console was restarted), it is adopted
    instead of starting a second one.
    """

    def __init__(
        self,
        command: list[str],
        socket_path: Path | str,
        link: ProjectorLink | None = None,
        *,
        backoff_max_s: float = 5.0,
        start_timeout_s: float = 20.0,
        log_path: Path | str | None = None,
        env: dict[str, str] | None = None,
    ) -> None:
        self.command = list(command)
        self.socket_path = Path(socket_path)
        self.link = link
        self.backoff_max_s = backoff_max_s
        self.start_timeout_s = start_timeout_s
        self.log_path = Path(log_path) if log_path else None
        self.env = env
        self.proc: subprocess.Popen | None = None
        self.pid: int | None = None
        self.adopted = False
        self.restarts = 0
        self.last_exit: int | None = None
        self.last_reason = ""
        self.last_error = ""
        self._started_t = 0.0
        self._connects_at_start = 0
        self._next_start_t = 0.0
        self._backoff = 0.25
        self._hung = threading.Event()
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        if link is not None:
            link.on_hung = self.notify_hung

    def start(self) -> None:
        prepare_socket_dir(self.socket_path)
        pid = probe(self.socket_path)
        with self._lock:
            if pid is not None and pid > 0:
                self.pid, self.adopted, self._started_t = pid, True, time.monotonic()
                self._connects_at_start = self.link.handshakes if self.link is not None else 0
                log.info("projector: adopted the running projector (pid %d)", pid)
            else:
                self._spawn()
        self._thread = threading.Thread(
            target=self._watch, name="projector-supervisor", daemon=True
        )
        self._thread.start()

    def notify_hung(self, pid: int | None) -> None:
        """The link heard nothing for too long: kill and restart the projector."""
        self._hung.set()

    def _spawn(self) -> None:
        out = (
            os.fdopen(open_private(self.log_path, append=True), "ab")
            if self.log_path
            else subprocess.DEVNULL
        )
        try:
            self.proc = subprocess.Popen(
                self.command,
                stdin=subprocess.DEVNULL,
                stdout=out,
                stderr=subprocess.STDOUT,
                start_new_session=True,  # own session + process group: survives the console
                close_fds=True,
                env=self.env,
            )
        except OSError as e:
            raise UserError(
                f"projector: cannot start {self.command[0]!r} ({e}); check the projector command"
            ) from None
        finally:
            if out is not subprocess.DEVNULL:
                out.close()
        self.pid, self.adopted = self.proc.pid, False
        self._started_t = time.monotonic()
        self._connects_at_start = self.link.handshakes if self.link is not None else 0
        log.info("projector: started pid %d", self.pid)

    def _log_tail(self) -> str:
        """The last error line the projector wrote to its log (shown in the status)."""
        if self.log_path is None:
            return ""
        try:
            with open(self.log_path, "rb") as f:
                f.seek(0, os.SEEK_END)
                f.seek(max(0, f.tell() - 4096))
                lines = f.read().decode("utf-8", "replace").splitlines()
        except OSError:
            return ""
        errors = [ln for ln in lines if "error" in ln.lower()]
        return (errors or [""])[-1].strip()[:300]

    def _is_alive(self) -> bool:
        if self.proc is not None:
            code = self.proc.poll()
            if code is not None:
                self.last_exit = code
                return False
            return True
        return self.pid is not None and pid_alive(self.pid)

    def _watch(self) -> None:
        while not self._stop.wait(0.05):
            with self._lock:
                now = time.monotonic()
                if self.pid is None:
                    if now >= self._next_start_t:
                        self.restarts += 1
                        self._spawn()
                    continue
                connected = self.link is not None and self.link.connected
                stuck = (
                    self.link is not None
                    and not connected
                    and self.link.handshakes == self._connects_at_start
                    and now - self._started_t > self.start_timeout_s
                )
                reason = ""
                if self._hung.is_set() or stuck:
                    self._hung.clear()
                    reason = "did not connect" if stuck else "hung (no heartbeat)"
                    kill_projector(self.pid)
                    if self.proc is not None:
                        with contextlib.suppress(subprocess.TimeoutExpired):
                            self.proc.wait(timeout=2.0)
                if not self._is_alive():
                    self.last_error = self._log_tail()
                    if not reason:
                        reason = (
                            f"exited ({self.last_exit})" if self.proc is not None else "vanished"
                        )
                    self.last_reason = reason
                    ran = now - self._started_t
                    self._backoff = (
                        0.25 if ran > 10.0 else min(self._backoff * 2, self.backoff_max_s)
                    )
                    self._next_start_t = now + (0.0 if ran > 10.0 else self._backoff)
                    log.warning("projector: pid %s %s; restarting", self.pid, reason)
                    self.pid, self.proc = None, None

    def status(self) -> dict:
        return {
            "pid": self.pid,
            "adopted": self.adopted,
            "restarts": self.restarts,
            "last_exit": self.last_exit,
            "last_reason": self.last_reason,
            "last_error": self.last_error,
            "log": str(self.log_path) if self.log_path else None,
            "uptime_s": time.monotonic() - self._started_t if self.pid else 0.0,
        }

    def detach(self) -> None:
        """Stop watching and leave the projector running (black) for the next console."""
        self._stop.set()

    def stop(self, timeout_s: float = 3.0) -> None:
        """Stop watching and end the projector (quit, then SIGTERM, then SIGKILL)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        with self._lock:
            pid, proc = self.pid, self.proc
            if pid is None:
                return
            if self.link is not None and self.link.connected:
                self.link.send_quit()
            deadline = time.monotonic() + timeout_s
            sent_term = False
            while time.monotonic() < deadline:
                if (proc.poll() is not None) if proc else not pid_alive(pid):
                    break
                if not sent_term and time.monotonic() > deadline - timeout_s / 2:
                    kill_projector(pid, signal.SIGTERM)
                    sent_term = True
                time.sleep(0.02)
            else:
                kill_projector(pid, signal.SIGKILL)
                if proc is not None:
                    proc.wait(timeout=2.0)
            self.pid = self.proc = None
