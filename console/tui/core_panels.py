"""The console's own screens as panels: registered through ``haptable_register_panels``
like any plugin's, each with the tab it shows as (title, key, order).

The plugin manager registers this module beside the core plugin (as ``core.panels``);
Electrostatic (F5) and Scenes (F6) are registered by their plugins (electrostatic, demos).
"""

from __future__ import annotations

from typing import Any

from console.config.plugins import PanelTab
from console.core.hookspecs import hookimpl


def _devices(app: Any) -> Any:
    # lazy: Textual loads only when the console opens
    from console.tui.panes.devices import DevicesPane

    return DevicesPane()


def _camera(app: Any) -> Any:
    # lazy: Textual loads only when the console opens
    from console.tui.panes.camera import CameraPane

    return CameraPane()


def _vibration(app: Any) -> Any:
    # lazy: Textual loads only when the console opens
    from console.tui.panes.vibration import VibrationPane

    return VibrationPane()


def _relays(app: Any) -> Any:
    # lazy: Textual loads only when the console opens
    from console.tui.panes.relays import RelaysPane

    return RelaysPane()


def _latency(app: Any) -> Any:
    # lazy: Textual loads only when the console opens
    from console.tui.panes.latency import LatencyPane

    return LatencyPane()


def _scope(app: Any) -> Any:
    # lazy: Textual loads only when the console opens
    from console.tui.panes.scope import ScopePane

    return ScopePane()


def _signals(app: Any) -> Any:
    # lazy: Textual loads only when the console opens
    from console.tui.panes.signals import SignalsPane

    return SignalsPane()


@hookimpl
def haptable_register_panels(register: Any) -> None:
    register(
        "devices",
        _devices,
        description="the profile's devices and their state",
        tab=PanelTab("Devices", "f1", 10),
    )
    register(
        "camera",
        _camera,
        description="camera view, vision tuning, touch calibration",
        tab=PanelTab("Camera", "f2", 20),
    )
    register(
        "vibration",
        _vibration,
        description="vibration map: measure, load, audition points and flows",
        tab=PanelTab("Vibration", "f3", 30),
    )
    register(
        "relays",
        _relays,
        description="relay channels and their switching log",
        tab=PanelTab("Relays", "f4", 40),
    )
    register(
        "latency",
        _latency,
        description="per-stage latency of the frame loop or the running demo",
        tab=PanelTab("Latency", "f7", 70),
    )
    register(
        "signals",
        _signals,
        description="signal designer and library: waveform, spectrum, audition on any patch",
        tab=PanelTab("Signals", "f8", 80),
    )
    register(
        "scope",
        _scope,
        description="the last output per channel as the safety gate passed it, in volts",
        tab=PanelTab("Scope", "f9", 90),
    )
