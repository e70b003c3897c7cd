"""Scenes as the console sees them: needs, events, JSON state; the plugin's hooks."""

from __future__ import annotations

import json

import numpy as np
import pytest

from console.core.errors import UserError
from console.runtime.projector.service import prepare_needs
from plugins.projector.draw import DRAWERS, primitives
from plugins.projector.layout import grid_points_mm, parse_pairs, parse_regions
from plugins.projector.scenes import BUILTIN_SCENES, FlowHand, FlowTwoPoint, GridAudition, Knob

NEED_KINDS = {"tables", "flow_regions", "knob", "contacts"}


@pytest.mark.parametrize("name", BUILTIN_SCENES)
def test_every_scene_gives_json_state_of_a_drawable_kind(name):
    scene = BUILTIN_SCENES[name][0](None)
    state = json.loads(json.dumps(scene.state(), allow_nan=False))
    assert state["kind"] in DRAWERS
    assert set(scene.needs) <= NEED_KINDS
    primitives(state)  # draws without error


def test_grid_numbering_matches_the_paper():
    pts = grid_points_mm(None)
    assert pts.shape == (84, 2)
    # points 51 and 52 are horizontal neighbours 60 mm apart (row 5, columns 3 and 4)
    assert pts[51] - pts[50] == pytest.approx([60.0, 0.0])
    assert pts[0] == pytest.approx([41.73, 43.645])
    assert pts[83] == pytest.approx([41.73 + 660, 43.645 + 360])


def test_knob_rotation_moves_the_current_item_one_per_sector():
    k = Knob(None)
    k.update({"type": "trial", "sectors": 8, "distance_deg": 270, "seed": 3})
    s0 = k.state()
    assert s0["target"] - s0["current"] == 6  # 270 degrees / 45 per sector
    assert s0["items"][s0["target"]] not in s0["items"][: s0["target"]]  # distinct cities
    k.update({"type": "rotate", "delta_deg": 44.0})
    assert k.state()["current"] == s0["current"]
    k.update({"type": "rotate", "delta_deg": 1.0})
    assert k.state()["current"] == s0["current"] + 1
    k.update({"type": "rotate", "delta_deg": 225.0})
    assert k.state()["reached"] is True
    k.update(
        {"type": "rotate", "delta_deg": -10_000.0}
    )  # far past the start: clamped to the first item
    assert k.state()["current"] == 0


@pytest.mark.parametrize("sectors,distance", [(8, 135), (16, 270), (32, 450)])
def test_knob_trials_of_the_paper(sectors, distance):
    k = Knob(None)
    k.update({"type": "trial", "sectors": sectors, "distance_deg": distance, "seed": 1})
    s = k.state()
    assert s["target"] - s["current"] == round(distance / (360 / sectors))
    assert len(set(s["items"])) == len(s["items"])
    with pytest.raises(UserError, match="sectors"):
        k.update({"type": "trial", "sectors": 1})


def test_flow_hand_buttons_sit_on_the_free_hand_side_and_answer_touches():
    f = FlowHand(None)
    for name, (x, _, hand) in f.regions.items():
        f.update({"type": "region", "name": name})
        s = f.state()
        xs = [b["c"][0] for b in s["buttons"]]
        if hand == "left":
            assert min(xs) > x + s["region_size_mm"] / 2
        else:
            assert max(xs) < x - s["region_size_mm"] / 2
        for b in s["buttons"]:  # whole buttons on the glass
            h = b["size_mm"] / 2
            assert h <= b["c"][0] <= f.table_mm[0] - h and h <= b["c"][1] <= f.table_mm[1] - h
    by_dir = {b["dir"]: b["c"] for b in f.state()["buttons"]}
    assert by_dir["up"][1] < by_dir["down"][1] and by_dir["left"][0] < by_dir["right"][0]
    f.update({"type": "touch", "pos_mm": by_dir["left"]})
    assert f.state()["selected"] == "left"
    f.update({"type": "touch", "pos_mm": [1.0, 1.0]})  # not on a button: answer unchanged
    assert f.state()["selected"] == "left"
    with pytest.raises(UserError, match="R9"):
        f.update({"type": "region", "name": "R9"})


def test_two_point_needs_only_the_tables_of_its_pairs():
    f = FlowTwoPoint(None)
    assert f.needs == {"tables": sorted({p for ab in f.pairs.values() for p in ab})}
    f.update({"type": "pair", "name": "F"})
    s = f.state()
    assert s["pair_points"]["F"] == [51, 52]
    assert np.allclose(s["pairs"]["F"][1], np.array(s["pairs"]["F"][0]) + [60, 0])


def test_bad_layout_strings_say_how_to_write_them():
    with pytest.raises(UserError, match="name:active:passive"):
        parse_pairs(["F:51"], 84)
    with pytest.raises(UserError, match="1..84"):
        parse_pairs(["F:51:99"], 84)
    with pytest.raises(UserError, match="left|right"):
        parse_regions(["R1:10:10:both"])


def test_grid_audition_checks_the_point():
    g = GridAudition(None)
    g.update({"type": "audition", "point": 51, "passive": 52, "excitation": "PALL"})
    s = g.state()
    assert s["active"] == 51 and s["excitation_patches"] == ["PA", "PB", "PC", "PD"]
    with pytest.raises(UserError, match="not on the map's grid"):
        g.update({"type": "audition", "point": 85})


def test_grid_follows_the_maps_own_ids_and_places():
    """A map numbered column by column (ids 1001..1084): the projected labels are its ids,
    and the auditioned id is lit where that point is on the glass."""
    g = GridAudition(None)
    rows, cols, pitch, ox, oy = 7, 12, 60.0, 41.73, 43.645
    ids, pts = [], []
    for c in range(cols):  # column-major numbering
        for r in range(rows):
            ids.append(1001 + c * rows + r)
            pts.append([ox + c * pitch, oy + r * pitch])
    g.update({"type": "points", "ids": ids, "points_mm": pts})
    g.update({"type": "audition", "point": 1009, "passive": 1002, "excitation": "PA"})
    s = g.state()
    assert s["points_mm"][s["active"] - 1] == [ox + 1 * pitch, oy + 1 * pitch]
    assert s["points_mm"][s["passive"] - 1] == [ox, oy + 1 * pitch]
    texts = {sh["text"] for sh in primitives(s) if sh.get("p") == "text"}
    assert {"1001", "1084", "1009"} <= texts and "1" not in texts
    with pytest.raises(UserError, match="points"):
        g.update({"type": "points", "ids": [1, 1], "points_mm": [[0, 0], [1, 1]]})


def test_runtime_prepares_only_what_a_scene_declares():
    calls = []
    providers = {k: (lambda v, k=k: calls.append(k) or k) for k in NEED_KINDS}
    prepared, missing = prepare_needs(BUILTIN_SCENES["contacts"][0](None).needs, providers)
    assert calls == ["contacts"] and prepared == {"contacts": "contacts"} and missing == []
    calls.clear()
    prepared, missing = prepare_needs(Knob(None).needs, {"contacts": providers["contacts"]})
    assert calls == ["contacts"] and missing == ["knob"]


def test_plugin_registers_scenes_section_command_and_bench():
    from console.config.plugins import load_plugins

    plugins = load_plugins(builtins={"projector": "plugins.projector"}, entrypoints=False)
    assert set(BUILTIN_SCENES) <= set(plugins.of("scene"))
    assert "projector" in plugins.sections and "projector" in plugins.commands
    assert "projector" in plugins.benchmarks
    fields = plugins.sections["projector"][0]
    assert fields["width_px"].default == 1280 and fields["socket_path"].default == ""


def test_contacts_overlay_takes_the_pipeline_value_types():
    from console.core.types import Contact, Hand, HandShape

    c = BUILTIN_SCENES["contacts"][0](None)
    hand = Hand(
        contour_px=np.zeros((4, 2)),
        center_px=(10.0, 10.0),
        radius_px=5.0,
        angle_deg=0.0,
        shape=HandShape.of(np.zeros(8), 2),
        center_mm=(300.0, 200.0),
    )
    c.update(
        {
            "type": "contacts",
            "contacts": [Contact(7, (1.0, 2.0), (120.0, 80.0)), Contact(8, (3.0, 4.0))],
            "hands": [hand],
        }
    )
    s = json.loads(json.dumps(c.state()))
    assert s["contacts"][0] == {"id": 7, "pos_mm": [120.0, 80.0]}
    assert s["contacts"][1]["pos_mm"] is None  # not calibrated yet: not drawn
    assert s["hands"][0]["center_mm"] == [300.0, 200.0] and s["hands"][0]["label"] == "2 fingers"
    prims = primitives(s)
    assert sum(p["p"] == "ring" for p in prims) == 1
