"""Stopping the flow demo does not wait for an atlas chunk under way (issue 27, fourth
new-user try: a stop took ~6 s, joining the preparation thread while its pool worked on
a chunk): the preparation is told, and cancels itself when the chunk comes back."""

from __future__ import annotations

import threading

from .test_flow_ready import SlowPlans, _demo, _wait


def test_stop_returns_while_an_atlas_chunk_is_under_way(profile, plugins):
    plans = SlowPlans(steps=1000)  # its first chunk ends when ``release`` is set
    demo = _demo(profile, plugins, plans)
    demo.start()
    assert _wait(lambda: (demo.preparation() or {}).get("what", "").endswith("(atlas)"))
    late = threading.Timer(15.0, plans.release.set)  # the chunk, far later than a stop takes
    late.start()
    try:
        demo.stop()
        assert not plans.release.is_set()  # the stop did not wait for the chunk
    finally:
        late.cancel()
        plans.release.set()
    assert _wait(lambda: demo.prepared.is_set(), 30)  # it cancels at its next step
    assert plans.cancelled and plans.atlas is None
