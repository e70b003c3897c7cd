"""Issue 27, fourth new-user try: one spelling of a patch set (``PA,PC``, as typed) on
Signals and Scope, and a demo's plan named as the demo, not as ``python``."""

from __future__ import annotations

from console.kernel.last_plan import KernelPlan, who_sent
from console.signals.design import parse_target
from console.tui.panes.scope import plan_line


def test_a_patch_set_is_spelt_as_typed():
    assert parse_target("PA,PC").label == "PA,PC"
    assert parse_target("pa + pc").label == "PA,PC"


def test_the_scope_spells_a_patch_set_as_typed():
    plan = KernelPlan(1, "nm2", "this console", True, 1.0, ("PA", "PC"), (0,), (10,), True, "")
    assert "on PA,PC (done)" in plan_line(plan)


def test_a_demos_plan_is_named_as_the_demo():
    command = "python -m console.runtime.demo_host"
    assert who_sent("demo knob", command, 42, False) == "the knob demo (pid 42)"
    assert who_sent("client", command, 42, False) == "a demo (pid 42)"
    assert who_sent("client", "haptable play sweep", 7, False) == "the CLI (pid 7)"
