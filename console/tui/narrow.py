"""The console's frame at any width, 80 columns included: every screen's tab shows in the
tab bar (the longest titles shortened when they do not all fit), and the footer shows
whole keys only, in the order the screen gives them (its most important first), with
E-STOP and ``?`` (the help, which lists every key) always among them."""

from __future__ import annotations

from rich.cells import cell_len
from textual.widgets import Footer, TabbedContent, Tabs
from textual.widgets._footer import FooterKey

ELLIPSIS = "…"


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


class ConsoleFooter(Footer):
    """The footer: only keys that show whole, in the order the bindings come (the
    screen's own first, as the screen orders them by importance); the keys in
    ``ALWAYS`` (E-STOP, the help) and the screens' key (``f1-f10 screens``: the app's
    ``screens_key``) are kept whatever the width, on every screen alike; the command
    palette's only where there is room. Compact below ``COMPACT_BELOW`` columns."""

    ALWAYS = ("ctrl+e", "question_mark")
    COMPACT_BELOW = 100

    def _key_width(self, key: FooterKey) -> int:
        kd, desc = cell_len(key.key_display), cell_len(key.description)
        if self.compact:
            width = kd + (1 + desc if desc else 0) + 1  # margin-right 1
        else:
            width = kd + 2 + (desc + 1 if desc else 0)
        if key.has_class("-command-palette"):
            width += 1  # its border
        return width

    def _app_key(self, key: str) -> FooterKey | None:
        """The app's binding of ``key`` as a footer key: Textual leaves a priority key out
        of the footer when the focused field would type it (``?``), though the app takes
        it there (``HapTableApp.on_event``)."""
        for binding in self.app._bindings.key_to_bindings.get(key, ()):
            if binding.show:
                return FooterKey(
                    binding.key,
                    self.app.get_key_display(binding),
                    binding.description,
                    binding.action,
                    tooltip=binding.tooltip,
                ).data_bind(compact=Footer.compact)
        return None

    def _always(self) -> tuple[str, ...]:
        screens = getattr(self.app, "screens_key", "")
        return (*self.ALWAYS, screens) if screens else self.ALWAYS

    def _tabs_key(self) -> list[FooterKey]:
        """The tab bar focused (Tab reaches it on every screen): its keys, which Textual
        leaves out of the footer, name it, first."""
        if not isinstance(self.screen.focused, Tabs):
            return []
        return [FooterKey("right", "←→", "screens", "").data_bind(compact=Footer.compact)]

    def compose(self):
        items = [*self._tabs_key(), *super().compose()]
        width = self.size.width
        keys = [k for k in items if isinstance(k, FooterKey)]
        always = self._always()
        missing = [self._app_key(a) for a in always if a not in {k.key for k in keys}]
        at = next((i for i, k in enumerate(items) if k.has_class("-command-palette")), len(items))
        items[at:at] = [k for k in missing if k is not None]
        keys = [k for k in items if isinstance(k, FooterKey)]
        if width <= 0 or not keys:
            yield from items
            return
        palette = [k for k in keys if k.has_class("-command-palette")]
        rest = [k for k in keys if k not in palette]
        kept = [k for k in rest if k.key in always]
        room = width - sum(map(self._key_width, kept))
        for k in rest:
            if k not in kept and self._key_width(k) <= room:
                kept.append(k)
                room -= self._key_width(k)
        for k in palette:
            if self._key_width(k) <= room:
                kept.append(k)
        yield from (item for item in items if not isinstance(item, FooterKey) or item in kept)

    def on_mount(self) -> None:
        """The screen's keys from the first draw: a screen that focused its widget before
        the footer listened (a panel's ``on_mount``) signals no change until the next
        focus move, and Textual's footer shows nothing until one."""
        self._bindings_ready = True
        self.call_after_refresh(self.recompose)

    def on_resize(self, event) -> None:
        self.compact = event.size.width < self.COMPACT_BELOW
        self.call_after_refresh(self.recompose)
