"""ctrl+e and ctrl+r typed at once (``tmux send-keys C-e C-r``): the kernel's reset can
be answered and told before its event thread, late on a loaded machine, has handed on the
e-stop's own event. That late event is past: the kernel latches nothing again (the table
stayed latched after the operator's reset, the next command refused) and a client keeps
the reset's state (it read e-stopped again under an idle table: the console's E-STOP
notification outlived the reset). An e-stop after the reset still counts."""

from __future__ import annotations

import os
import threading
import time

from console.kernel.client import open_outputs
from console.kernel.server import Kernel
from console.kernel.tables import private_table, read_latch
from console.safety import GateEvent


def _gate_event(t_s: float, message: str = "operator e-stop (console)") -> dict:
    return {"op": "gate", "kind": "estop", "clock": 0, "t": t_s, "message": message, "cut": True}


def test_a_client_keeps_the_reset_s_state_over_the_estop_s_late_event(profile, plugins):
    with open_outputs(profile, plugins, fast=True) as out:
        told: list[tuple[str, str]] = []
        out.add_listener(lambda kind, msg: told.append((kind, msg)))
        before = time.monotonic()
        out.estop("operator e-stop (console)")
        out.reset()  # the table's owner: a private table's may
        assert not out.estopped
        out._on_gate(_gate_event(before))  # handed on after the reset
        assert not out.estopped and out.estop_reason == ""
        t_end = time.monotonic() + 5  # told on the listeners' thread
        past = ("estop", "operator e-stop (console); reset since")  # not read as a new one
        while past not in told and time.monotonic() < t_end:
            time.sleep(0.01)
        assert past in told, told  # it stopped what played
        with open_outputs(profile, plugins, fast=True) as later:  # opened after the reset
            later._reset_t = out._reset_t  # as the kernel's reset event told it
            later._on_gate(_gate_event(before))
            assert not later.estopped and later.estopped_by is None  # none of its business
        out._on_gate(_gate_event(time.monotonic() + 1e-3, "haptable estop"))  # a new one
        assert out.estopped and out.estop_reason == "haptable estop"


def test_the_kernel_does_not_latch_again_for_an_estop_before_the_reset(profile, plugins):
    table = private_table("late")
    kernel = Kernel(table.ensure(), profile, plugins, fast=True, owner=os.getpid())
    loop = threading.Thread(target=kernel._event_loop, daemon=True)
    loop.start()
    try:
        before = time.monotonic()
        kernel.reset_t = time.monotonic()  # a reset began after that e-stop
        kernel._on_gate_event(GateEvent(before, 0, "estop", "operator e-stop (console)"))
        kernel._on_gate_event(GateEvent(time.monotonic(), 0, "estop", "haptable estop"))
    finally:
        kernel._events.put(None)
        loop.join(5)
    latch = read_latch(table)
    assert latch is not None and latch["reason"] == "haptable estop", latch
    assert "later" not in latch, latch  # the one before the reset not among them


class _Gate:
    """The gate as the kernel's reset and event thread see it: e-stopped, then reset."""

    def __init__(self) -> None:
        self.estopped, self.estop_reason = True, "operator e-stop (console)"

    def reset(self) -> None:
        self.estopped, self.estop_reason = False, ""


def test_a_reset_during_the_event_thread_s_latch_write_leaves_no_latch(
    profile, plugins, monkeypatch
):
    """The event thread checked the e-stop was not yet reset and then wrote the latch
    while the reset ran (ctrl+e ctrl+r in one write, 3 of 5 times): the gate was reset,
    the console played, and every other process found the table latched. The latch and
    the gate's e-stop change together: a reset waits for a latch write under way."""
    import console.kernel.server as server

    table = private_table("race")
    kernel = Kernel(table.ensure(), profile, plugins, fast=True, owner=os.getpid())
    kernel.gate = _Gate()
    writing = threading.Event()
    real_write = server.write_latch

    def slow_write(t, record):  # a loaded machine's event thread, between check and write
        writing.set()
        time.sleep(0.3)
        real_write(t, record)

    monkeypatch.setattr(server, "write_latch", slow_write)
    loop = threading.Thread(target=kernel._event_loop, daemon=True)
    loop.start()
    try:
        kernel._on_gate_event(GateEvent(time.monotonic(), 0, "estop", "operator e-stop (console)"))
        assert writing.wait(5)
        said = kernel.reset(os.getpid(), "the console (ctrl+r)", via_terminal=False)
        assert said.startswith("ok"), said
    finally:
        kernel._events.put(None)
        loop.join(5)
    assert not kernel.gate.estopped
    assert read_latch(table) is None, read_latch(table)  # the table is as the gate says


def test_a_play_cut_by_an_estop_is_known_as_e_stopped_before_the_estop_s_event(profile, plugins):
    """The kernel tells a job's end, cut by an e-stop, with the e-stop's reason: a command
    whose play ended before the e-stop's event came (its thread was late) exited 2
    ('error: ... stopped') instead of 4 ('e-stopped by ...')."""
    with open_outputs(profile, plugins, fast=True) as out:
        rep = out._register(77, "knob HD+VF")
        done = {"op": "job", "job": 77, "what": "done", "error": "stopped: haptable estop (pid 1)"}
        out._apply(rep, {**done, "estop": "haptable estop (pid 1)"})
        assert out.estopped_by == "haptable estop (pid 1)"
        with open_outputs(profile, plugins, fast=True) as other:
            other._apply(other._register(79, "sweep"), {**done, "job": 79, "error": "underrun"})
            assert other.estopped_by is None  # a play that failed otherwise is no e-stop
