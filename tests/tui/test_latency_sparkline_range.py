"""A new operator's try, finding 16a: after a finished demo every Latency "p50 history"
sparkline was a solid block. A p50 that stays near one value (4.1 to 4.3 ms) filled every
bar when the bars were scaled to the maximum alone; scaled to the data's own range the
sparkline shows how the p50 moved, and a constant one shows as a flat low line."""

from __future__ import annotations

from console.tui.plots import BARS, sparkline


def test_a_p50_near_one_value_shows_its_shape_not_a_solid_block():
    p50_ms = [4.1, 4.2, 4.3, 4.2, 4.1, 4.3, 4.15]
    line = sparkline(p50_ms, 20)
    assert line != BARS[-1] * len(p50_ms), line
    assert line[0] == BARS[0] and line[2] == BARS[-1]  # its lowest and highest readings
    assert len(set(line)) >= 3


def test_a_constant_p50_is_a_flat_low_line():
    assert sparkline([4.2] * 9, 20) == BARS[0] * 9
    assert sparkline([0.0, 0.0], 20) == BARS[0] * 2
