"""Helpers for ``haptable bench``: percentiles and the machine a number was measured on."""

from __future__ import annotations

import os
import platform
from collections.abc import Sequence

import numpy as np


def machine_info() -> dict[str, object]:
    """Where a benchmark ran: report it next to every number."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "system": f"{platform.system()} {platform.release()}",
    }


def summarize_s(samples_s: Sequence[float]) -> dict[str, float]:
    """Median, p99 and max of durations given in seconds, reported in milliseconds."""
    a = np.asarray(samples_s, dtype=float) * 1e3
    if a.size == 0:
        return {"n": 0, "p50_ms": float("nan"), "p99_ms": float("nan"), "max_ms": float("nan")}
    return {
        "n": int(a.size),
        "p50_ms": float(np.percentile(a, 50)),
        "p99_ms": float(np.percentile(a, 99)),
        "max_ms": float(a.max()),
    }
