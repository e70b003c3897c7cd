"""What the operator reads of a demo: its snapshot as status lines (Textual markup).

The console shows these lines and never decodes the snapshot's keys itself
(``console.core.contracts.Demo.status_lines``); the demo process and the console's process
format the same snapshot the same way.
"""

from __future__ import annotations

from typing import Any

from textual.markup import escape as _escape

from console.plugin_api import OFF_LOOP, counted, left_words

#: the scene each demo drives on the projector (``SceneLink`` in flow.py and knob.py)
DEMO_SCENES = {"flow": "flow_hand", "knob": "knob"}


def escape(value: Any) -> str:
    """``value`` for a markup line, its square brackets shown as written (the demo's
    process formats too: ``console.tui.text.escape`` without the console's widgets)."""
    return _escape(str(value))


def unprepared_text(scene: str | None, needs: list[str], why: dict[str, str]) -> str:
    """Why a projected scene's needs are not prepared, and the fix (Textual markup).

    A need with a reason (a provider that could not prepare it: ``tables`` without a
    vibration map) says it. A need nothing in the console prepares is live input the
    scene waits for (the knob's angle, the contacts): started from the Scenes table
    alone the scene shows its picture without it; the demo that drives the scene sends
    it."""
    live = [k for k in needs if not why.get(k)]
    parts = [f"{escape(k)} ({escape(why[k])})" for k in needs if why.get(k)]
    if live:
        names = " and ".join(escape(k) for k in live)
        demos = [d for d, s in DEMO_SCENES.items() if s == scene]
        if demos:
            fix = f"start the {escape(demos[0])} demo (d, then enter on it): it drives this scene"
        else:
            fix = "a demo or a screen that drives this scene sends it; alone it stays still"
        parts.append(f"{names}: live input the scene waits for; nothing sends it yet: {fix}")
    return "not prepared: " + "; ".join(parts)


#: The latency stages shown, as (monitor key, label), in the order a frame passes them.
DEMO_STAGES = (
    ("capture_to_arrival", "capture"),
    ("vision", "vision"),
    ("classify", "classify"),
    ("scene", "scene"),
    ("effect", "effect"),
    ("scheduled", "output"),
    ("end_to_end", "end to end"),
)


#: how the runtime watchdog's e-stop reasons begin (``console.runtime.watchdog``)
WATCHDOG_SAYS = "runtime watchdog: "


def estop_text(reason: str) -> str:
    """An e-stop as the operator reads it: who asked it (the watchdog, else the reason's
    own words) and why."""
    reason = str(reason)
    if reason.startswith(WATCHDOG_SAYS):
        return f"e-stop by the watchdog ({reason.removeprefix(WATCHDOG_SAYS)})"
    return f"e-stop: {reason}"


def _ms(v: Any) -> str:
    if v is None or v != v:
        return "-"
    return f"{v:.1f}" if v < 10 else f"{v:.0f}"


def status_lines(snap: dict[str, Any]) -> list[str]:
    """A demo snapshot (``DemoRun.snapshot()``, with ``hand``: what its camera last saw,
    when the host adds it; ``stopping``: the console stops it) as lines: state, watchdog
    and camera; latency per stage; the hand; the flow's last stimulus (or a newer
    refusal) or the knob's state; an error."""
    name = snap.get("demo", "?")
    wd = snap.get("watchdog") or {}
    gate = (snap.get("outputs") or {}).get("gate") or {}
    why = snap.get("estop") or gate.get("estop_reason") or ""
    if wd.get("tripped"):
        why = WATCHDOG_SAYS + (wd.get("reason") or "loop stalled").removeprefix(WATCHDOG_SAYS)
    if why:  # the e-stop, from the first snapshot that knows it, whoever asked it
        dog = f"[red]{escape(estop_text(why))}[/]"
    elif wd and snap.get("running") and not snap.get("stopping"):
        dog = f"watchdog ok ({wd.get('limit_ms', 0):.0f} ms)"
    else:  # stopped, stopping or cancelled: no watchdog watches it any more
        dog = "watchdog off"
    cam = snap.get("camera", {})
    lat = snap.get("latency") or {}
    up = f"{snap.get('uptime_s', 0):.0f} s"
    if snap.get("stopping"):  # the console asked it to stop (its last numbers)
        state = f"[yellow]stopping[/] (ran {escape(up)})"
    else:
        state = ("running " if snap.get("running") else "[yellow]loop stopped[/] ") + up
    # the rates and drops on a line of their own: within 80 columns, never dropped as a
    # middle field of a line too long (``fit_fields``)
    lines = [
        f"[b]{escape(name)}[/b] " + state + "  " + dog,
        f"{_rates(cam, lat)}, dropped {escape(lat.get('dropped_camera', 0))} (camera) + "
        f"{escape(lat.get('dropped_queue', 0))} (queue)",
    ]
    stages = dict(lat.get("stages", {}))
    stages["capture_to_arrival"] = lat.get("capture_to_arrival") or {}
    stages["end_to_end"] = lat.get("end_to_end") or {}
    parts = [
        f"{label} {_ms(stages[key].get('p50_ms'))}/{_ms(stages[key].get('p99_ms'))}"
        for key, label in DEMO_STAGES
        if key in stages
    ]
    lines.append("latency p50/p99 ms: " + "  ".join(parts))
    hand = snap.get("hand")
    if hand is not None:
        lines.append(_hand_line(hand))
    if "flow" in snap:
        lines.append(_flow_text(snap["flow"], stopping=bool(snap.get("stopping"))))
    if "knob" in snap:
        k = snap["knob"]
        lines.append(
            f"knob {escape(k.get('condition'))}: {escape(item_words(k.get('item')))}, angle "
            f"{k.get('angle_deg', 0):.0f} deg, {'touching' if k.get('touching') else 'not touched'}"
            f", {counted(int(k.get('crossings', 0)), 'crossing')}"
        )
    if snap.get("last_error"):
        lines.append(f"[red]{escape(snap['last_error'])}[/]")
    return lines


def item_words(item: Any) -> str:
    """The knob's item under the finger: ``item 3``; ``no item`` for its -1 (between
    items, or no finger on the knob), never the raw index."""
    try:
        n = int(item)
    except (TypeError, ValueError):
        return "no item"
    return f"item {n}" if n >= 0 else "no item"


def _rates(cam: dict[str, Any], lat: dict[str, Any]) -> str:
    """The camera's frame rate (the rate it is set to, else as measured: named which, two
    measured rates of different windows never side by side) and the rate the demo's loop
    reads frames at (its latency monitor's)."""
    camera = cam.get("rate_fps") or cam.get("nominal_fps")
    loop = lat.get("fps")
    if loop is None:  # no monitor numbers: what the camera delivered is the loop's rate
        loop = cam.get("fps", 0)
    if not camera:  # the camera names no rate: the loop's is the one measured
        return f"loop {float(loop):.0f} fps"
    return f"camera set to {float(camera):.0f} fps, loop {float(loop):.0f} fps"


def _hand_line(hand: dict[str, Any]) -> str:
    if not hand.get("hands"):
        return "no hand on the table"
    rest = hand.get("rest_mm")
    seen = (
        f"hand resting at {rest[0]:.0f},{rest[1]:.0f} mm"
        if rest is not None
        else "hand seen (moving)"
    )
    seen += ", " + counted(int(hand.get("contacts", 0)), "contact")
    if hand.get("gesture"):
        seen += f", gesture {escape(hand['gesture'])}"
    return seen


def _flow_text(f: dict[str, Any], stopping: bool = False) -> str:
    text = escape(f"flow {f.get('direction')}: {f.get('flows', 0)} played")
    if f.get("flows_late"):  # Latency's own row counts them (``off_loop``), not its frames
        text += f" ({int(f['flows_late'])} {OFF_LOOP}, not in Latency's end to end)"
    last = [e for e in f.get("last", []) if e.get("parts")]
    if last:
        e = last[-1]
        at = e.get("center_mm") or e.get("from_mm")
        where = f" at {at[0]:.0f},{at[1]:.0f} mm" if at else ""
        pts = " + ".join(
            f"{escape(p['actuator'])} {p['frequency_hz']:.0f} Hz" for p in e.get("parts", [])
        )
        text += f"; last{where}: {pts}"
        if e.get("late_s"):  # its plan was computed first (not prepared)
            text += f" (planned in {e['late_s'] * 1e3:.0f} ms)"
    newest = (f.get("last") or [None])[-1]
    if newest is not None and not newest.get("parts"):  # a refusal or no flow there
        text += f"\n[yellow]{escape(newest.get('kind'))}: {escape(newest.get('reason', ''))}[/]"
    prep = f.get("preparing")
    if prep and not stopping:  # (a stop ends the preparation too)
        text += "\n" + escape(preparing_text(prep))
    return text


def preparing_text(prep: dict[str, Any]) -> str:
    """What the flow demo prepares behind itself, how far, and the time left."""
    done, total = int(prep.get("done", 0)), int(prep.get("total", 0)) or 1
    left = prep.get("left_s")
    eta = "estimating the time left" if left is None else left_words(left)
    return (
        f"preparing {prep.get('what', '?')}: {100 * done // total} % ({done}/{total}), "
        f"{eta}; a hand elsewhere gets its flow planned when asked (1-3 s)"
    )
