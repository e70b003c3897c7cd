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
    assert "[red]watchdog tripped: stuck[/]" in lines[0]
    assert lines[-1] == "knob HD: item 2, angle 30 deg, touching, 0 crossings"
    assert not any("hand" in line for line in lines)  # no camera view given
