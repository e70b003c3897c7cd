"""The console's frame at any width, 80 columns included: every screen's tab shows in the
tab bar (the longest titles shortened when they do not all fit), and the footer shows
whole keys only, in the order the screen gives them (its most important first), with
E-STOP and ``?`` (the help, which lists every key) always among them."""

from __future__ import annotations

import re
from typing import Protocol, runtime_checkable

from rich.cells import cell_len
from textual.binding import Binding
from textual.widgets import Footer, TabbedContent, Tabs
from textual.widgets._footer import FooterKey

from console.tui.focus_keys import field_words, own_key, shown_words

ELLIPSIS = "…"


@runtime_checkable
class Switches(Protocol):
    """An app whose screen switch waits for its focus (the console's): ``switching(screen)``
    says whether ``screen`` is the one switching, its new widget not focused yet."""

    def switching(self, screen) -> bool: ...


def fit_titles(titles: list[str], budget: int) -> list[str]:
    """``titles`` with the longest cut first (to a common length, ending in ``…``) until
    their lengths sum to at most ``budget``; unchanged when they fit."""
    titles = list(titles)
    if sum(map(cell_len, titles)) <= budget or not titles:
        return titles
    for cap in range(max(map(len, titles)), 1, -1):
        out = [t if len(t) <= cap else t[: cap - 1] + ELLIPSIS for t in titles]
        if sum(map(cell_len, out)) <= budget:
            return out
    return [t if len(t) <= 2 else t[0] + ELLIPSIS for t in titles]


def fit_tab_bar(tabbed: TabbedContent, titles: dict[str, str], width: int) -> None:
    """Label ``tabbed``'s tabs (pane id -> title) so all of them show in ``width``
    columns: the titles as they are with a space either side where they fit, else one
    space between them and the longest titles shortened."""
    ids = [i for i in titles if tabbed.query(f"#--content-tab-{i}")]
    if not ids or width <= 0:
        return
    full = [titles[i] for i in ids]
    roomy = sum(map(cell_len, full)) + 2 * len(ids) <= width
    labels = full if roomy else fit_titles(full, width - len(ids) - 1)
    for pane_id, label in zip(ids, labels, strict=True):
        tab = tabbed.get_tab(pane_id)
        tab.styles.padding = (0, 1) if roomy else (0, 0, 0, 1)
        if tab.label.plain != label:
            tab.label = label
            tab.tooltip = None if label == titles[pane_id] else titles[pane_id]


class TypesEveryKey:
    """A text field that types every character, ``?`` included: no app key is taken
    from it, the footer promises none while it has the focus."""


def types_every_key(widget: object) -> bool:
    """Whether ``widget`` types every character (a ``TypesEveryKey`` field)."""
    return isinstance(widget, TypesEveryKey)


def typed_key(key: str) -> bool:
    """Whether a text field types ``key`` (``question_mark``), not a control or function
    key (``ctrl+e``, ``f1``)."""
    return not re.match(r"(ctrl|alt|shift|super|meta)\+|f\d+$|escape$|tab$", key)


class ConsoleFooter(Footer):
    """The footer: only keys that show whole, in the order the bindings come (the
    screen's own first, as the screen orders them by importance); the keys in
    ``ALWAYS`` (E-STOP, the help) and the screens' key (``f1-f10 screens``: the app's
    ``screens_key``) are kept whatever the width, on every screen alike (while a named
    field has the focus, E-STOP, then the field's name and words: help and screens go
    first where they do not all fit); the command palette's only where there is room. Compact below ``COMPACT_BELOW`` columns.

    It follows a screen switch at once, however busy the console is (a demo running):
    the keys are worked out as data first and the footer is built again only when they
    changed (a focus move inside a screen, or Textual's signal sent twice, costs nothing),
    one rebuild at a time, each key built with its style (Textual's keys are each styled
    twice after mounting, through a data binding: a dozen style passes per rebuild)."""

    ALWAYS = ("ctrl+e", "question_mark")
    COMPACT_BELOW = 100

    def __init__(self, *args, **kw) -> None:
        super().__init__(*args, **kw)
        self._shown: tuple | None = None  # the keys shown (``_wanted``'s value)
        self._rebuild_queued = False

    @staticmethod
    def _width(key: tuple, compact: bool) -> int:
        _key, display, desc, *_rest, palette = key
        kd, dl = cell_len(display), cell_len(desc)
        width = kd + (1 + dl if dl else 0) + 1 if compact else kd + 2 + (dl + 1 if dl else 0)
        return width + 1 if palette else width  # the palette key's border

    def _key_data(self, binding, enabled: bool = True, tooltip: str = "", palette=False):
        return (
            binding.key,
            self.app.get_key_display(binding),
            binding.description,
            binding.action,
            not enabled,
            tooltip,
            palette,
        )

    def _app_key(self, key: str) -> tuple | None:
        """The app's binding of ``key`` as footer key data: Textual leaves a priority key
        out of the footer when the focused field would type it (``?``), though the app
        takes it there (``HapTableApp.on_event``); None for a key a field that types every
        key types while it has the focus (``types_every_key``: ``?`` is typed, no help
        promised; E-STOP and the F-keys still act there and show)."""
        focused = self.screen.focused
        if focused is not None and types_every_key(focused) and typed_key(key):
            return None
        for binding in self.app._bindings.key_to_bindings.get(key, ()):
            if binding.show:
                return self._key_data(binding, tooltip=binding.tooltip)
        return None

    def _always(self) -> tuple[str, ...]:
        screens = getattr(self.app, "screens_key", "")
        return (*self.ALWAYS, screens) if screens else self.ALWAYS

    def _wanted(self) -> tuple:
        """(compact, the keys to show as data, in order): the focused widget's first (the
        tab bar's, a button's or a check box's, which Textual leaves out, name it:
        ``focus_keys.own_key``), one key per action as Textual's
        footer has them, the ``ALWAYS`` keys it lacks before the palette's, then only
        what fits the width."""
        if not self._bindings_ready or not self.is_attached:
            return (self.compact, ())
        app = self.app
        if self._shown is not None and isinstance(app, Switches) and app.switching(self.screen):
            return self._shown  # the old keys until the new screen's widget has the focus
        active = self.screen.active_bindings
        keys: list[tuple] = []
        focused = self.screen.focused
        own = own_key(focused) if not isinstance(focused, Tabs) else None
        own_display = own and self.app.get_key_display(Binding(own[0], ""))
        # a button or check box names itself; when a key of the screen says the same
        # (Start: s start), that key's entry gains the focused control's (⏎/s start)
        merged = own is not None and any(
            b.show and b.description == own[1] for _n, b, _e, _t in active.values()
        )
        if isinstance(focused, Tabs):
            keys.append(("right", "←→", "screens", "", False, "", False))
        elif own is not None and not merged:
            keys.append((own[0], own_display, own[1], "", False, "", False))
        actions: set[str] = set()
        for _node, binding, enabled, tooltip in active.values():
            if binding.show and binding.action not in actions:
                actions.add(binding.action)
                data = self._key_data(binding, enabled, tooltip)
                if merged and own is not None and binding.description == own[1]:
                    data = (data[0], f"{own_display}/{data[1]}", *data[2:])
                keys.append(data)
        named = field_words(focused)
        field: list[tuple] = []  # a named field's name and words: kept before generic keys
        if named is not None:  # a field: its name first, then what its keys do there
            keys, field = self._named_first(keys, named, shown_words(focused))
        shown = {k[0] for k in keys}
        keys += [k for a in self._always() if a not in shown and (k := self._app_key(a))]
        if self.show_command_palette and self.app.ENABLE_COMMAND_PALETTE:
            found = active.get(self.app.COMMAND_PALETTE_BINDING)
            if found is not None:
                _node, binding, enabled, _tip = found
                tip = binding.tooltip or binding.description
                keys.append(self._key_data(binding, enabled, tip, palette=True))
        width, compact = self.size.width, self.compact
        if width <= 0:
            return (compact, tuple(keys))
        always = self._always()
        rest = [k for k in keys if not k[-1]]
        # the ALWAYS keys whatever the width; with a named field only E-STOP so, then the
        # field's name and words, then the others (help, screens) if they fit, then the
        # screen's own keys in order
        kept = [k for k in rest if k[0] in (always[:1] if field else always)]
        room = width - sum(self._width(k, compact) for k in kept)
        for k in [*field, *(k for k in rest if k[0] in always)]:
            if k not in kept and self._width(k, compact) <= room:
                kept.append(k)
                room -= self._width(k, compact)
        for k in rest:
            if k not in kept and self._width(k, compact) <= room:
                kept.append(k)
                room -= self._width(k, compact)
        for k in keys:
            if k[-1] and self._width(k, compact) <= room:
                kept.append(k)
        return (compact, tuple(k for k in keys if k in kept))

    def _named_first(
        self, keys: list[tuple], named: tuple, own: dict[str, str]
    ) -> tuple[list[tuple], list[tuple]]:
        """(``keys`` with a named field's name first (``participant id:``, clicked: its
        first key), its own shown keys after it, then the words of its other keys, a
        screen's key the field's words say otherwise left out (Gestures' ``esc back``
        goes back to the buttons from a field: ``esc buttons``); the name and words)."""
        name, words = named
        said = {key for key, _word in words}
        keys = [k for k in keys if k[0] not in said or k[0] in own]
        at = max((i + 1 for i, k in enumerate(keys) if k[0] in own), default=0)
        extra = [
            (key, self.app.get_key_display(Binding(key, "")), word, "", False, "", False)
            for key, word in words
            if key not in own
        ]
        first = words[0][0] if words else "tab"
        head = (first, f"{name}:", "", "", False, "", False)
        return [head, *keys[:at], *extra, *keys[at:]], [head, *extra]

    def compose(self):
        compact, keys = self._shown = self._wanted()
        for key, display, desc, action, disabled, tooltip, palette in keys:
            item = FooterKey(
                key,
                display,
                desc,
                action,
                disabled=disabled,
                tooltip=tooltip,
                classes="-command-palette" if palette else "",
            )
            # its style from the start: Textual's palette key stays compact
            small = compact or palette
            item.set_reactive(FooterKey.compact, small)
            item.set_class(small, "-compact", update=False)
            yield item

    def _rebuild(self) -> None:
        """Build the footer again, after the next refresh (the bindings then settled),
        when the keys to show changed; one rebuild queued at a time (it looks at the keys
        as they are when it runs)."""
        if self._rebuild_queued or not self.is_attached:
            return
        self._rebuild_queued = True

        async def rebuild() -> None:
            self._rebuild_queued = False
            if self.is_attached and self._wanted() != self._shown:
                await self.recompose()

        self.call_after_refresh(rebuild)

    def bindings_changed(self, screen) -> None:
        self._bindings_ready = True
        if self.app.app_focus and self.is_attached and screen is self.screen:
            self._rebuild()

    def on_mount(self) -> None:
        """The screen's keys from the first draw: a screen that focused its widget before
        the footer listened (a panel's ``on_mount``) signals no change until the next
        focus move, and Textual's footer shows nothing until one."""
        self._bindings_ready = True
        self.call_after_refresh(self._rebuild)

    def on_resize(self, event) -> None:
        self.compact = event.size.width < self.COMPACT_BELOW
        self.call_after_refresh(self._rebuild)
