"""Reference frequency parameters lambda = omega a^2 sqrt(rho h / D) (FACTS.md, checked).

First six elastic modes; a = long side. The 1.662 rows are the glass's own ratio
743.46 / 447.29 = 1.66214 (the SSSS closed form confirms it to 4e-5). Tolerances:
SSSS 1e-4 relative, CCCC 1e-3, FFFF 1.5 % (nu = 0.3 unless given).
"""

from __future__ import annotations

import math

GLASS_ASPECT = 743.46 / 447.29

#: (edges, aspect, poisson) -> lambdas of modes 1-6
LAMBDA_TABLE: dict[tuple[str, float, float], tuple[float, ...]] = {
    ("ssss", 1.5, 0.3): (32.076, 61.685, 98.696, 111.033, 128.305, 177.653),
    ("ssss", GLASS_ASPECT, 0.3): (37.138, 66.747, 116.095, 118.944, 148.553, 185.182),
    ("cccc", 1.0, 0.3): (35.985, 73.394, 73.394, 108.217, 131.581, 132.205),
    ("cccc", 1.5, 0.3): (60.761, 93.833, 148.780, 149.674, 179.561, 226.824),
    ("cccc", GLASS_ASPECT, 0.3): (71.596, 103.238, 157.851, 180.100, 209.955, 234.208),
    ("ffff", 1.0, 0.3): (13.468, 19.596, 24.270, 34.801, 34.801, 61.093),
    ("ffff", 1.5, 0.3): (20.096, 21.413, 46.347, 49.910, 57.713, 67.030),
    ("ffff", GLASS_ASPECT, 0.22): (21.884, 23.359, 52.342, 60.382, 61.465, 78.103),
}

TOLERANCE = {"ssss": 1e-4, "cccc": 1e-3, "ffff": 1.5e-2}


def ssss_exact(aspect: float, count: int) -> list[float]:
    """Closed-form SSSS lambdas pi^2 (m^2 + n^2 (a/b)^2), ascending."""
    vals = sorted(
        math.pi**2 * (m * m + n * n * aspect * aspect) for m in range(1, 30) for n in range(1, 30)
    )
    return vals[:count]
