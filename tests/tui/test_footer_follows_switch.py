"""The footer follows a screen switch while a demo runs (issue 27: the old screen's keys
stayed for most of a second). Right after an F-key (a pilot pause) the footer shows the
new screen's own keys, and it is built once for the switch, straight from the old
screen's keys to the new one's: never a footer with neither (only E-STOP, help and the
screens: what it showed while the focus moved), never rebuilt for keys it already shows
(each rebuild restyled every key twice: the delay under a demo). 80 x 24 and 120 x 40."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Footer
from textual.widgets._footer import FooterKey

from console.cli.main import Context
from console.tui import narrow
from console.tui.app import HapTableApp

from .test_demos import _start

#: F-key -> a key only that screen's footer shows (its description, whole at 80 columns)
OWN_KEYS = [("f7", "measure"), ("f4", "toggle"), ("f1", "doctor"), ("f6", "projector")]


def _words(keys) -> list[str]:
    return [k.description for k in keys if isinstance(k, FooterKey)]


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_footer_shows_the_new_screens_keys_right_after_a_switch(plugins, size, monkeypatch):
    built: list[list[str]] = []  # every footer as built, in order
    compose = narrow.ConsoleFooter.compose

    def recorded(self):
        items = list(compose(self))
        built.append(_words(items))
        yield from items

    monkeypatch.setattr(narrow.ConsoleFooter, "compose", recorded)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="scenes")
        async with app.run_test(size=size) as pilot:
            await _start(app, pilot, "knob")
            await pilot.pause(0.5)
            for key, own in OWN_KEYS:
                built.clear()
                await pilot.press(key)
                await pilot.pause()
                shown = _words(app.screen.query(Footer).first().query(FooterKey))
                others = [o for _k, o in OWN_KEYS if o != own]
                assert any(own in w for w in shown), (key, shown)
                assert not [w for w in shown if any(o in w for o in others)], (key, shown)
                # one footer for the switch: the new screen's keys (none in between)
                assert len(built) == 1, (key, built)

    asyncio.run(scenario())
