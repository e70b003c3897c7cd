"""Only what is needed: tables, pair answers and flow-under-hand maps computed on demand
and cached on disk, keyed by a hash of their inputs (map content, parameters).

``prepare`` is what a scene's ``needs`` turn into: ``{"tables": [(a, b), ...],
"flow_regions": [((x, y), direction), ...]}``; ``progress(fraction, message)`` is called
for work that may take more than a second.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable

from console.plugin_api import VibrationMap
from plugins.vibrotactile.cache import cached, cached_entry
from plugins.vibrotactile.hand import hand_flow
from plugins.vibrotactile.perceptual_rule import PerceptualRule
from plugins.vibrotactile.tables import Tables, build_tables, query_points, validate_tables
from plugins.vibrotactile.thresholds import Perception

CacheDir = str | os.PathLike | None


def tables_cached(
    m: VibrationMap,
    band_hz: float,
    cache_dir: CacheDir,
    progress=None,
    *,
    min_contrast_db: float = 0.0,
    perceptual: PerceptualRule | None = None,
    steps: int = 1,
    builder: Callable[[], Tables] | None = None,
) -> Tables:
    """``build_tables`` (or ``builder()``, the same tables built another way) cached under
    a key of the map and the rule's parameters."""
    key: dict = {"map": m.content_hash(), "band_hz": band_hz}
    if min_contrast_db > 0:  # the paper's tables keep their old key
        key["min_contrast_db"] = float(min_contrast_db)
    if perceptual is not None:
        key["rule"] = perceptual.to_json()

    def build() -> dict:
        if builder is not None:
            return _arrays(builder())
        return _arrays(
            build_tables(
                m,
                band_hz,
                progress,
                min_contrast_db=min_contrast_db,
                perceptual=perceptual,
                steps=steps,
            )
        )

    def tables_of(res: dict) -> Tables:
        t = _tables(res, m, band_hz, min_contrast_db, perceptual)
        validate_tables(t, where="tables cache")
        return t

    # an entry of other inputs, damaged or failing the tables' checks is rebuilt
    res, _ = cached_entry(
        cache_dir, "tables", key, build, what="lookup-tables cache entry", check=tables_of
    )
    return tables_of(res)


def _tables(
    res: dict,
    m: VibrationMap,
    band_hz: float,
    min_contrast_db: float,
    perceptual: PerceptualRule | None = None,
) -> Tables:
    return Tables(
        res["max_diff_um_per_v"],
        res["freq_hz"],
        res["actuator"],
        band_hz,
        m,
        float(min_contrast_db),
        perceptual,
    )


def _arrays(t: Tables) -> dict:
    return {"max_diff_um_per_v": t.max_diff_um_per_v, "freq_hz": t.freq_hz, "actuator": t.actuator}


def pair_cached(t: Tables, a_mm, b_mm, method: str, cache_dir: CacheDir) -> dict:
    """Table answer for arbitrary points (x, y mm), cached."""
    key = {
        "map": t.vmap.content_hash(),
        "band_hz": t.band_hz,
        **({"min_contrast_db": t.min_contrast_db} if t.min_contrast_db > 0 else {}),
        **({"rule": t.perceptual.to_json()} if t.perceptual is not None else {}),
        "a": list(map(float, a_mm)),
        "b": list(map(float, b_mm)),
        "method": method,
    }
    return cached(
        cache_dir,
        "pair",
        key,
        lambda: {"answer_json": query_points(t, tuple(a_mm), tuple(b_mm), method=method)},
    )["answer_json"]


def hand_flow_cached(
    m: VibrationMap, center_mm, direction: str, per: Perception, cache_dir: CacheDir, **kw
) -> dict:
    """``hand.hand_flow`` for one region and direction, cached."""
    key = {
        "map": m.content_hash(),
        "center": [float(c) for c in center_mm],
        "direction": direction,
        "perception": repr(per),
        **kw,
    }
    return cached(
        cache_dir,
        "handflow",
        key,
        lambda: {"result_json": hand_flow(m, center_mm, direction, per, **kw)},
    )["result_json"]


def prepare(
    m: VibrationMap,
    per: Perception,
    *,
    pairs: Iterable = (),
    regions: Iterable = (),
    band_hz: float = 650.0,
    method: str = "spline",
    cache_dir: CacheDir = None,
    progress: Callable[[float, str], None] | None = None,
    perceptual: PerceptualRule | None = None,
    **hand_kw,
) -> dict:
    """Build what a scene asked for and nothing else: pair answers and hand-flow maps
    (pairs under the perceptual rule when ``perceptual`` is given, else the paper's)."""
    pairs, regions = list(pairs), list(regions)
    total = max(1, len(pairs) + len(regions) + 1)
    t = tables_cached(m, band_hz, cache_dir, perceptual=perceptual)
    out: dict = {"pairs": {}, "regions": {}}
    for i, (a, b) in enumerate(pairs):
        xa = m.points_mm[m.point_index(a)] if isinstance(a, int) else a
        xb = m.points_mm[m.point_index(b)] if isinstance(b, int) else b
        out["pairs"][
            (a if isinstance(a, int) else tuple(a), b if isinstance(b, int) else tuple(b))
        ] = pair_cached(t, xa, xb, method, cache_dir)
        if progress:
            progress((i + 2) / total, f"pair {i + 1}/{len(pairs)}")
    for j, (c, d) in enumerate(regions):
        out["regions"][(tuple(c), d)] = hand_flow_cached(
            m, c, d, per, cache_dir, band_hz=band_hz, method=method, **hand_kw
        )
        if progress:
            progress((len(pairs) + j + 2) / total, f"flow region {j + 1}/{len(regions)}")
    out["tables"] = t
    return out
