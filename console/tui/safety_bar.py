"""The always-visible bar: e-stop key, live output state, closed relays.

The bar is one line at any width: the closed relays and the e-stop / reset key always
show; what does not fit (the e-stop's reason, words around the voltages) is shortened
first, by whole words and fields (never a word cut). Notifications sit above it (``console.tcss``: the toast rack keeps clear of the
bar and the footer). Its text is shown literally (``markup=False``): a reason or a
driver's error naming ``[audio] device`` keeps its brackets.
"""

from __future__ import annotations

from textual.widgets import Static

from console.kernel.shell import reset_command
from console.kernel.tables import latched_others
from console.tui.live import live_of
from console.tui.shorten import balanced


def _fit(variants: list[str], width: int | None) -> str:
    """The first (longest) variant that fits ``width`` columns, else the last one
    shortened by whole words from its end (its least important part: ``_cut_words``)."""
    if not width:
        return variants[0]
    for text in variants:
        if len(text) <= width:
            return text
    return _cut_words(variants[-1], width)


def _cut_words(text: str, width: int) -> str:
    """``text`` within ``width`` columns, whole words dropped from its end (``…`` says
    words went); a field left empty goes with its ``|``. Never a word cut, never a
    bracket left open (``console.tui.shorten``)."""
    words = text.split(" ")
    while len(words) > 1:
        words.pop()
        head = " ".join(words).rstrip()
        if not balanced(head.replace("…", "")):  # never a bracket left half
            continue
        if head.endswith("|"):  # the whole last field went: its separator too
            head = head[:-1].rstrip()
            if len(head) <= width:
                return head
        elif len(head) + 1 <= width:
            return head + "…"
    return ""


def relay_names(profile) -> dict[int, str]:
    """What each relay channel switches, as the profile names it: its patches (``PA``
    .. ``PD``, ``[patches.*] relay_channel``) and the screen (``[screen]
    relay_channel``); a channel nothing names is left out."""
    names: dict[int, list[str]] = {}
    try:
        patches = profile.items("patches")
        screen = profile.get("screen.relay_channel")
    except Exception:  # noqa: BLE001 - a bare profile stub: no names, the numbers show
        return {}
    for name, p in patches.items():
        if p.get("relay_channel"):
            names.setdefault(int(p["relay_channel"]), []).append(str(name))
    if screen:
        names.setdefault(int(screen), []).append("screen")
    return {ch: "+".join(n) for ch, n in sorted(names.items())}


def closed_relays(closed, names: dict[int, str] | None = None) -> str:
    """The closed relays by number, then what they switch by name: ``1,2,5,6 (PA PB
    screen)``; ``none``."""
    if not closed:
        return "none"
    numbers = ",".join(str(c) for c in closed)
    named = [names[int(c)] for c in closed if names and int(c) in names]
    return f"{numbers} ({' '.join(named)})" if named else numbers


def describe(
    status: dict, width: int | None = None, names: dict[int, str] | None = None
) -> tuple[str, str]:
    """(text, css class) for the gate/scheduler status of an ``Outputs``, fitted to
    ``width`` columns (None: the full text); ``names``: what each relay channel
    switches (``relay_names``), shown after the numbers while they fit."""
    text, kind = _describe(status, width, names)
    others = status.get("latched_elsewhere") or []
    if not others:
        return text, kind
    # the other tables a shell's `haptable estop` latched: named, with where they reset
    # (ctrl+r here resets this table only: the kernel takes a reset from its own console)
    named = ",".join(others)
    n = len(others)
    ends = [
        f" | also e-stopped: {named} (reset in its console or `haptable reset`)",
        f" | also e-stopped: {named}",
        f" | +e-stop: {named}",
        f" | {n} other table{'s' if n > 1 else ''} e-stopped",
        f" | +{n} e-stopped",
    ]
    variants = [_describe(status, None, names, k)[0] for k in range(_variants(status))]
    named, counted = ends[:3], ends[3:]
    if status.get("busy") or status["gate"]["estopped"]:
        # playing or e-stopped: the others give way before this table's own words
        fits = [v + e for v in variants for e in ends]
    else:  # idle: the levels (zero) give way first, then what the relays switch
        fits = [v + e for v in variants for e in named] + [v + e for v in variants for e in counted]
    return _fit([*fits, *variants], width), kind  # no room for the others: not a word cut


def still_latched(out) -> str:
    """The other tables still latched (a shell's bare `haptable estop` latches every
    table), said with ctrl+r's outcome: it resets this console's table only, the kernel
    of each taking a reset from its own console or `haptable reset` at a terminal."""
    tables = latched_others(out.table) if out is not None else []
    if not tables:
        return ""
    each = ", ".join(f"{t.name} (`{reset_command(t, None)}`)" for t in tables)
    return f"; still e-stopped: table {each}: ctrl+r in its console, or that command at a terminal"


def latched_here(latch: dict, error: str) -> list[str]:
    """The bar's variants, longest first, for a table e-stopped while this console holds
    no outputs (``live.own_latch``: its reason and where it resets; ``error``: why the
    outputs are not open here). E-STOP first, as on every bar; ctrl+r is not offered."""
    reason, reset, short = latch["reason"], latch["reset"], latch.get("short", latch["reset"])
    why = f" | not open here: {error}" if error else ""
    return [
        f" E-STOP: {reason} | {reset}{why}",
        f" E-STOP: {reason} | {reset}",
        f" E-STOP | {reset} | {reason}",
        f" E-STOP | {short} | {reason}",  # the reason is cut when it must be
    ]


def _variants(status: dict) -> int:
    return 3 if status["gate"]["estopped"] else 6 if status.get("busy") else 7


def _describe(
    status: dict, width: int | None, names: dict[int, str] | None, pick: int | None = None
) -> tuple[str, str]:
    """``describe`` for this table alone; ``pick``: that variant whole (no fitting)."""
    gate = status["gate"]
    numbers = closed_relays(gate["relays_closed"])
    relays = closed_relays(gate["relays_closed"], names)

    def fitted(variants: list[str], width: int | None) -> str:  # or the variant picked
        return variants[min(pick, len(variants) - 1)] if pick is not None else _fit(variants, width)

    if gate["estopped"]:
        reason = gate["estop_reason"]
        return (
            fitted(
                [
                    f" E-STOP: {reason}  [ctrl+r: reset]  relays closed: {relays}",
                    # the key and the relays first: the reason is cut when it must be
                    f" E-STOP: ctrl+r resets | relays closed: {relays} | {reason}",
                    f" E-STOP: ctrl+r resets | relays closed: {numbers} | {reason}",
                ],
                width,
            ),
            "estop",
        )
    # a level that shows as zero is zero: never "-0.0 V" after a ramp down
    levels = [0.0 if abs(float(v)) < 0.05 else float(v) for v in gate["level_v"]]
    names = gate.get("channels") or ["piezo", "screen"]
    pairs = list(zip(names, levels, strict=False))
    if len(levels) == 2:
        (_, piezo), (_, screen) = pairs
        full = f"piezo {piezo:+7.1f} V  screen {screen:+7.1f} V"
    else:  # a channel per patch
        full = "  ".join(f"{n} {v:+6.1f} V" for n, v in pairs)
    mid = " ".join(f"{n} {v:+.1f} V" for n, v in pairs)
    if len(pairs) <= 2:  # each level with its unit ("piezo -10 screen +0 V" read as no unit)
        short = " ".join(f"{n} {v:+.0f} V" for n, v in pairs)
    else:  # a channel per patch: the unit once, so that every channel keeps its name
        short = " ".join(f"{n} {v:+.0f}" for n, v in pairs) + " V"
    state = "PLAYING" if status["busy"] else "idle"
    return (
        fitted(
            [
                f" ctrl+e E-STOP | outputs {state} | {full} | relays closed: {relays}",
                f" ctrl+e E-STOP | {state} | {mid} | relays closed: {relays}",
                f" ^e E-STOP | {state} | {short} | closed: {relays}",
                # idle: the levels (zero) go before what the relays switch
                *([] if status["busy"] else [f" ^e E-STOP | {state} | closed: {relays}"]),
                f" ^e E-STOP | {state} | {short} | closed: {numbers}",
                # the levels last: what does not fit is cut from them
                f" ^e E-STOP | {state} | closed: {numbers} | {short}",
                f" ^e E-STOP | {state} | closed: {numbers}",  # no level rather than half
            ],
            width,
        ),
        "live" if status["busy"] else "idle",
    )


class SafetyBar(Static):
    """One line above the footer of every screen. It registers with the app while
    mounted (``app.safety_bars``), which shows it each output change; it redraws only
    when its text or colour changes."""

    DEFAULT_CSS = """
    SafetyBar { height: 1; background: $panel; color: $text; }
    SafetyBar.live { background: $warning; color: $background; text-style: bold; }
    SafetyBar.estop { background: $error; color: $text; text-style: bold; }
    SafetyBar.nooutputs { background: $error-darken-2; }
    """

    def __init__(self, *args, **kw) -> None:
        kw.setdefault("markup", False)
        super().__init__(*args, **kw)
        self._shown: tuple[dict | None, str] | None = None
        self._drawn: tuple[str, str] | None = None  # (text, css class) on screen now
        self.draws = 0  # how often the bar was redrawn (tests count it)
        self._names: dict[int, str] | None = None  # what each relay switches (profile)

    def on_mount(self) -> None:
        live = live_of(self.app)
        if live is not None:
            live.bars.add(self)
        self.show(None)  # the state as the app last read it, at once

    def on_unmount(self) -> None:
        live = live_of(self.app)
        if live is not None:
            live.bars.discard(self)

    def _width(self) -> int | None:
        return self.size.width or self.app.size.width or None

    def show(self, status: dict | None, error: str = "", latch: dict | None = None) -> None:
        """Draw ``status`` (None: the outputs are not open, ``error`` says why; ``latch``:
        the table's e-stop then, ``live.own_latch``). A bare ``show(None)`` (a screen
        setting its bar up) draws the state the app knows."""
        live = live_of(self.app)
        if status is None and not error and live is not None:
            status = live.now[0]
            error = "" if status is not None else live.error()
            latch = live.latch if status is None else None
        self._shown = (status, error, latch)
        if status is None and latch:
            text, cls = _fit(latched_here(latch, error), self._width()), "estop"
        elif status is None:
            why = error or "starting..."
            variants = [
                f" ctrl+e E-STOP | outputs not open: {why}",
                f" ^e E-STOP | not open: {why}",
            ]
            text, cls = _fit(variants, self._width()), "nooutputs"
        else:
            if self._names is None:
                try:
                    profile = self.app.ctx.profile
                except AttributeError:  # an app without a profile: the numbers show
                    profile = None
                self._names = relay_names(profile)
            text, cls = describe(status, self._width(), self._names)
        if (text, cls) == self._drawn:
            return
        self._drawn = (text, cls)
        self.draws += 1
        self.update(text, layout=False)  # one line, always: no layout to redo
        self.set_classes(cls)

    def on_resize(self) -> None:
        if self._shown is not None:
            self.show(*self._shown)
