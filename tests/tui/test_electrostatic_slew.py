"""Issue 27, a new operator's try: on Electrostatic `+` to the maximum, `]` to 1000 Hz,
`t` (square), `p` reached a setting the screen's slew limit refuses, and the refusal,
said twice, named the CLI's `vpp or freq_hz`. The keys keep the setting inside the slew
limit for its waveform and frequency (the gate's, from [amplifiers] and [screen]), say
which limit stops them with the console's key that makes room, and `p` then plays."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp
from plugins.electrostatic.effects import slew_max_vpp

from .conftest import wait_for, words_on
from .test_screens import _ready


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_keys_keep_the_setting_inside_the_slew_limit_and_it_plays(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="electrostatic")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            pane = app.pane("electrostatic")
            line = lambda: words_on(app, "#es-status")  # noqa: E731
            profile = app.ctx.profile
            for _ in range(12):
                await pilot.press("plus")
            assert pane.vpp == pane.max_vpp  # 180 Hz sine: the maximum is below the slew's
            pane.freq_hz = 700.0  # near the limit: the keys take it the rest of the way
            for _ in range(20):
                await pilot.press("right_square_bracket")
            cap = slew_max_vpp(profile, pane.freq_hz, pane.waveform)
            assert pane.vpp <= cap, (pane.vpp, pane.freq_hz, cap)  # never past it
            assert pane.freq_hz < 1000  # the amplitude held the frequency back
            await wait_for(pilot, lambda: "slew limit" in line(), 10, "the limit said")
            assert "- lowers the amplitude first" in line(), line()
            assert "freq_hz" not in line(), line()  # the console's keys, not the CLI's
            top = slew_max_vpp(profile, 1000, "sine")  # at 1000 Hz
            while pane.vpp > top:
                await pilot.press("minus")
            for _ in range(30):
                await pilot.press("right_square_bracket")
            assert pane.freq_hz == 1000, (pane.freq_hz, line())  # lower: the frequency rises
            await pilot.press("t")  # square: its edges may need less amplitude
            assert pane.waveform == "square"
            assert pane.vpp <= slew_max_vpp(profile, pane.freq_hz, "square")
            await pilot.press("p")
            await wait_for(pilot, lambda: "on the screen" in line(), 20, "the play said")
            await pilot.pause(0.5)
            assert "refused" not in line() and "slew" not in line(), line()

    asyncio.run(scenario())


def test_the_sine_s_slew_cap_is_the_analytic_one_and_the_square_s_is_below(plugins):
    """A sine of Vpp at f changes at most at pi f Vpp volts a second: the cap is the slew
    limit over pi f (an independent formula; sampled at the card's rate, a step is a
    little gentler than the slope: 0.3 % at 1000 Hz); a square's edges are steeper or
    equal."""
    from console.plugin_api import Limits

    ctx = Context("sim", plugins)
    slew = Limits.from_profile(ctx.profile).slew_v_per_s("screen")
    for f in (10.0, 180.0, 400.0, 870.0, 1000.0):
        sine = slew_max_vpp(ctx.profile, f, "sine")
        assert sine == pytest.approx(slew / (3.141592653589793 * f), rel=4e-3), f
        assert slew_max_vpp(ctx.profile, f, "square") <= sine * 1.0001, f
