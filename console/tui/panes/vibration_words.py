"""The Vibration screen's words for what it shows: a typed point id, a lookup-table entry,
how a flow was rendered and a plan described in a line."""

from __future__ import annotations

from console.core.errors import UserError


def point_word(word: str) -> int:
    """A point id typed on the command line, or one line saying what to type."""
    try:
        return int(word)
    except ValueError:
        raise UserError(f"{word!r}: give a point id (the map's node number), e.g. 51") from None


def table_entry(e: dict) -> str:
    """A lookup-table entry (``TableEffect.query``) in words: what the tables hold for
    the pair, its contrast under the tables' rule where they give it."""
    if e.get("actuator") is None:
        return str(e.get("note", "no entry"))
    c = e.get("contrast_db")
    return (
        f"{e['max_difference_um_per_v']:.4g} um/V at {e['frequency_hz']:g} Hz with "
        f"{e['actuator']}" + ("" if c is None else f", contrast {c:.1f} dB")
    )


def rendering(plan) -> str:
    """How a flow was rendered, from its plan's ``meta`` (``contracts.FlowEffect``): the
    effect's ``method`` (how it renders: ``paper``, the lookup tables' two parts, or a
    drive per patch), the contrast it predicts (of a flow in parts: the weaker part's,
    the number the tables give for that pair) and the tables' ``rule`` (which pair entry
    the tables pick) when it used them. One name each, as the tables name them."""
    meta = plan.meta
    method = meta.get("method")
    if method is None:
        return "method not given by the effect"
    c = meta.get("predicted_contrast_db")
    patches = " (a drive per patch)" if any(s.patch_v for s in plan.segments) else ""
    weaker = " (the weaker part)" if len(meta.get("parts") or ()) > 1 else ""
    tail = "" if c is None else f", predicted contrast {c:.1f} dB{weaker}"
    rule = f", tables rule {meta['rule']}" if meta.get("rule") else ""
    return f"method {method}{patches}{tail}{rule}"


def describe_plan(plan) -> str:
    parts = []
    for seg in plan.segments:
        parts.append(f"{seg.label or 'segment'} on {'+'.join(sorted(seg.patches)) or 'screen'}")
    head = f"{plan.duration_s:.1f} s, " + ", ".join(parts)
    return head + (f"; {rendering(plan)}" if plan.meta.get("kind") == "flow" else "")
