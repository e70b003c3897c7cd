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
        while ("estop", "operator e-stop (console)") not in told and time.monotonic() < t_end:
            time.sleep(0.01)
        assert ("estop", "operator e-stop (console)") in told  # it stopped what played
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
