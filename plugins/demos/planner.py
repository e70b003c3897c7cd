"""Flow plans computed in a process of their own.

A plan that was not prepared (a hand resting away from the scene's regions) costs up to
a second or two of search. On a thread of the demo's process that search shares the
interpreter with the frame loop and the audio thread: frames wait and audio blocks come
late. ``PlanProcess`` runs the same registered effects (``adapters.flow_effects``: the
flow under a hand, the flow between two points) in a spawned worker process; the demo's plan thread waits for the answer without holding the
interpreter. The plans are the effects' own: the same request gives the same samples.
"""

from __future__ import annotations

import multiprocessing
import threading
from typing import Any

from console.plugin_api import OutputPlan, UserError, load_plugins

from .adapters import flow_effects


def _serve(profile: Any, conn) -> None:
    """The worker: the flow effects by role (``flow_effects``), one request at a time,
    until closed."""
    effects = flow_effects(load_plugins(), profile)
    while True:
        try:
            role, req = conn.recv()
        except (EOFError, OSError):
            return
        try:
            if effects.get(role) is None:
                raise UserError(f"the flow demo needs a {role} flow effect; none is registered")
            conn.send((True, effects[role].render(**req)))
        except Exception as exc:  # the caller raises it
            conn.send((False, exc))


class PlanProcess:
    """``render(role, **request)``: the plan of the effect in ``role`` (``hand`` or
    ``pair``, ``adapters.flow_effects``), computed in the worker
    process (blocking; call it from a thread that may wait). ``close()`` ends it, a plan
    under way included."""

    def __init__(self, profile: Any) -> None:
        ctx = multiprocessing.get_context("spawn")  # never fork a threaded process
        self._conn, child = ctx.Pipe()
        self._proc = ctx.Process(
            target=_serve, args=(profile, child), name="haptable-flow-planner", daemon=True
        )
        self._proc.start()
        child.close()
        self._lock = threading.Lock()

    def render(self, role: str, **req: Any) -> OutputPlan:
        with self._lock:
            try:
                self._conn.send((role, req))
                ok, value = self._conn.recv()
            except (EOFError, OSError):
                raise UserError("flow planner: its process ended (the demo stopped)") from None
        if not ok:
            raise value
        return value

    def close(self) -> None:
        self._proc.terminate()
        self._conn.close()
        self._proc.join(2.0)
