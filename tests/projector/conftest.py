"""Fixtures for the projector tests: a shared EGL offscreen renderer (skips without EGL)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def requires_egl():
    """Skip (saying why) where a headless projector process cannot render."""
    from plugins.projector.renderer import egl_available

    ok, why = egl_available()
    if not ok:
        pytest.skip(f"headless rendering unavailable: {why}")


@pytest.fixture(scope="session")
def egl_ctx():
    from plugins.projector.renderer import egl_available, egl_context

    ok, why = egl_available()
    if not ok:
        pytest.skip(f"headless rendering unavailable: {why}")
    ctx = egl_context()
    yield ctx
    ctx.release()


@pytest.fixture
def render(egl_ctx):
    """render(state, size=(960, 600), calibration=None) -> (H, W, 3) uint8, top row first."""
    from plugins.projector.geometry import default_calibration
    from plugins.projector.renderer import Offscreen

    made = []

    def _render(state, size=(960, 600), calibration=None):
        cal = calibration or default_calibration(size)
        off = Offscreen(size, cal, ctx=egl_ctx)
        made.append(off)
        off.render(state)
        return off.read_rgb(), cal

    yield _render
    for off in made:
        off.release()
