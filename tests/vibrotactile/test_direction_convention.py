"""A flow "up" moves the way the projected "up" arrow points (one convention)."""

from __future__ import annotations

import numpy as np
import pytest

from console.core.types import DIRECTIONS_MM
from plugins.projector.draw import DIRECTIONS as ARROWS
from plugins.vibrotactile.hand import side_masks


@pytest.mark.parametrize("direction", sorted(DIRECTIONS_MM))
def test_flow_runs_along_the_arrow(direction):
    start, end = side_masks(direction, 3)
    rows, cols = np.indices((3, 3))  # rows grow with y, columns with x (mm)
    centre = lambda m: np.array([cols[m].mean(), rows[m].mean()])  # noqa: E731
    travel = centre(end) - centre(start)
    assert travel @ np.array(DIRECTIONS_MM[direction]) > 0
    assert ARROWS[direction] == DIRECTIONS_MM[direction]
