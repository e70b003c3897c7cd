"""A new operator's try: Camera said `twin camera 5 fps, vision 5 fps` for a twin of 60
fps with nothing on screen saying why (the explaining line gave way at 80 x 24). The
rate line itself says the camera sends the view's rate and what it can."""

from __future__ import annotations

import asyncio
import re

import pytest

from .conftest import wait_for, words_on
from .test_camera import _app, _first_frame


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_rate_line_says_the_view_s_rate(plugins, size):
    async def scenario():
        app = _app(plugins, "camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            text = lambda: words_on(app, "#camera-info")  # noqa: E731
            rates = re.compile(r"camera \d+ fps.*, vision \d+ fps")
            await wait_for(pilot, lambda: rates.search(text()) is not None, 30, "both rates")
            assert "fps (the view's rate; it can 60), vision" in text(), text()

    asyncio.run(scenario())
