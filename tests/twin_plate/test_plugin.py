"""The plate plugin registers its sections, command and benchmark on the manager."""

from __future__ import annotations

import pytest

from console.config.plugins import load_plugins
from console.config.profile import load_profile
from console.core.errors import ProfileError


@pytest.fixture(scope="module")
def plugins():
    return load_plugins()


def test_sections_command_and_benchmark_are_registered(plugins):
    for name in ("glass", "plate", "piezo", "vibrometer"):
        assert name in plugins.sections
    assert "plate" in plugins.commands and "plate" in plugins.benchmarks


def test_defaults_fill_in_when_the_sections_are_absent(plugins):
    p = load_profile("sim", plugins)
    assert p.get("plate.damping_ratio") == 0.01
    assert p.get("glass.youngs_modulus_gpa") == 72.0
    assert p.get("piezo.d31_pc_per_n") == -180.0


def test_a_bad_plate_value_is_a_one_line_profile_error(tmp_path, plugins):
    src = load_profile("sim", plugins).path.read_text(encoding="utf-8")
    bad = tmp_path / "bad.toml"
    bad.write_text(src + "\n[plate]\ndamping_ratio = -0.01\n", encoding="utf-8")
    with pytest.raises(ProfileError, match="damping_ratio") as exc:
        load_profile(str(bad), plugins)
    assert "\n" not in str(exc.value)


@pytest.mark.slow
def test_benchmark_runs_and_reports_accuracy_next_to_time():
    from plugins.twin.plate.bench import run_bench

    out = run_bench(None, quick=True)
    assert out["machine"]["cores"] >= 1
    assert max(r["max_rel_error"] for r in out["modal_solve"] if r["basis_order"] >= 16) < 1e-3
    assert out["vibrometer"]["max_error_rel_to_peak"] < 0.2
    best = [r for r in out["frf_truncation"] if r["mode_margin"] == 2.0 and r["static_residual"]]
    assert best[0]["max_rel"] < 5e-3
