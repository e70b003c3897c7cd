"""The Scenes screen's two tables. Each names what enter does on it in the footer (the
focused widget's keys come first there), so the footer says which table has the focus:
the scenes (enter starts one on the projector) or the demos (enter starts or stops one)."""

from __future__ import annotations

from textual.binding import Binding

from console.plugin_api.tui import LiteralTable


class SceneTable(LiteralTable):
    """The scenes plugins register; enter starts the highlighted one on the projector."""

    BINDINGS = [Binding("enter", "select_cursor", "start scene")]


class DemoTable(LiteralTable):
    """The interactive demos; enter starts the highlighted one, or stops it when it runs."""

    BINDINGS = [Binding("enter", "select_cursor", "start/stop demo")]
