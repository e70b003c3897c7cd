"""``bench flow-latency``'s ``decision_to_dac_ms``: ``decision_to_output_ms`` (the block
handed to the driver) plus the output latency from the driver to the DAC.

That latency is the one ``haptable frf latency --save`` measured on the loopback
(``[audio] measured_output_latency_ms``) when the profile has it, else the driver's
claimed output latency, marked so (``added_from``).
"""

from __future__ import annotations

import math
from typing import Any

MEASURED = "measured: [audio] measured_output_latency_ms (haptable frf latency --save)"
CLAIMED = "claimed by the driver (not measured: run haptable frf latency --save)"


def output_latency_ms(profile: Any, claimed_s: Any) -> tuple[float | None, str]:
    """(ms, where from): the profile's measured output latency, else the driver's claim."""
    measured = profile.get("audio.measured_output_latency_ms")
    if measured is not None and float(measured) >= 0:
        return float(measured), MEASURED
    try:
        claimed = float(claimed_s) * 1e3
    except (TypeError, ValueError):
        return None, "unknown: no measured latency and the driver claims none"
    if not math.isfinite(claimed):
        return None, "unknown: no measured latency and the driver claims none"
    return claimed, CLAIMED


def to_dac(summaries: dict[str, dict], profile: Any, claimed_s: Any) -> dict[str, Any]:
    """Each run's ``decision_to_output_ms`` summary shifted by the output latency."""
    add, why = output_latency_ms(profile, claimed_s)
    out: dict[str, Any] = {"added_ms": add, "added_from": why}
    for run, summary in summaries.items():
        out[run] = {
            k: (v + add if k.endswith("_ms") and add is not None else v if k == "n" else None)
            for k, v in summary.items()
        }
    return out
