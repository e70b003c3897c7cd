"""Every process holding outputs registers here, so that `haptable estop` reaches them all.

``register_outputs(outputs)`` is called by ``Outputs`` itself, so the console, a demo
process and every CLI command register through one code path. It serves a socket
``<pid>-<n>.sock`` (0600, ``console.runtime.line_server``) in ``runtime_dir()/outputs``
with ``<pid>-<n>.json`` beside it (pid, command line, profile). Its ``estop`` command
e-stops the gate, waits for the relays to open and answers ``confirmed`` only when the gate
reports silence (0 V / 0 V handed to the driver) with every relay open; then it tells the
registration's ``listeners`` (a CLI command stops, a demo process ends its run).

``estop_everywhere()`` is ``haptable estop``'s side: every registration at once, each with
the same deadline; registrations of dead processes are removed.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import os
import shlex
import signal
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from console.runtime.line_server import LineServer, PeerRefused, request
from console.runtime.private_dir import ensure_private_dir, pid_alive, runtime_dir, write_private

#: how long the server waits for the relays to open after its e-stop
ESTOP_WAIT_S = 1.0
_seq = itertools.count(1)


def registry_dir() -> Path:
    """``runtime_dir()/outputs``, created 0700 and checked like its parent."""
    return ensure_private_dir(runtime_dir() / "outputs")


def command_line() -> str:
    """This process's command as a user would recognise it (``haptable demo knob``)."""
    argv = list(getattr(sys, "orig_argv", sys.argv))
    if "-m" in argv[:-1]:
        i = argv.index("-m")
        mod, rest = argv[i + 1], argv[i + 2 :]
        words = ["haptable", *rest] if mod == "console.cli" else ["python", "-m", mod, *rest]
    else:
        words = [Path(sys.argv[0]).name or "python", *sys.argv[1:]]
    return shlex.join(words)[:200]


class Registration:
    """One ``Outputs`` reachable by `haptable estop`; ``close()`` removes it."""

    def __init__(self, outputs: Any) -> None:
        self.outputs = outputs
        self.listeners: list[Callable[[str], None]] = []
        self.estopped_by: str | None = None  # set before the gate's e-stop starts
        d = registry_dir()
        stem = f"{os.getpid()}-{next(_seq)}"
        self.path = d / f"{stem}.sock"
        self.meta_path = d / f"{stem}.json"
        for stale in (self.path, self.meta_path):  # a dead process's, with our pid
            with contextlib.suppress(FileNotFoundError):
                stale.unlink()
        profile = outputs.profile
        write_private(
            self.meta_path,
            json.dumps(
                {
                    "pid": os.getpid(),
                    "command": command_line(),
                    "profile": str(getattr(profile, "name", profile)),
                    "profile_path": str(getattr(profile, "path", "")),
                    "started": time.time(),
                }
            ),
        )
        try:
            self.server = LineServer(self.path, self._command, name="haptable-outputs-estop")
        except BaseException:
            self.meta_path.unlink()
            raise

    def _command(self, line: str, peer_pid: int) -> str:
        if line == "ping":
            return json.dumps({"pid": os.getpid()})
        if line == "status":
            return json.dumps({"pid": os.getpid(), **self.outputs.gate.status()}, default=list)
        if line == "estop":
            return json.dumps(self.estop(f"haptable estop (pid {peer_pid})"))
        return json.dumps({"error": f"unknown command {line[:40]!r}"})

    def estop(self, reason: str) -> dict:
        """E-stop the gate, wait for open relays, say whether silence is confirmed."""
        gate = self.outputs.gate
        t0 = time.monotonic()
        if self.estopped_by is None:
            self.estopped_by = reason
        gate.estop(reason)
        opened = gate.wait_safe(ESTOP_WAIT_S)
        st = gate.status()
        level = tuple(float(v) for v in st["level_v"])
        problems = []
        if not opened:
            problems.append(f"relays not opened within {ESTOP_WAIT_S:g} s")
        if any(level):
            problems.append(f"outputs still at {' / '.join(f'{v:.2f} V' for v in level)}")
        if st["relays_closed"]:
            problems.append(f"relays {', '.join(map(str, st['relays_closed']))} still closed")
        for fn in list(self.listeners):
            try:
                fn(reason)
            except Exception as exc:  # a listener never stops the answer
                problems.append(f"listener failed: {exc}")
        return {
            "pid": os.getpid(),
            "confirmed": not problems,
            "why": "; ".join(problems) or "silent (0 V / 0 V), relays open",
            "ms": round((time.monotonic() - t0) * 1e3, 2),
        }

    def close(self) -> None:
        """Stop answering and remove the files. Safe to call twice."""
        self.server.close()
        with contextlib.suppress(FileNotFoundError):
            self.meta_path.unlink()


def register_outputs(outputs: Any) -> Registration:
    """Register ``outputs`` (see the module's doc); on failure the outputs are closed."""
    try:
        return Registration(outputs)
    except BaseException:
        outputs.close()
        raise


# ---------------------------------------------------------------------- haptable estop
@dataclass(frozen=True)
class Reached:
    """What one registered process answered to the e-stop."""

    pid: int
    command: str
    profile: str
    confirmed: bool
    why: str
    stale: bool = False  # a dead process's registration, removed
    server_ms: float | None = None  # the process's own e-stop -> confirmation time

    def line(self) -> str:
        who = f"pid {self.pid} ({self.command or '?'}; profile {self.profile or '?'})"
        if self.stale:
            return f"{who}: gone, its stale registration removed"
        return f"{who}: " + ("confirmed " if self.confirmed else "NOT confirmed: ") + self.why


def _reach(sock: Path, timeout_s: float) -> Reached:
    meta_path = sock.with_suffix(".json")
    try:
        meta = json.loads(meta_path.read_text()[:4096])
    except (OSError, ValueError):
        meta = {}
    try:
        pid = int(sock.stem.split("-", 1)[0])
    except ValueError:
        pid = -1
    command, profile = str(meta.get("command", "")), str(meta.get("profile", ""))

    def result(confirmed: bool, why: str, stale: bool = False, ms=None) -> Reached:
        return Reached(pid, command, profile, confirmed, why, stale, ms)

    def remove() -> Reached:
        for p in (sock, meta_path):
            with contextlib.suppress(FileNotFoundError):
                p.unlink()
        return result(True, "", stale=True)

    if pid > 0 and not pid_alive(pid):
        return remove()
    try:
        reply, server_pid = request(sock, "estop", timeout_s=timeout_s)
    except (ConnectionRefusedError, FileNotFoundError):  # nobody listens: a dead one's
        return remove()
    except PeerRefused as exc:
        return result(False, f"refused: {exc}")
    except TimeoutError as exc:
        return result(False, str(exc))
    except OSError as exc:
        return result(False, f"{type(exc).__name__}: {exc.strerror or exc}")
    if server_pid and pid > 0 and server_pid != pid:
        return result(False, f"refused: the socket is served by pid {server_pid}, not {pid}")
    try:
        data = json.loads(reply)
        ms = data.get("ms")
        ms = float(ms) if isinstance(ms, (int, float)) else None
        return result(data["confirmed"] is True, str(data["why"]), ms=ms)
    except (ValueError, KeyError, TypeError):
        return result(False, f"unexpected answer {reply[:80]!r}")


def estop_everywhere(timeout_s: float = 2.0) -> list[Reached]:
    """E-stop every registered process at once; one ``Reached`` each (sorted by pid).
    Raises ``UserError`` when the runtime directory is refused."""
    socks = sorted(registry_dir().glob("*.sock"))
    results: dict[Path, Reached] = {}

    def one(sock: Path) -> None:
        results[sock] = _reach(sock, timeout_s)

    threads = [threading.Thread(target=one, args=(s,), daemon=True) for s in socks]
    for th in threads:
        th.start()
    t_end = time.monotonic() + timeout_s + 0.5
    for th in threads:
        th.join(max(0.0, t_end - time.monotonic()))
    out = []
    for s in socks:
        r = results.get(s)
        if r is None:  # its thread is stuck past every deadline
            pid = int(s.stem.split("-", 1)[0]) if s.stem.split("-", 1)[0].isdigit() else -1
            r = Reached(pid, "", "", False, f"no answer within {timeout_s:g} s")
        out.append(r)
    return sorted(out, key=lambda r: r.pid)


def estop_or_refusal(timeout_s: float) -> tuple[list[Reached], str]:
    """``estop_everywhere``, or no results and the one-line reason the runtime directory
    was refused (the caller still opens what it can)."""
    from console.errors import UserError

    try:
        return estop_everywhere(timeout_s), ""
    except UserError as exc:
        return [], str(exc)


# ---------------------------------------------------------------------- a CLI command
class RemoteStop:
    """Ends a CLI command whose outputs another process e-stopped: ``KeyboardInterrupt``
    in the main thread (its sleeps and waits wake up), ``reason`` says why."""

    def __init__(self, registration: Registration) -> None:
        self._registration = registration
        self._woken = False
        self._lock = threading.Lock()
        self._armed = threading.current_thread() is threading.main_thread()
        if self._armed:
            _install_handler()
        registration.listeners.append(self._on_estop)

    @property
    def reason(self) -> str | None:
        """Why another process e-stopped these outputs (None: it did not)."""
        return self._registration.estopped_by

    def _on_estop(self, reason: str) -> None:
        global _pending
        with self._lock:
            if self._woken:
                return
            self._woken = True
            if self._armed:
                _pending = True
                signal.pthread_kill(threading.main_thread().ident, _SIGNAL)

    def disarm(self) -> None:
        global _pending
        with self._lock:
            self._armed = False
            _pending = False


_SIGNAL = signal.SIGUSR1
_pending = False
_handler_installed = False


def _on_signal(signum, frame) -> None:
    global _pending
    if _pending:
        _pending = False
        raise KeyboardInterrupt


def _install_handler() -> None:
    global _handler_installed
    if not _handler_installed:
        signal.signal(_SIGNAL, _on_signal)
        _handler_installed = True
