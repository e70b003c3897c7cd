"""A plan's description is typed (``console.core.types.PlanInfo``): every key the console
reads from a plan's ``meta`` is declared there, and the built-in effects' plans (a
point, a two-point flow, a flow under a hand) agree with its types."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from console.core.types import PlanInfo, plan_info_problems, plan_parts

ROOT = Path(__file__).resolve().parents[2]


def _is_meta(node: ast.expr, local: bool) -> bool:
    """``x.meta``, or a name ``meta`` where ``local`` (the function took ``x.meta`` into
    it: ``meta = plan.meta``)."""
    return (isinstance(node, ast.Attribute) and node.attr == "meta") or (
        local and isinstance(node, ast.Name) and node.id == "meta"
    )


def _takes_meta(fn: ast.AST) -> bool:
    return any(
        isinstance(n, ast.Assign)
        and any(isinstance(t, ast.Name) and t.id == "meta" for t in n.targets)
        and isinstance(n.value, ast.Attribute)
        and n.value.attr == "meta"
        for n in ast.walk(fn)
    )


def meta_keys_read(root: Path) -> dict[str, list[str]]:
    """The string keys console/ reads from a plan's ``meta`` (``plan.meta["k"]``,
    ``plan.meta.get("k")``, the same on a local ``meta = plan.meta``), with where."""
    found: dict[str, list[str]] = {}
    for path in sorted((root / "console").rglob("*.py")):
        tree = ast.parse(path.read_text())
        scopes = [
            n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)
        ]
        for fn in scopes:
            add_keys(fn, _takes_meta(fn), path.relative_to(root), found)
    return found


def add_keys(fn: ast.AST, local: bool, where: Path, found: dict[str, list[str]]) -> None:
    """Add the meta keys read in ``fn`` (a nested function's reads are found twice: once
    here, once as its own scope; each place is kept once)."""
    for node in ast.walk(fn):
        key = None
        if isinstance(node, ast.Subscript) and _is_meta(node.value, local):
            if isinstance(node.slice, ast.Constant):
                key = node.slice.value
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr == "get"
            and _is_meta(node.func.value, local)
            and node.args
            and isinstance(node.args[0], ast.Constant)
        ):
            key = node.args[0].value
        if isinstance(key, str):
            at = f"{where}:{node.lineno}"
            if at not in found.get(key, []):
                found.setdefault(key, []).append(at)


def test_every_plan_key_the_console_reads_is_declared():
    read = meta_keys_read(ROOT)
    assert {"kind", "frequency_hz", "method"} <= set(read)  # the scan sees the pane's reads
    undeclared = {k: v for k, v in read.items() if k not in PlanInfo.__optional_keys__}
    assert not undeclared, f"declare these in console.core.types.PlanInfo: {undeclared}"


def test_the_checker_names_a_wrong_type():
    assert plan_info_problems({"kind": "point", "frequency_hz": 250, "amplitude_v": 3.0}) == []
    bad = plan_info_problems({"kind": 3, "parts": [{"frequency_hz": "250"}]})
    assert bad == ["kind: int, not str", "parts[0].frequency_hz: str, not float"]
    assert plan_parts({"kind": "point", "actuator": "PA"}) == [{"kind": "point", "actuator": "PA"}]


def _rendered(plugins, kind: str):
    """The built-in effect's plan of ``kind`` on the sim profile's measured map (only the
    one a test asks: the hand flow's search takes seconds)."""
    from console.config.profile import load_profile
    from console.core.contracts import FlowEffect, HandFlowEffect, PointEffect
    from console.runtime.measured_map import measured_map_file

    profile = load_profile("sim", plugins)
    vmap = str(measured_map_file(profile, plugins))
    if kind == "point":
        return plugins.provider("effect", PointEffect, profile).render_point(14, vmap)
    if kind == "flow":
        return plugins.provider("effect", FlowEffect, profile).render_flow(51, 52, vmap)
    return plugins.provider("effect", HandFlowEffect, profile).render_hand_flow(
        (370.0, 220.0), "right", vmap
    )


@pytest.mark.parametrize("kind", ["point", "flow", "hand_flow"])
def test_the_built_in_effects_plans_agree_with_plan_info(plugins, kind):
    meta = _rendered(plugins, kind).meta
    assert meta.get("kind") == kind
    assert plan_info_problems(meta) == []
    for part in plan_parts(meta):
        assert isinstance(part.get("frequency_hz"), float | int)
