"""The projected grid's point labels stay clear of the patches' drawings (issue 27: the
PB and PC outlines crossed labels 36 and 76). Checked on the drawn geometry: each label's
box (its width from the font the renderer sets it in) against each patch's rectangle and
every other label."""

from __future__ import annotations

import pytest

from console.config.plugins import load_plugins
from console.config.profile import load_profile
from plugins.projector.draw import build_layer, draw_grid
from plugins.projector.scenes import GridAudition
from plugins.projector.text import text_bitmap


def _box(t):
    """The renderer's quad for a text item (``renderer._upload_texts``), in mm."""
    bh, bw = text_bitmap(t.text, 64).shape
    h = t.size_mm
    w = h * bw / bh
    x = t.xy_mm[0] - {"l": 0.0, "c": w / 2, "r": w}[t.anchor]
    y = t.xy_mm[1] - h / 2
    return (x, y, x + w, y + h)


def _hit(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


@pytest.mark.parametrize("lit", [None, "PALL"])
def test_point_labels_clear_the_patches(lit):
    profile = load_profile("sim", load_plugins(entrypoints=False))
    scene = GridAudition(profile)
    if lit:
        scene.update({"type": "audition", "point": 1, "excitation": lit})
    state = scene.state()
    layer = build_layer(draw_grid(state))
    names = {p["name"] for p in state["patches"]}
    ids = {str(n) for n in state["point_ids"]}
    labels = [t for t in layer.texts if t.text in ids and t.size_mm < 10]
    assert len(labels) == len(ids) - (1 if lit else 0)  # the active point has its own
    patches = []
    for p in state["patches"]:
        (cx, cy), (w, h) = p["center_mm"], p["size_mm"]
        m = 0.75  # half the outline's width
        patches.append(
            (p["name"], (cx - w / 2 - m, cy - h / 2 - m, cx + w / 2 + m, cy + h / 2 + m))
        )
    assert {n for n, _ in patches} == names == {"PA", "PB", "PC", "PD"}
    covered = [(t.text, n) for t in labels for n, r in patches if _hit(_box(t), r)]
    assert covered == []
    boxes = [(t.text, _box(t)) for t in labels]
    touching = [(a, b) for i, (a, x) in enumerate(boxes) for b, y in boxes[i + 1 :] if _hit(x, y)]
    assert touching == []
