"""The demos' profile sections: ``[runtime]`` (the frame loop, its watchdog and monitor)
and ``[demos]`` (the flow and knob demos)."""

from __future__ import annotations

from console.plugin_api import Field

#: ``[runtime]``: the interaction loop's queue, watchdog and latency monitor
RUNTIME_FIELDS = {
    "watchdog_ms": Field(
        "float",
        250.0,
        min=20,
        max=10000,
        help="silence the outputs (e-stop) when the frame loop is stuck this long "
        "(a frame in one stage, or no frame from the camera)",
    ),
    "queue_frames": Field(
        "int", 2, min=1, max=64, help="frames waiting for processing; the oldest is dropped"
    ),
    "latency_window_frames": Field(
        "int", 1200, min=10, max=1000000, help="frames the latency monitor's p50/p99 cover"
    ),
    "realtime_loop": Field(
        "bool",
        True,
        help="a demo's frame loop threads ask for real-time (FIFO) scheduling one step "
        "below the audio thread, where the system allows it (rtprio limit or CAP_SYS_NICE)",
    ),
    "twin_camera_process": Field(
        "bool",
        True,
        help="demos on the twin camera: render its frames in a separate process, as a "
        "camera device delivers them (false: in the console's process, sharing its CPU time)",
    ),
}

#: ``[demos]``: the flow and knob demos
DEMOS_FIELDS = {
    "flow_map": Field(
        "path",
        "",
        help="vibration map the flow demo uses (relative to the profile's folder); empty on "
        "the twin: the profile's measured map, measured once into HapTable's cache",
    ),
    "flow_direction": Field(
        "str", "right", choices=("left", "right", "up", "down"), help="flow direction"
    ),
    "flow_grid_mm": Field(
        "float",
        10.0,
        min=0,
        max=100,
        help="a hand away from the scene's regions gets the flow of the nearest point of "
        "this grid (0: its exact position)",
    ),
    "plan_process": Field(
        "bool",
        True,
        help="flows not prepared at the start (a hand away from the scene's regions) are "
        "planned in a separate process (false: on a thread sharing the loop's interpreter)",
    ),
    "flow_atlas": Field(
        "bool",
        True,
        help="when the flow demo prepares, choose every flow under a hand on the "
        "flow_grid_mm grid in every direction (minutes the first time, then cached): a "
        "resting hand's flow starts at once (false: planned when asked, 1-3 s late)",
    ),
    "still_mm": Field("float", 12.0, min=1, max=200, help="a resting hand moves less than this"),
    "still_ms": Field("float", 300.0, min=0, max=10000, help="... for this long to trigger"),
    "knob_condition": Field(
        "str", "HD+CF", help="knob feedback condition (V, HD, HD+CF, HD+VF, variants)"
    ),
}
