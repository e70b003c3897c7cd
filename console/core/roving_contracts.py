"""The guided roving-sensor measurement as a capability (an effect offers it).

The console runs it from the Vibration screen (``m`` with an accelerometer among
``[audio_inputs]``) without knowing the plugin that measures: it asks the registered
effects for ``RovingSensorMaps`` and hands it the console's outputs, where to write the
map, and three callbacks. Every excitation is the plugin's plan through the safety gate.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol, TypedDict, runtime_checkable


class RovingStep(TypedDict, total=False):
    """What ``report`` is told. ``event`` ``"next"``: the sensor goes to ``point`` at
    (``x_mm``, ``y_mm``) (``done`` of ``total`` points kept); ``"measured"``: ``point``
    measured, its coherence over the band and every excitation (``coherence_min``,
    ``coherence_median``, ``good_fraction``: the part >= ``good_coherence``) and
    whether it ``passes`` (``pass_fraction`` of its band good); ``"dummy"``: the clip-on
    dummy of ``dummy_mass_g`` goes on the sensor at ``point`` (``on``; the operator
    confirms on a table) or comes off (``on`` false)."""

    event: str
    point: int
    x_mm: float
    y_mm: float
    done: int
    total: int
    coherence_min: float
    coherence_median: float
    good_fraction: float
    good_coherence: float
    pass_fraction: float
    passes: bool
    simulated: bool
    on: bool
    dummy_mass_g: float


@runtime_checkable
class RovingSensorMaps(Protocol):
    """An effect measuring the vibration map with a roving sensor on the card's inputs.

    ``render(**request)``: the plan of one excitation at one point (``excitation="PA"``).
    ``measure_roving(outputs, out, report=, wait_placed=, stopped=) -> summary``: every
    grid point not kept yet in ``out``'s journal (resumable: started again it goes on
    where it stopped), then the map file ``out``; ``report(step)`` each step
    (``RovingStep``); ``wait_placed(point, x_mm, y_mm)`` blocks until the operator put
    the sensor there (on a twin the plugin moves it itself and never calls it);
    ``stopped()`` polled between points (the caller releases the outputs to stop a point
    under way: that point is measured again on resume). The summary: ``map``,
    ``points_measured_now``, ``coherence_ge_0.9``, ``bins``, ``elapsed_s``."""

    def render(self, **request: Any) -> Any: ...

    def measure_roving(
        self,
        outputs: Any,
        out: Path,
        *,
        report: Callable[[RovingStep], None],
        wait_placed: Callable[[int, float, float], None],
        stopped: Callable[[], bool],
    ) -> dict[str, Any]: ...
