"""The Scenes screen's projector line: what the projector shows and, for a scene whose
needs are not prepared, why, derived from what runs (``DemoControl.scene_feed``)."""

from __future__ import annotations

from console.plugin_api.tui import escape

from .status import unprepared_text


def needs_text(st: dict, feed: dict | None) -> str:
    """Why the shown scene's needs are not prepared (markup), derived from what runs: a
    need with a reason says it; the live input (a need nothing in the console
    prepares: the knob's angle, the contacts) is sent by the running demo when it drives
    this scene and its events reach the projector (``DemoControl.scene_feed``), else it
    says what would send it."""
    scene = st.get("scene")
    needs, why = list(st["unprepared_needs"]), st.get("unprepared_why") or {}
    live = [k for k in needs if not why.get(k)]
    if not live or feed is None or feed.get("scene") != scene:
        return "[yellow]" + unprepared_text(scene, needs, why) + "[/]"
    reasoned = [k for k in needs if why.get(k)]
    head = "[yellow]" + unprepared_text(scene, reasoned, why) + "[/]  " if reasoned else ""
    if feed.get("sent"):  # what the demo does now: running, or stopping (sends until then)
        state = feed.get("state") or "running"
        until = "" if state == "running" else " until it ends"
        return head + escape(
            f"{' and '.join(live)}: sent by the {feed['demo']} demo{until} ({state})"
        )
    text = (
        f"{' and '.join(live)}: live input the scene waits for; the {feed['demo']} demo "
        "runs but sends its scene to no projector (it started before the projector): s "
        "stops it, enter starts it again"
    )
    return head + f"[yellow]{escape(text)}[/]"


def status_text(st: dict | None, feed: dict | None = None) -> str:
    """One paragraph about the projector from ``ProjectorService.status()`` and what
    the running demo sends it (``feed``: ``DemoControl.scene_feed()``)."""
    if st is None:
        return "projector: not started (enter on a scene starts it)"
    holder = f" for {escape(st['holder'])}" if st.get("holder") else ""
    if st.get("starting"):
        return f"projector: starting{holder} (scene {escape(st.get('scene') or '')}) ..."
    conn = "[green]connected[/]" if st.get("connected") else "[yellow]not connected[/]"
    parts = [f"projector: {conn}", f"scene: {escape(st.get('scene') or 'black')}{holder}"]
    for key, label in (("pid", "pid"), ("fps", "fps"), ("restarts", "restarts")):
        if st.get(key) is not None:
            parts.append(f"{label} {escape(st[key])}")
    if st.get("headless"):
        parts.append("headless (no display)")
    if st.get("unprepared_needs"):
        parts.append(needs_text(st, feed))  # markup: its values are escaped
    if st.get("last_error"):
        parts.append(f"[red]{escape(st['last_error'])}[/]")
    elif not st.get("connected") and st.get("last_drop"):
        parts.append(f"[yellow]{escape(st['last_drop'])}[/]")
    return "  ".join(parts)
