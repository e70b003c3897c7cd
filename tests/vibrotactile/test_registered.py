"""The registered ``flow`` effect's extras: tables built step by step (progress, cancel,
the same tables and cache file as the one-shot build) and UFF import."""

from __future__ import annotations

import numpy as np
import pytest

from console.core.errors import UserError
from console.files import paths
from plugins.vibrotactile import lazy
from plugins.vibrotactile.registered import TABLE_STEPS, tables_stepwise_cached
from plugins.vibrotactile.tables import build_tables


class Stop(Exception):
    pass


@pytest.mark.parametrize("contrast_db", [0.0, 10.0])
def test_stepwise_tables_equal_the_one_shot_build(ss_map, contrast_db):
    seen: list[float] = []
    got = build_tables(
        ss_map, 650.0, lambda f, m: seen.append(f), min_contrast_db=contrast_db, steps=TABLE_STEPS
    )
    want = build_tables(ss_map, 650.0, min_contrast_db=contrast_db)
    assert np.array_equal(got.max_diff_um_per_v, want.max_diff_um_per_v)
    assert np.array_equal(got.freq_hz, want.freq_hz, equal_nan=True)
    assert np.array_equal(got.actuator, want.actuator)
    assert len(seen) >= 10 and seen == sorted(seen) and seen[0] == 0.0 and seen[-1] == 1.0


def test_cancelled_build_caches_nothing_and_the_next_build_is_found_by_lazy(
    ss_map, tmp_path, monkeypatch
):
    calls = []

    def cancel_at_third(f: float, msg: str) -> None:
        calls.append(f)
        if len(calls) == 3:
            raise Stop()

    with pytest.raises(Stop):
        tables_stepwise_cached(ss_map, 650.0, tmp_path, cancel_at_third)
    assert not list(tmp_path.iterdir())  # nothing half-built was kept
    t = tables_stepwise_cached(ss_map, 650.0, tmp_path)
    assert len(list(tmp_path.glob("tables-*.npz"))) == 1

    def no_build(*a, **k):
        raise AssertionError("lazy.tables_cached rebuilt tables that were cached")

    monkeypatch.setattr(lazy, "build_tables", no_build)
    again = lazy.tables_cached(ss_map, 650.0, tmp_path)
    assert np.array_equal(again.max_diff_um_per_v, t.max_diff_um_per_v)


def _flow(ctx, tmp_path):
    """The registered flow effect, caching in HapTable's cache (this test's own: conftest)."""
    return ctx.pm.get("effect", "flow").factory(ctx.profile)


def test_flow_effect_tables_with_progress_serve_query_and_render(ctx, ss_map, tmp_path):
    flow = _flow(ctx, tmp_path)
    seen: list[str] = []
    t = flow.tables(vmap=ss_map, progress=lambda f, m: seen.append(m))
    assert seen[-1] == "lookup tables built"
    assert flow.tables(vmap=ss_map) is t  # render and query use these, no second build
    entry = flow.query(51, 52, vmap=ss_map)
    i, j = ss_map.point_index(51), ss_map.point_index(52)
    assert entry["frequency_hz"] == t.freq_hz[i, j]
    plan = flow.render(51, 52, vmap=ss_map)
    assert plan.meta["parts"][0]["frequency_hz"] == entry["frequency_hz"]
    assert plan.meta["parts"][0]["actuator"] == entry["actuator"]


def test_flow_effect_build_cancelled_then_built_on_demand(ctx, ss_map, tmp_path):
    flow = _flow(ctx, tmp_path)

    def cancel(f: float, msg: str) -> None:
        if f > 0.3:
            raise Stop()

    with pytest.raises(Stop):
        flow.tables(vmap=ss_map, progress=cancel)
    plan = flow.render(51, 52, vmap=ss_map)  # builds what it needs
    assert plan.name == "flow 51->52" and len(plan.segments) == 2


def test_flow_effect_imports_uff(ctx, ss_map, tmp_path):
    from console.files.vibration_map import make_map
    from plugins.vibrotactile.uff_export import export_uff

    sub = make_map(
        ss_map.frf_um_per_v[:, :12],
        ss_map.freq_hz,
        ss_map.points[:12],
        ss_map.points_mm[:12],
        ss_map.excitations,
        ss_map.masked,
    )  # one row keeps it quick
    gain = float(ctx.profile.get("amplifiers.piezo_gain"))
    paths = export_uff(sub, tmp_path / "uff", gain=gain)
    flow = _flow(ctx, tmp_path)
    back = flow.import_map({p.stem.lower(): p for p in paths[:2]})  # PA, PB only
    assert back.excitations == ("PA", "PB")
    np.testing.assert_allclose(back.frf_um_per_v, sub.frf_um_per_v[:2], rtol=1e-10, atol=1e-14)
    with pytest.raises(UserError, match="PX"):
        flow.import_map({"PX": paths[0]})


def test_tables_cache_only_in_haptables_cache_or_nowhere(ctx, plugins, tmp_path):
    """`[vibrotactile] cache_dir` is empty (the one cache) or "none"; a folder of its own
    is refused with the line that says so."""
    from console.config.profile import load_profile
    from console.core.errors import ProfileError
    from plugins.vibrotactile.settings import setup_from_profile

    assert setup_from_profile(ctx.profile).cache_dir == paths.cache_dir()
    ctx.profile.data["vibrotactile"]["cache_dir"] = "none"
    assert setup_from_profile(ctx.profile).cache_dir is None
    bad = tmp_path / "bad.toml"
    bad.write_text('[vibrotactile]\ncache_dir = "/srv/tables"\n')
    with pytest.raises(ProfileError, match=r"\[vibrotactile\] cache_dir.*none.*HAPTABLE_CACHE_DIR"):
        load_profile(bad, plugins)
