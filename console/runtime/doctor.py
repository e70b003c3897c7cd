"""What `haptable doctor` and the Devices screen report (``checks``, one list for both):
one status per device the profile uses, the classifier's files (``classifier_status``),
and whether the audio thread may lock its memory and run with real-time priority."""

from __future__ import annotations

import dataclasses

from console.core.realtime import HOW_TO_ALLOW, may_use_realtime
from console.core.types import DeviceStatus

DEVICE_KINDS = (
    ("audio", "audio_output"),
    ("relays", "relay_board"),
    ("camera", "camera"),
    ("vibrometer", "vibrometer"),
)


def diagnose(profile, plugins) -> list[DeviceStatus]:
    """One status per device the profile uses: ok / simulated / missing / error, with a fix."""
    out = []
    for section, kind in DEVICE_KINDS:
        name = profile.get(f"{section}.driver")
        reg = plugins.of(kind).get(name)
        if reg is None:
            out.append(
                DeviceStatus(
                    section,
                    name,
                    "error",
                    "driver not registered",
                    "install the plugin that provides it, or fix the profile",
                )
            )
            continue
        if reg.probe is None:
            out.append(DeviceStatus(section, name, "ok", "no probe: assumed present"))
            continue
        try:
            out.append(dataclasses.replace(reg.probe(profile), kind=section, name=name))
        except Exception as exc:
            out.append(
                DeviceStatus(
                    section,
                    name,
                    "error",
                    f"probe failed: {exc}",
                    f"report this to the {reg.plugin} plugin",
                )
            )
    return out


def classifier_status(profile, plugins) -> DeviceStatus | None:
    """The profile's classifier by its registration's probe (the svm one reads the touch
    calibration as the camera will); None when it has no probe."""
    name = profile.get("gestures.classifier") or "svm"
    reg = plugins.of("classifier").get(name)
    if reg is None:
        return DeviceStatus(
            "gestures",
            name,
            "error",
            "classifier not registered",
            "install the plugin that provides it, or fix [gestures] classifier",
        )
    if reg.probe is None:
        return None
    try:
        return dataclasses.replace(reg.probe(profile), kind="gestures", name=name)
    except Exception as exc:
        return DeviceStatus(
            "gestures",
            name,
            "error",
            f"probe failed: {exc}",
            f"report this to the {reg.plugin} plugin",
        )


def checks(profile, plugins) -> list[DeviceStatus]:
    """Every check of `haptable doctor`, in its order: the devices, the classifier's files
    (when its plugin has a probe), real-time memory and scheduling. The Devices screen
    (F1) shows these rows: a check added here shows on both."""
    return [
        *diagnose(profile, plugins),
        *filter(None, [classifier_status(profile, plugins)]),
        realtime_status(profile, plugins),
        scheduling_status(profile, plugins),
    ]


def realtime_status(profile, plugins) -> DeviceStatus:
    """Whether the audio thread can keep its memory in RAM (``[audio] lock_memory``)."""
    # lazy: keeps `haptable` startup light
    from console.kernel.memory_lock import HOW_TO_ALLOW, _may_lock

    if not profile.get("audio.lock_memory"):
        return DeviceStatus("realtime", "memory", "ok", "lock_memory = false: not asked for")
    ok, why = _may_lock()
    if ok:
        return DeviceStatus("realtime", "memory", "ok", f"can be locked in RAM ({why})")
    twin = plugins.simulated("audio_output", profile)
    return DeviceStatus(
        "realtime",
        "memory",
        "ok" if twin else "missing",
        f"cannot be locked ({why}): a paged-out page can stall the audio thread"
        + (" (the twin only counts the underruns)" if twin else ""),
        HOW_TO_ALLOW,
    )


def scheduling_status(profile, plugins) -> DeviceStatus:
    """Whether the audio thread and a demo's frame loop can run with real-time priority."""
    if may_use_realtime():
        return DeviceStatus("realtime", "scheduling", "ok", "real-time (FIFO) priority allowed")
    twin = plugins.simulated("audio_output", profile)
    return DeviceStatus(
        "realtime",
        "scheduling",
        "ok" if twin else "missing",
        "real-time priority not allowed: other programs can delay the audio and the "
        "frame loop" + (" (the twin only counts the underruns)" if twin else ""),
        HOW_TO_ALLOW,
    )
