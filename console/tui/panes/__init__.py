"""The console's screens, one tab each: Devices, Camera, Vibration, Relays, Electrostatic,
Scenes, Latency. Each pane is a widget whose ``BINDINGS`` apply while it has the focus;
``focus_target`` is what the app focuses when the tab opens."""
