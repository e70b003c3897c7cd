"""A demo in its own process: the frame loop and nothing else.

The console's interpreter draws the screens; a frame loop beside it shares its GIL and
misses the loop's latency target whenever the console paints. So the console runs a demo
here, as it runs the projector: ``python -m console.runtime.demo_host`` joins the table's
outputs kernel (the console's table: ``table_dir`` in the request), starts the registered
demo (``haptable_register_demos``) and talks over its standard streams, one JSON object a
line. An e-stop of the table (from anywhere) ends the run.

In (stdin, after the pickled start request): ``{"cmd": "stop"}``, ``{"cmd": "estop",
"reason": ...}``, ``{"cmd": "target", "pos_mm": [x, y] | null}`` (the operator's finger
on the twin). End of input (the console is gone) is an e-stop. A stop or e-stop before
the demo runs ends its preparation at once (``console.runtime.prep_cancel``).

Out (the protocol's own descriptor; stray prints go to stderr): ``{"step": what}``,
``{"progress": [done, total, what]}`` (the demo's preparation), ``{"started": {...}}``, ``{"status": snapshot}`` five times a second (the
demo's snapshot plus ``outputs`` (gate, audio, busy) and ``hand`` (what the camera saw)),
``{"scene": event}`` (for the projector), ``{"error": line}``, ``{"stopped": {...}}``.
"""

from __future__ import annotations

import json
import os
import pickle
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from console.core.contracts import TouchableCamera
from console.core.errors import UserError
from console.core.realtime import SUPPORT_PRIORITY, realtime_priority
from console.kernel.client import open_outputs
from console.kernel.tables import table_at
from console.runtime.prep_cancel import Preparation, PreparationCancelled, reap_children
from console.runtime.twin_log import copy_twin_log, write_twin_log

#: status lines per second
STATUS_HZ = 5.0


class HandWatch:
    """Frame sink: what the camera last saw (hands, contacts, gesture, a resting hand)."""

    def __init__(self) -> None:
        self.state: dict[str, Any] = {"hands": 0, "contacts": 0, "gesture": None, "rest_mm": None}

    def __call__(self, frame, work: dict) -> None:
        hands = work.get("hands") or ()
        rest = work.get("rest_mm")
        if rest is None and hands:
            rest = self.state["rest_mm"]  # still resting where it was placed
        g = work.get("gesture")
        self.state = {
            "hands": len(hands),
            "contacts": len(work.get("contacts") or ()),
            "gesture": g.name if g is not None else self.state["gesture"],
            "rest_mm": None if rest is None else (float(rest[0]), float(rest[1])),
        }


def wait_silent(outputs, timeout_s: float = 10.0) -> bool:
    """Wait (bounded) until ``outputs`` play nothing: a demo's stop lets the plan that is
    playing end by its own ramps (at most one plan)."""
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        st = outputs.status()
        if not st.get("busy") and not any(st["gate"]["level_v"]):
            return True
        time.sleep(0.05)
    return False


def _jsonable(o: Any) -> Any:
    if isinstance(o, np.ndarray | np.generic):
        return o.tolist()
    if isinstance(o, (set, frozenset, tuple)):
        return list(o)
    return str(o)


class _Protocol:
    """The out stream: one JSON object a line, from any thread."""

    def __init__(self, stream) -> None:
        self._stream = stream
        self._lock = threading.Lock()

    def send(self, kind: str, value: Any) -> None:
        line = json.dumps({kind: value}, default=_jsonable)
        with self._lock:
            try:
                self._stream.write(line + "\n")
                self._stream.flush()
            except (BrokenPipeError, ValueError, OSError):
                pass  # the console is gone: the end of stdin stops us


class _Cancelled(Exception):
    pass


class Host:
    """One demo run on this process's outputs, driven by the command stream."""

    def __init__(self, request: dict, proto: _Protocol) -> None:
        self.request = request
        self.proto = proto
        self.outputs = None
        self.run = None
        self.hand = HandWatch()  # the frame sink: what the demo's camera saw
        self.stop_asked = threading.Event()
        #: the console quits: the playing plan ramps down now (through the kernel) rather
        #: than playing to its end
        self.stop_now = False
        self.estop_reason: str | None = None
        self.prep = Preparation()  # a stop cancels the preparation at once (``main`` arms it)

    # ---------------------------------------------------------------- commands
    def read_commands(self, stream) -> None:
        realtime_priority(SUPPORT_PRIORITY)  # an e-stop must not wait behind other programs
        for raw in stream:
            try:
                msg = json.loads(raw.decode("utf-8", "replace"))
            except ValueError:
                continue
            self.command(msg)
        self.estop("the console closed the demo's command stream")

    def command(self, msg: dict) -> None:
        cmd = msg.get("cmd")
        if cmd == "stop":
            self.stop_now = self.stop_now or bool(msg.get("now"))
            self.stop_asked.set()
            self.prep.cancel()
        elif cmd == "estop":
            self.estop(str(msg.get("reason") or "e-stop"))
        elif cmd == "target":
            cam = self.run.camera if self.run is not None else None
            if isinstance(cam, TouchableCamera):
                pos = msg.get("pos_mm")
                cam.set_target(None if pos is None else (float(pos[0]), float(pos[1])))

    def _on_table(self, kind: str, message: str) -> None:
        if kind == "estop":  # the table is silent already: the run ends
            if self.estop_reason is None:
                self.estop_reason = message
            self.stop_asked.set()
            self.prep.cancel()

    def estop(self, reason: str) -> None:
        if self.estop_reason is None:
            self.estop_reason = reason
        if self.outputs is not None:
            self.outputs.estop(reason)
        self.stop_asked.set()
        self.prep.cancel()

    # ---------------------------------------------------------------- the run
    def progress(self, done: int, total: int, what: str) -> None:
        if self.stop_asked.is_set():
            raise _Cancelled()
        self.proto.send("progress", [done, total, what])

    def status(self) -> dict:
        snap = self.run.snapshot()
        st = self.outputs.status()
        snap["outputs"] = {k: st[k] for k in ("gate", "audio", "busy")}
        snap["hand"] = self.hand.state
        return snap

    def serve(self) -> int:
        try:
            if not self.prepare():
                return 2
            cam = self.run.camera
            self.proto.send(
                "started",
                {
                    "scene_name": self.run.scene_name,
                    "touchable": isinstance(cam, TouchableCamera),
                    "pid": os.getpid(),
                },
            )
            period = 1.0 / STATUS_HZ
            realtime_priority(SUPPORT_PRIORITY)  # prepared; now see console.core.realtime
            self.proto.send("status", self.status())
            while not self.stop_asked.wait(period):
                self.proto.send("status", self.status())
            return self.finish()
        except (_Cancelled, PreparationCancelled):
            reap_children()  # what it started: the flow planner, an atlas's workers
            self.proto.send("stopped", {"reason": "cancelled", "estop": self.estop_reason})
            return 0
        finally:
            if self.run is not None:
                self.run.stop()
            if self.outputs is not None:
                self.outputs.close()

    def prepare(self) -> bool:
        """The plugins, the table's outputs and the demo's run (``self.run``); False (its
        error sent) when no plugin registers the demo. A stop (or e-stop) while the
        plugins load or the demo prepares ends that at once (``prep_cancel``); joining
        the table is never cut short (an e-stop asked meanwhile reaches it)."""
        # lazy: plugins load on first use
        from console.config.plugins import load_plugins

        req = self.request
        profile, name = req["profile"], req["demo"]
        with self.prep.armed():
            pm = load_plugins()
        reg = pm.of("demo").get(name)
        if reg is None:
            self.proto.send("error", f"demo {name!r}: no plugin registers it in this process")
            return False
        self.proto.send("step", "opening the outputs")
        table = table_at(req["table_dir"]) if req.get("table_dir") else None
        self.outputs = open_outputs(
            profile, pm, fast=bool(req.get("fast")), table=table, role=f"demo {name}"
        )
        self.outputs.add_listener(self._on_table)  # an e-stop of the table ends the run
        if self.estop_reason is not None:
            self.outputs.estop(self.estop_reason)
        if self.stop_asked.is_set():
            raise _Cancelled()
        self.proto.send("step", "opening the camera")
        with self.prep.armed():
            self.run = reg.factory(
                profile,
                pm,
                self.outputs,
                script=True,
                camera_apart=True,
                sinks=[self.hand],
                projector=_SceneOut(self.proto),
                progress=self.progress,
                **req.get("params", {}),
            )
        return True

    def finish(self) -> int:
        """Stop the run, let the playing plan end, write the twin's log, say so."""
        self.run.stop()
        if self.estop_reason is None:
            if self.stop_now:  # the kernel ramps it down, queued plans dropped
                self.outputs.release("the console quits")
            wait_silent(self.outputs)
        final = self.status()  # the stopped run says running: false
        logs = self.write_logs()
        self.proto.send(
            "stopped", {"reason": "stopped", "estop": self.estop_reason, "final": final, **logs}
        )
        return 0

    def write_logs(self) -> dict:
        """The twin's recording and relay log (``console.runtime.twin_log``) where the
        console asked, and beside ``$HAPTABLE_TWIN_LOG`` when that is set."""
        paths = []
        if self.request.get("twin_log"):
            paths.append(Path(self.request["twin_log"]))
        env = os.environ.get("HAPTABLE_TWIN_LOG")
        if env:
            p = Path(env)
            paths.append(p.with_name(f"{p.stem}.demo-{self.request['demo']}{p.suffix or '.json'}"))
        if not paths:
            return {}
        try:  # written once (its bursts are found once), copied to the other place
            got = write_twin_log(paths[0], self.outputs, [])
            if got is None:
                return {}
            for p in paths[1:]:
                copy_twin_log(got, p)
        except (OSError, UserError) as exc:
            print(f"twin log: {exc}", file=sys.stderr)
            return {}
        return {"twin_log": str(got)}


class _SceneOut:
    """The demo's projector: its scene events go to the console, which shows them."""

    def __init__(self, proto: _Protocol) -> None:
        self.proto = proto

    def update(self, event: dict) -> dict:
        self.proto.send("scene", event)
        return {}


def _on_term(signum: int, frame: Any) -> None:
    """SIGTERM (the console gave up waiting for a stop): leave through ``serve``'s own
    way out (the run stopped, the table left), exit 128 + the signal."""
    raise SystemExit(128 + signum)


def main() -> int:
    import signal

    signal.signal(signal.SIGTERM, _on_term)
    proto = _Protocol(os.fdopen(os.dup(1), "w", buffering=1))
    os.dup2(2, 1)  # a stray print must not break the protocol
    sys.stdout = sys.stderr
    raw = sys.stdin.buffer
    request = pickle.loads(raw.read(int(raw.readline())))
    host = Host(request, proto)
    host.prep.install()  # (the main thread's signal: a stop reaches its preparation)
    commands = threading.Thread(
        target=host.read_commands,
        args=(raw,),  # the same buffer: commands may already sit behind the request
        name="haptable-demo-commands",
        daemon=True,
    )
    commands.start()
    try:
        return host.serve()
    except UserError as exc:
        proto.send("error", str(exc))
        return 2
    except Exception as exc:  # one line for the console; the traceback to our stderr
        import traceback

        traceback.print_exc()
        proto.send("error", f"demo {request.get('demo')}: {type(exc).__name__}: {exc}")
        return 1


def _exit_code(exc: BaseException) -> int:
    """The status for a ``SystemExit``/``KeyboardInterrupt`` ending the host (the signal
    hook of ``console.safety`` raises them after e-stopping the gate)."""
    if isinstance(exc, SystemExit):
        return exc.code if isinstance(exc.code, int) else 1
    return 130


if __name__ == "__main__":
    try:
        code = main()
    except (SystemExit, KeyboardInterrupt) as exc:  # SIGTERM/SIGINT: the gate is e-stopped
        code = _exit_code(exc)
    sys.stderr.flush()
    # the command thread sits in a read of stdin: leave without finalising the
    # interpreter (which would abort on that thread's lock), whatever ended main
    os._exit(code)
