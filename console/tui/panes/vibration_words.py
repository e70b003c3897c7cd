"""The Vibration screen's words for what it shows: its help and command names, a typed
point id, a lookup-table entry, how a flow was rendered, a plan described in a line and
the info panel of the selected points."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from console.core.errors import UserError
from console.tui.roving_view import ADD_ACCELEROMETER
from console.tui.text import escape
from console.tui.time_left import JobLeft

#: the ``:`` line's commands, one name each: its hint and the help show this line
COMMANDS = "51; 51 52; hand 51 up; measure; tables; cancel; import PA=F.uff; load F.npz"
HELP = (
    "enter: audition a point\n"
    "f / r: flow between the last two points, either way (listed here once chosen)\n"
    "w a s d: flow under a hand at the cursor (· marks where a hand fits)\n"
    "m: measure   b: build tables   x: cancel   : command line\n"
    f"{COMMANDS}"
)
#: the ``?`` help: every key of the screen, the side panel named as such
HELP_KEYS = (
    "arrows: move the cursor on the grid   enter: audition the point under it\n"
    "f / r: flow between the last two points, either way (the side panel names them)\n"
    "w a s d: flow under a hand at the cursor (· marks where a hand fits)\n"
    "m: measure (with an accelerometer input: the roving sensor, point by point; m again "
    "when the sensor is placed; x or escape stops, m resumes)\n"
    f"{ADD_ACCELEROMETER}\n"
    "b: build the lookup tables   x: cancel what runs\n"
    "page down / page up: scroll to the FRF plot's axes and legend and back (the grid "
    "keeps the cursor)\n"
    ": opens the command line; on it ctrl+u clears it, escape gives the keys back to "
    "the grid\n"
    f"commands: {COMMANDS}"
)
#: ``m`` with a kept map asks first; ``m`` again within this many seconds measures anew
MEASURE_AGAIN_S = 5.0
NOTHING_TO_CANCEL = "x: nothing to cancel (no measurement, import, load or table build runs)"
MEASURE_ESTOPPED = "measurement stopped by the e-stop; map unchanged; ctrl+r resets, m measures"
KEY_DIRECTIONS = {"w": "up", "a": "left", "s": "down", "d": "right"}
#: a play or a table asked before any map is loaded
NO_MAP = "no vibration map yet: press m to measure, or import one"
#: the line in place of a refused ``m``, load or import once the run on the map ended
MAP_FREE = "the run that played on this map has ended: m measures the grid anew"
#: a play asked while this screen measures the map (its sweeps are what it measures)
MEASURING_REFUSAL = "refused: the map is being measured (x stops the measurement)"


def measure_again(takes: str, again: str = "m") -> str:
    """What ``m`` (or the typed ``measure``: ``again`` "Enter") with a kept map asks:
    ``again`` measures anew, for ``takes`` ("about 10 s"; "" when unknown), and replaces
    the kept map."""
    how_long = f" ({takes})" if takes else ""
    return (
        f"{again} again within {MEASURE_AGAIN_S:.0f} s measures the grid anew{how_long} and "
        "replaces the kept map (the demos and studies use it too)"
    )


def with_time_left(
    progress: Callable[[float, str], Any], expected_s: float | None = None
) -> Callable[[float, str], Any]:
    """``progress(fraction, text)`` that says the time left after ``text`` ("step 4/8;
    about 6 s left") by the console's one rule (``console.tui.time_left.JobLeft``: the
    pace since its first call, ``expected_s`` until that pace tells, counting down and
    never jumping up as the pace slows)."""
    job = JobLeft(expected_s)

    def said(frac: float, msg: str) -> Any:
        left = job.words(frac)
        return progress(frac, f"{msg}; {left}" if left else msg)

    return said


@dataclass
class Ask:
    """A play asked for: ``what`` it plays, the typed ``command`` that asked (or None),
    its ``plan`` once made, whether the outputs said it ``started`` and whether its
    e-stop was ``estopped`` said already (the line says it once)."""

    what: str
    command: str | None = None
    plan: Any = None
    started: bool = False
    estopped: bool = False


def estop_reason(stopped: str) -> str:
    """The reason in a play's ``"the e-stop (reason)"`` outcome, its own parentheses
    kept (``"operator e-stop (console)"``); "" when none is given."""
    why = stopped.removeprefix("the e-stop").strip()
    return why[1:-1].strip() if why.startswith("(") and why.endswith(")") else why


def estop_line(name: str, reason: str) -> str:
    """The status line of a play the e-stop stopped: why, and what to do."""
    why = f" ({reason})" if reason else ""
    return f"{name} stopped by the e-stop{why}; ctrl+r resets it, then play again"


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
        f"{e['max_difference_um_per_v']:.4g} µm/V at {e['frequency_hz']:g} Hz with "
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


def segment_words(seg) -> str:
    """A segment and where it plays: "excitation PALL (PA+PB+PC+PD)", "excitation PA" (an
    excitation is its patches, named once), "point paper on PA+PB+PC+PD"."""
    where = "+".join(sorted(seg.patches)) or "screen"
    label = seg.label or "segment"
    if label.startswith("excitation "):
        return label if label.endswith(f" {where}") else f"{label} ({where})"
    return f"{label} on {where}"


def describe_plan(plan) -> str:
    parts = [segment_words(seg) for seg in plan.segments]
    head = f"{plan.duration_s:.1f} s, " + ", ".join(parts)
    return head + (f"; {rendering(plan)}" if plan.meta.get("kind") == "flow" else "")


def info_text(s: Any, sel: list[int]) -> tuple[str, float | None]:
    """The info panel for the selected points ``sel`` (the last one shown) of the
    Vibration session ``s``: the point's plan, the lookup tables and the flow between
    the last two; (Rich text, the frequency to mark on the FRF or None)."""
    n = sel[-1]
    lines = []
    i = s.vmap.point_index(n)
    x, y = s.vmap.points_mm[i]
    try:
        plan = s.point_plan(n)
        mark = plan.meta["frequency_hz"]
        who = plan.meta.get("actuator") or f"{plan.meta.get('method')} patches"
        lines.append(
            f"[b]point {n:d}[/b] ({x:.0f}, {y:.0f} mm): plays {mark:g} Hz with "
            f"{escape(who)}, {plan.meta['amplitude_v']:.1f} V "
            f"({plan.meta['um_per_v']:.3g} µm/V)"
        )
    except UserError as exc:
        mark = None
        lines.append(f"point {n:d}: {escape(exc)}")
    if len(sel) > 1:
        a, rule = sel[-2], None
        entries = []
        for act, pas in ((a, n), (n, a)):
            try:
                e = s.lookup(act, pas)
            except UserError as exc:
                entries.append(f"  {escape(exc)}")
                break
            rule = rule or e.get("rule")
            entries.append(f"  {act:d} / {pas:d}: {escape(table_entry(e))}")
        lines.append(
            "[b]lookup tables[/b]"
            + (f", rule {escape(rule)}" if rule else "")
            + " (active / passive: difference, frequency, actuator, contrast)"
        )
        lines.extend(entries)
        lines.append(f"[b]f[/b]: flow {a:d} -> {n:d}   [b]r[/b]: flow {n:d} -> {a:d}")
        try:
            lines.append(f"flow {a:d} -> {n:d}: {escape(rendering(s.flow_plan(a, n)))}")
        except UserError as exc:
            lines.append(f"flow {a:d} -> {n:d}: {escape(exc)}")
    else:
        lines.append("f / r: audition a second point, then f flows to it")
    lines.append(f"· on the grid: a {s.hand_mm:g} mm hand fits there (w a s d)")
    return "\n".join(lines), mark


def point_problem(points: tuple[int, ...], cell_of: dict, session: Any) -> str:
    """Why ``points`` cannot play ('' when they can): a point off the grid names the
    grid's range (map or not), no map says how to get one, a hole in the map says so."""
    off = [n for n in points if n not in cell_of]
    if off:
        ids = cell_of or {0: (0, 0)}
        return f"point {off[0]}: the grid has points {min(ids)}-{max(ids)}"
    if session is None:
        return NO_MAP
    hole = [n for n in points if not session.has(n)]
    if hole:
        return f"point {hole[0]}: not measured in this map (its id is dimmed)"
    return ""
