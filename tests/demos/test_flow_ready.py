"""The flow demo runs at once: its regions and atlas are prepared behind it, with a
progress that only moves forward and a time left, and a stop cancels the preparation."""

from __future__ import annotations

import threading
import time

from plugins.demos.status import preparing_text


class SlowPlans:
    """Regions that take a moment each and an atlas built in steps the test releases."""

    def __init__(self, steps: int = 5) -> None:
        self.steps = steps
        self.release = threading.Event()
        self.regions: list = []
        self.atlas = None
        self.cancelled = False

    def plan(self, c, direction, exhaustive=False):
        self.regions.append((c, direction, exhaustive))
        time.sleep(0.02)

    def prepare_atlas(self, step_mm, progress):
        try:
            for i in range(self.steps + 1):
                progress(i, self.steps, "flows under a hand")
                if i == 0:
                    self.release.wait(30)
                time.sleep(0.05)
        except BaseException:
            self.cancelled = True
            raise
        self.atlas = object()
        return True


class FakeOutputs:
    def play(self, plan, wait=False):
        raise AssertionError("nothing plays in this test")


def _demo(profile, plugins, plans):
    from plugins.demos.flow import FlowDemo

    return FlowDemo(profile, plugins, FakeOutputs(), plans=plans, grid_mm=10.0)


def _wait(cond, timeout_s=10.0):
    t_end = time.monotonic() + timeout_s
    while not cond() and time.monotonic() < t_end:
        time.sleep(0.01)
    return cond()


def test_the_flow_demo_runs_before_its_atlas_and_says_how_far_it_is(profile, plugins):
    plans = SlowPlans()
    demo = _demo(profile, plugins, plans)
    t0 = time.monotonic()
    demo.start()
    assert time.monotonic() - t0 < 1.0 and demo._running  # running, not waiting
    assert _wait(lambda: (demo.preparation() or {}).get("what", "").endswith("(atlas)"))
    seen = [demo.preparation()]
    plans.release.set()
    while not demo.prepared.is_set():
        p = demo.preparation()
        if p is not None:
            seen.append(p)
        time.sleep(0.005)
    demo.stop()
    atlas = [p for p in seen if p["what"].endswith("(atlas)")]
    done = [p["done"] for p in atlas]
    assert done == sorted(done) and done[-1] >= 3  # forward only
    # its time left is the console's one rule (``console.core.time_left.JobLeft``: none
    # in the first second, this atlas's whole build here; tests/tui/test_time_left_one_rule)
    assert all(ex for _c, _d, ex in plans.regions)  # regions: the reference search
    assert len(plans.regions) == len(demo.regions)
    assert plans.atlas is not None and demo.preparation() is None
    text = preparing_text({"what": "the atlas", "done": 3, "total": 12, "left_s": 95.0})
    assert "25 %" in text and "about 1 min 35 s left" in text


def test_stopping_the_demo_cancels_its_preparation(profile, plugins):
    plans = SlowPlans(steps=1000)
    demo = _demo(profile, plugins, plans)
    demo.start()
    plans.release.set()
    assert _wait(
        lambda: (
            (p := demo.preparation() or {}).get("what", "").endswith("(atlas)") and p["done"] >= 2
        )
    )
    demo.stop()
    assert demo.prepared.is_set() and plans.cancelled and plans.atlas is None


def test_the_atlas_workers_yield_the_cpu_to_the_live_loop():
    import multiprocessing
    import os

    from plugins.vibrotactile.instant import WORKER_NICE, _init_pool_worker

    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(1, initializer=_init_pool_worker, initargs=(None, None, 1.0, {})) as pool:
        assert (
            pool.apply(os.nice, (0,)) >= os.nice(0) + WORKER_NICE or pool.apply(os.nice, (0,)) == 19
        )  # at most the lowest priority
        if hasattr(os, "SCHED_IDLE"):  # Linux: only on a CPU nothing else wants
            assert pool.apply(os.sched_getscheduler, (0,)) == os.SCHED_IDLE
