"""Shared pieces of the console tests: a vibration map file, waiting helpers."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(scope="session")
def map_file(tmp_path_factory):
    """An analytic (simply supported plate) vibration map of the sim grid, as a file."""
    from console.vibration_map import save_map
    from plugins.vibrotactile.analytic_plate import analytic_map

    path = tmp_path_factory.mktemp("maps") / "analytic.npz"
    save_map(path, analytic_map(freq_hz=np.arange(0.0, 625.01, 1.0)))
    return path


async def wait_for(pilot, cond, timeout_s: float = 10.0, what: str = "condition") -> None:
    for _ in range(int(timeout_s / 0.05)):
        if cond():
            return
        await pilot.pause(0.05)
    raise AssertionError(f"{what} not reached in {timeout_s:g} s")


def segment_in(rec: np.ndarray, seg: np.ndarray, start_hint: int) -> float:
    """Largest |difference| between ``seg`` and the recording aligned on its first
    non-zero sample at ``start_hint`` (the first non-zero sample of a burst)."""
    k = int(np.flatnonzero(seg)[0])
    a = start_hint - k
    got = rec[a : a + seg.size]
    if got.size != seg.size:
        return float("inf")
    return float(np.max(np.abs(got - seg)))
