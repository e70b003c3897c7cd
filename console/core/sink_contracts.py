"""The contracts of the kinds that take what the console has: a frame sink (fed each
frame and its vision results: TUIO, recorders) and a console panel (a Textual screen a
plugin adds). Re-exported by ``console.core.contracts``, where every kind's contract is
found."""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

from console.core.types import Frame


@runtime_checkable
class FrameSink(Protocol):
    """Fed ``sink(frame, work)`` after the frame loop's stages (``work``: ``contacts``,
    ``hands``, ``gesture`` ...), untimed; ``close()`` when the run ends."""

    def __call__(self, frame: Frame, work: dict[str, Any]) -> None: ...

    def close(self) -> None: ...


@runtime_checkable
class FrameSinkFactory(Protocol):
    """``factory(profile, *, force=False) -> FrameSink | None`` (``None``: the profile
    leaves it off; ``force`` opens it anyway)."""

    def __call__(self, profile: Any, *, force: bool = False) -> FrameSink | None: ...


@runtime_checkable
class SwitchableSink(FrameSinkFactory, Protocol):
    """A frame-sink factory the console switches on and off and points at a host:port
    (the Camera screen; saved per profile): ``keys`` names its profile keys,
    ``{"enabled": "<section>.enabled", "host": ..., "port": ...}``; optionally
    ``AdvisesInField``."""

    keys: dict[str, str]


@runtime_checkable
class AdvisesInField(Protocol):
    """A switchable sink whose refusals advise the screen's keys (``fix``), with that
    advice as it works while its target field types every key (``fix_in_field``): the
    screen says the one true where the focus is."""

    fix: str
    fix_in_field: str


@runtime_checkable
class Panel(Protocol):
    """A console panel: a Textual ``Screen`` (anything with ``compose``)."""

    def compose(self) -> Any: ...


@runtime_checkable
class PanelFactory(Protocol):
    """``factory(app) -> Panel``: built with the running app, not a profile."""

    def __call__(self, app: Any) -> Panel: ...
