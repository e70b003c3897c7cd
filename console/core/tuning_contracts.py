"""A classifier's tunables as capabilities (``console.core.contracts`` re-exports them):
where the profile keeps them, and the order some of them keep."""

from __future__ import annotations

from typing import Protocol, runtime_checkable


@runtime_checkable
class TunablesInProfile(Protocol):
    """A classifier whose tunables are profile settings, so the console can keep the
    operator's tuning for the next start: ``tunable_keys() -> {tunable: "section.key"}``."""

    def tunable_keys(self) -> dict[str, str]: ...


@runtime_checkable
class OrderedTunables(Protocol):
    """A classifier whose tunables keep an order (a threshold below another, or the
    vision finds nothing): ``tunable_order() -> ((lower, higher, why), ...)``: ``lower``
    stays below ``higher`` while ``higher`` is above 0 (0: off); ``why`` says it in an
    operator's words. The console's tuning keys keep it (``CameraService.set_param``);
    values set otherwise (a profile, a recording) are taken as they are."""

    def tunable_order(self) -> tuple[tuple[str, str, str], ...]: ...
