"""Triangulation of the 2D primitives: areas against closed forms and the shoelace formula."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from plugins.projector import tessellate as T
from plugins.projector.layout import hand_outline_mm


def star(n=7, r0=20.0, r1=50.0):
    a = np.linspace(0, 2 * np.pi, 2 * n, endpoint=False)
    r = np.where(np.arange(2 * n) % 2 == 0, r1, r0)
    return np.c_[r * np.cos(a), r * np.sin(a)] + 100


POLYGONS = {
    "arrow": T.arrow((0, 0), (100, 0), 20, 50),
    "star": star(),
    "hand": np.array(hand_outline_mm((300.0, 200.0), "right")),
    "left hand": np.array(hand_outline_mm((300.0, 200.0), "left")),
    "clockwise L": np.array([[0, 0], [0, 60], [20, 60], [20, 20], [60, 20], [60, 0]], float),
    "collinear + duplicate": np.array(
        [[0, 0], [50, 0], [50, 0], [100, 0], [100, 100], [0, 100]], float
    ),
    "comb": np.array(
        [
            [0, 0],
            [90, 0],
            [90, 40],
            [70, 40],
            [70, 10],
            [50, 10],
            [50, 40],
            [30, 40],
            [30, 10],
            [10, 10],
            [10, 40],
            [0, 40],
        ],
        float,
    ),
}


@pytest.mark.parametrize("name", POLYGONS)
def test_ear_clipping_covers_exactly_the_polygon(name):
    p = POLYGONS[name]
    tri = T.polygon(p)
    assert len(tri) % 3 == 0 and len(tri) > 0
    assert T.triangles_area(tri) == pytest.approx(abs(T.signed_area(p)), rel=1e-9)
    # every triangle lies inside the polygon (its centroid is inside)
    contour = p.astype(np.float32).reshape(-1, 1, 2)
    cents = (tri[0::3] + tri[1::3] + tri[2::3]) / 3
    assert all(cv2.pointPolygonTest(contour, (float(x), float(y)), False) >= 0 for x, y in cents)


def test_fewer_than_three_points_draw_nothing():
    assert len(T.polygon([[0, 0], [1, 1]])) == 0


@pytest.mark.parametrize("r", [0.2, 3.0, 40.0, 400.0])
def test_disc_area_is_pi_r_squared_within_the_chord_tolerance(r):
    area = T.triangles_area(T.disc((5, 5), r))
    n = T.segments_for(r)
    assert area == pytest.approx(
        0.5 * n * r * r * math.sin(2 * math.pi / n), rel=1e-9
    )  # exact polygon
    assert abs(area - math.pi * r * r) <= 2 * math.pi * r * T.TOL_MM + 1e-9
    if r >= 3:  # the sagitta stays within the tolerance
        assert r * (1 - math.cos(math.pi / n)) <= T.TOL_MM + 1e-12


def test_ring_and_arc_areas():
    n = T.segments_for(52.0)
    exact_polygon = 0.5 * n * math.sin(2 * math.pi / n) * (52.0**2 - 48.0**2)
    area = T.triangles_area(T.ring((0, 0), 50, 4))
    assert area == pytest.approx(exact_polygon, rel=1e-9)
    assert abs(area - 2 * math.pi * 50 * 4) <= 2 * math.pi * 100 * T.TOL_MM
    quarter = T.annulus_sector((0, 0), 10, 30, 0, math.pi / 2)
    assert (
        abs(T.triangles_area(quarter) - math.pi / 4 * (30**2 - 10**2))
        <= math.pi / 2 * 40 * T.TOL_MM
    )


def test_polyline_area_and_degenerate_segments():
    tri = T.polyline(
        [[0, 0], [100, 0], [100, 0]], 1.0
    )  # thin, no joins; zero-length segment skipped
    assert T.triangles_area(tri) == pytest.approx(100.0)
    assert len(T.polyline([[5, 5], [5, 5]], 2.0)) > 0  # a dot still draws its round cap
    assert len(T.polyline([[5, 5], [5, 5]], 0.5)) == 0


def test_rect_outline_is_the_frame_area():
    w, h, t = 100.0, 50.0, 2.0
    assert T.triangles_area(T.rect_outline(0, 0, w, h, t)) == pytest.approx(
        (w + t) * (h + t) - (w - t) * (h - t)
    )


@settings(max_examples=150, deadline=None)
@given(
    radii=st.lists(st.floats(0.5, 100.0), min_size=3, max_size=40),
    jitter=st.lists(st.floats(0.05, 0.95), min_size=40, max_size=40),
    clockwise=st.booleans(),
)
def test_ear_clipping_on_random_star_shaped_polygons(radii, jitter, clockwise):
    n = len(radii)
    a = (np.arange(n) + np.array(jitter[:n])) * 2 * np.pi / n  # increasing angles: a simple polygon
    p = np.c_[np.array(radii) * np.cos(a), np.array(radii) * np.sin(a)]
    if clockwise:
        p = p[::-1]
    assume(abs(T.signed_area(p)) > 1e-3)
    tri = T.polygon(p)
    assert T.triangles_area(tri) == pytest.approx(abs(T.signed_area(p)), rel=1e-6, abs=1e-6)
