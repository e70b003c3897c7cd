"""The demos word their own snapshots (``status_lines``): the console shows the lines."""

from plugins.demos.status import status_lines


def test_the_last_flow_and_a_newer_refusal():
    flow = {
        "kind": "flow",
        "center_mm": [300.0, 200.0],
        "parts": [
            {"actuator": "PA", "frequency_hz": 163.0},
            {"actuator": "PB", "frequency_hz": 94.0},
        ],
        "late_s": 0.42,
    }
    snap = {
        "demo": "flow",
        "running": True,
        "flow": {"direction": "up", "flows": 1, "last": [flow]},
    }
    text = "\n".join(status_lines(snap))
    assert "flow up: 1 played; last at 300,200 mm: PA 163 Hz + PB 94 Hz (planned in 420 ms)" in text
    refused = {"kind": "no_flow", "reason": "no region at 5,5 mm"}
    snap["flow"]["last"] = [flow, refused]
    assert "no_flow: no region at 5,5 mm" in "\n".join(status_lines(snap))


def test_a_stopped_run_without_a_camera_view():
    snap = {"demo": "knob", "running": False, "watchdog": {"tripped": True, "reason": "stuck"}}
    snap["knob"] = {"condition": "HD", "item": 2, "angle_deg": 30.4, "touching": True}
    lines = status_lines(snap)
    assert lines[0].startswith("[b]knob[/b] [yellow]loop stopped[/]")
    assert "[red]e-stop by the watchdog (stuck)[/]" in lines[0]
    assert lines[-1] == "knob HD: item 2, angle 30 deg, touching, 0 crossings"
    assert not any("hand" in line for line in lines)  # no camera view given


def test_not_prepared_says_what_is_missing_and_the_fix():
    from textual.content import Content

    from plugins.demos.panel import status_text

    def shown(st):
        return Content.from_markup(status_text(st)).plain

    knob = shown({"scene": "knob", "unprepared_needs": ["knob", "contacts"]})
    assert "not prepared: knob and contacts: live input the scene waits for" in knob
    assert "start the knob demo (d, then enter on it): it drives this scene" in knob
    alone = shown({"scene": "contacts", "unprepared_needs": ["contacts"]})
    assert "contacts: live input" in alone and "demo" in alone and "knob" not in alone
    why = {"tables": "no vibration map yet: load one; [vibrotactile] off"}
    both = shown({"scene": "flow_hand", "unprepared_needs": ["tables"], "unprepared_why": why})
    assert "not prepared: tables (no vibration map yet: load one; [vibrotactile] off)" in both


def test_status_lines_keep_brackets_and_count_pipeline_drops():
    from textual.content import Content

    snap = {
        "demo": "flow",
        "running": True,
        "camera": {"fps": 60.0, "dropped": 900},  # frames nobody read before the loop
        "latency": {"dropped_camera": 2, "dropped_queue": 3, "stages": {}},
        "last_error": "[audio] device = 'x': gone",
    }
    text = Content.from_markup("\n".join(status_lines(snap))).plain
    assert "dropped 2 (camera) + 3 (queue)" in text and "900" not in text
    assert "[audio] device = 'x': gone" in text
