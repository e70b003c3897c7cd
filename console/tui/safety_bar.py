"""The always-visible bar: e-stop key, live output state, closed relays."""

from __future__ import annotations

from textual.widgets import Static


def describe(status: dict) -> tuple[str, str]:
    """(text, css class) for the gate/scheduler status of an ``Outputs``."""
    gate = status["gate"]
    relays = ",".join(str(c) for c in gate["relays_closed"]) or "none"
    if gate["estopped"]:
        return (
            f" E-STOP: {gate['estop_reason']}  [ctrl+r: reset]  relays closed: {relays}",
            "estop",
        )
    levels = gate["level_v"]
    names = gate.get("channels") or ["piezo", "screen"]
    if len(levels) == 2:
        piezo, screen = levels
        shown = f"piezo {piezo:+7.1f} V  screen {screen:+7.1f} V"
    else:  # a channel per patch
        shown = "  ".join(f"{n} {v:+6.1f} V" for n, v in zip(names, levels, strict=False))
    state = "PLAYING" if status["busy"] else "idle"
    return (
        f" ctrl+e E-STOP | outputs {state} | {shown} | relays closed: {relays}",
        "live" if status["busy"] else "idle",
    )


class SafetyBar(Static):
    """One line above the footer of every screen."""

    DEFAULT_CSS = """
    SafetyBar { height: 1; background: $panel; color: $text; }
    SafetyBar.live { background: $warning; color: $background; text-style: bold; }
    SafetyBar.estop { background: $error; color: $text; text-style: bold; }
    SafetyBar.nooutputs { background: $error-darken-2; }
    """

    def show(self, status: dict | None, error: str = "") -> None:
        if status is None:
            self.update(f" ctrl+e E-STOP | outputs not open: {error or 'starting...'}")
            self.set_classes("nooutputs")
            return
        text, cls = describe(status)
        self.update(text)
        self.set_classes(cls)
