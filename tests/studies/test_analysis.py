"""``haptable study analyze``: run folders written from the file contract (synth_runs.py),
the RM-ANOVA against second implementations (statsmodels' AnovaRM, the textbook sums of
squares, pingouin; the GG epsilon and Mauchly's W by other formulas), missing and
unbalanced cells refused in one line, the report and the CLI."""

from __future__ import annotations

import itertools
import json
import math
import re
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from console.core.errors import UserError
from plugins.studies import analysis as an
from plugins.studies import rmanova as rm

sys.path.insert(0, str(Path(__file__).resolve().parent))
import synth_runs as sr  # noqa: E402

REGIONS = ("R1", "R2", "R3", "R4")


def _weak_r4_right(i, region, direction):
    return 0.55 if (region == "R4" and direction == "right") else 0.95


@pytest.fixture
def exp2_dir(tmp_path):
    return sr.write_flow(tmp_path / "exp2", "exp2", REGIONS, _weak_r4_right, 8, 10, seed=3)


def _long(cells: np.ndarray, names: list[str]) -> pd.DataFrame:
    rows = []
    for idx in itertools.product(*map(range, cells.shape)):
        rows.append(
            {
                "s": f"S{idx[0]}",
                **{n: f"{n}{i}" for n, i in zip(names, idx[1:], strict=True)},
                "y": cells[idx],
            }
        )
    return pd.DataFrame(rows)


def _random_cells(shape, seed):
    rng = np.random.default_rng(seed)
    y = rng.normal(size=shape) + rng.normal(size=(shape[0],) + (1,) * (len(shape) - 1))
    y[(slice(None), 0) + (slice(None),) * (len(shape) - 2)] += 0.7  # an effect of factor A
    # unequal variances across levels: sphericity does not hold exactly
    y *= np.linspace(1, 2.5, shape[1]).reshape((1, -1) + (1,) * (len(shape) - 2))
    return y


# --------------------------------------------------------------------- the ANOVA itself
@pytest.mark.parametrize("shape", [(7, 3, 4), (6, 4, 3, 3), (9, 2, 2)])
def test_rm_anova_matches_statsmodels_anovarm(shape):
    from statsmodels.stats.anova import AnovaRM

    names = ["A", "B", "D"][: len(shape) - 1]  # patsy reserves "C"
    y = _random_cells(shape, seed=len(shape) * 10 + shape[1])
    ref = AnovaRM(_long(y, names), "y", "s", within=names).fit().anova_table
    ours = {r.source.replace(" * ", ":"): r for r in rm.rm_anova(y, names)}
    assert set(ours) == set(ref.index)
    for src, row in ref.iterrows():
        assert ours[src].f == pytest.approx(row["F Value"], rel=1e-9)
        assert ours[src].df1 == row["Num DF"] and ours[src].df2 == row["Den DF"]
        assert ours[src].p == pytest.approx(row["Pr > F"], rel=1e-7, abs=1e-14)


def test_rm_anova_sums_of_squares_by_the_textbook():
    """Two-way, balanced: SS from the grand, marginal and cell means."""
    y = _random_cells((5, 3, 2), seed=1)
    n, a, b = y.shape
    g = y.mean()
    ma, mb, ms = y.mean(axis=(0, 2)), y.mean(axis=(0, 1)), y.mean(axis=(1, 2))
    mab = y.mean(axis=0)
    mas, mbs = y.mean(axis=2), y.mean(axis=1)  # (n, a), (n, b)
    ss_a = n * b * ((ma - g) ** 2).sum()
    ss_b = n * a * ((mb - g) ** 2).sum()
    ss_ab = n * ((mab - ma[:, None] - mb[None, :] + g) ** 2).sum()
    ss_as = b * ((mas - ma[None, :] - ms[:, None] + g) ** 2).sum()
    ss_bs = a * ((mbs - mb[None, :] - ms[:, None] + g) ** 2).sum()
    ss_tot = ((y - g) ** 2).sum()
    ss_s = a * b * ((ms - g) ** 2).sum()
    ss_abs = ss_tot - ss_a - ss_b - ss_ab - ss_s - ss_as - ss_bs
    rows = {r.source: r for r in rm.rm_anova(y, ["A", "B"])}
    for src, ss, sse in (("A", ss_a, ss_as), ("B", ss_b, ss_bs), ("A * B", ss_ab, ss_abs)):
        assert rows[src].ss == pytest.approx(ss, rel=1e-10)
        assert rows[src].ss_error == pytest.approx(sse, rel=1e-10)
        assert rows[src].np2 == pytest.approx(ss / (ss + sse), rel=1e-10)


def _box_epsilon(y: np.ndarray) -> float:
    """Greenhouse-Geisser epsilon by Box's formula on the k x k covariance of the levels
    (no contrasts): k^2 (mean diag - mean)^2 / ((k-1)(sum s^2 - 2k sum row-mean^2 + k^2 mean^2))."""
    s = np.cov(y, rowvar=False)
    k = s.shape[0]
    sbar, dbar, rows = s.mean(), np.diag(s).mean(), s.mean(axis=1)
    return (
        k**2
        * (dbar - sbar) ** 2
        / ((k - 1) * ((s**2).sum() - 2 * k * (rows**2).sum() + k**2 * sbar**2))
    )


def test_gg_epsilon_against_boxs_formula_and_its_bounds():
    y = _random_cells((10, 4), seed=7)
    (row,) = rm.rm_anova(y, ["A"])
    assert row.eps_gg == pytest.approx(_box_epsilon(y), rel=1e-10)
    assert 1 / 3 - 1e-12 <= row.eps_gg <= 1
    # compound symmetry (equal variances, equal covariances): epsilon 1, Mauchly W 1
    rng = np.random.default_rng(0)
    cs = rng.normal(size=(40, 1)) + rng.normal(size=(40, 4)) * 0.5
    cs = cs - cs.mean(axis=0)
    z = cs @ rm.helmert(4).T
    # rotate the contrast scores so their covariance is exactly isotropic
    w, v = np.linalg.eigh(np.cov(z, rowvar=False))
    z_iso = (z - z.mean(0)) @ v @ np.diag(w**-0.5) @ v.T
    assert rm.gg_epsilon(z_iso) == pytest.approx(1.0, abs=1e-12)
    assert rm.mauchly(z_iso)[0] == pytest.approx(1.0, abs=1e-10)


def test_mauchly_and_epsilon_match_pingouin_for_one_factor():
    import pingouin as pg

    y = _random_cells((12, 4), seed=11)
    df = _long(y, ["A"])
    (row,) = rm.rm_anova(y, ["A"])
    sph = pg.sphericity(df, dv="y", within="A", subject="s")
    assert row.mauchly_w == pytest.approx(sph.W, rel=1e-8)
    assert row.mauchly_chi2 == pytest.approx(sph.chi2, rel=1e-8)
    # pingouin's second-order term has 3(p + 1) where Anderson has 3p: nearly the same p
    assert row.mauchly_p == pytest.approx(sph.pval, rel=2e-3)
    assert row.eps_gg == pytest.approx(pg.epsilon(df, dv="y", within="A", subject="s"), rel=1e-8)


def test_pingouin_two_way_agrees_with_the_contrasts():
    import pingouin as pg

    y = _random_cells((8, 4, 4), seed=5)
    df = _long(y, ["A", "B"])
    aov = pg.rm_anova(
        df, dv="y", within=["A", "B"], subject="s", detailed=True, effsize="np2"
    ).set_index("Source")
    for r in rm.rm_anova(y, ["A", "B"]):
        assert r.f == pytest.approx(aov.loc[r.source, "F"], rel=1e-9)
        assert r.ss == pytest.approx(aov.loc[r.source, "SS"], rel=1e-9)
        assert r.np2 == pytest.approx(aov.loc[r.source, "np2"], rel=1e-9)
    # the main effects' epsilon as pingouin's (its interaction epsilon is approximate)
    for r in rm.rm_anova(y, ["A", "B"])[:2]:
        assert r.eps_gg == pytest.approx(aov.loc[r.source, "eps"], rel=1e-8)


def test_mauchly_is_untestable_with_too_few_subjects():
    y = _random_cells((4, 4, 4), seed=2)  # the interaction has 9 df, 3 subjects' worth
    inter = rm.rm_anova(y, ["A", "B"])[2]
    assert inter.sphericity == "untestable"
    assert inter.p_reported == inter.p_gg  # the conservative p


# --------------------------------------------------------------------- runs -> analysis
def test_exp2_accuracy_tables_are_the_files_counted(exp2_dir):
    res = an.analyze(an.load([exp2_dir]))
    recs = [
        json.loads(line)
        for f in sorted(exp2_dir.glob("*/trials.jsonl"))
        for line in f.read_text().splitlines()
    ]
    main = [r for r in recs if r["phase"] == "main"]
    acc = res["accuracy"]
    assert acc["overall_pct"] == pytest.approx(100 * np.mean([r["correct"] for r in main]))
    p1 = [r["correct"] for r in main if r["participant"] == "P01"]
    assert acc["participants"][0] == {
        "participant": "P01",
        "accuracy_pct": 100 * np.mean(p1),
        "trials": 160,
    }
    cell = next(c for c in acc["cells"] if c["region"] == "R4" and c["direction"] == "right")
    per = [
        np.mean(
            [
                r["correct"]
                for r in main
                if r["participant"] == p and r["region"] == "R4" and r["direction"] == "right"
            ]
        )
        for p in sorted({r["participant"] for r in main})
    ]
    assert cell["accuracy_pct"] == pytest.approx(100 * np.mean(per))
    assert cell["sd_pct"] == pytest.approx(100 * np.std(per, ddof=1))
    assert "practice" in acc


def test_exp2_anova_finds_the_weak_cell(exp2_dir):
    res = an.analyze(an.load([exp2_dir]))
    aov = res["anova"]
    inter = next(r for r in aov["anova"] if r["source"] == "region * direction")
    assert inter["p_reported"] < 0.01 and inter["np2"] > 0.2
    sme = {(e["effect"], e["at"]): e for e in aov["simple_main_effects"]}
    assert sme[("direction", "region = R4")]["p_bonferroni"] < 0.01
    for r in ("R1", "R2", "R3"):
        assert sme[("direction", f"region = {r}")]["p_bonferroni"] > 0.01
    # post-hoc within R4: right differs from the others
    r4 = [p for p in aov["posthoc_bonferroni"] if p.get("region") == "R4"]
    assert r4 and all(p["p-corr"] < 0.05 for p in r4 if "right" in (p["A"], p["B"]))


def test_the_last_done_of_a_trial_counts(tmp_path):
    root = sr.write_flow(tmp_path / "e", "exp1", ("1", "2"), lambda *a: 1.0, 3, 2)
    f = root / "P01" / "trials.jsonl"
    recs = [json.loads(x) for x in f.read_text().splitlines()]
    wrong = next(r for r in ("left_to_right", "right_to_left") if r != recs[-1]["direction"])
    again = {**recs[-1], "correct": False, "response": wrong}
    start = {k: recs[-1][k] for k in ("participant", "experiment", "phase", "trial")}
    start["event"] = "start"
    torn = json.dumps(again)[:25]  # a crash mid-write, then the run went on
    f.write_text(f.read_text() + json.dumps(start) + f"\n{torn}\n" + json.dumps(again) + "\n")
    res = an.analyze(an.load([root]))
    p1 = res["accuracy"]["participants"][0]
    assert p1["trials"] == 8 and p1["accuracy_pct"] == pytest.approx(100 * 7 / 8)


def test_missing_cells_are_one_line_and_no_f(tmp_path):
    root = sr.write_flow(tmp_path / "e", "exp2", REGIONS, _weak_r4_right, 4, 3, drop={"P02": 12})
    res = an.analyze(an.load([root]))
    assert set(res["anova"]) == {"skipped"}
    line = res["anova"]["skipped"]
    assert "missing cells: P02 R4/" in line and "--exclude" in line and "\n" not in line
    assert any("P02: 40/52 trials done" in n for n in res["notes"])
    ok = an.analyze(an.load([root], exclude=("P02",)))
    assert ok["anova"]["participants"] == 3


def test_unbalanced_cells_are_one_line(tmp_path):
    root = sr.write_flow(tmp_path / "e", "exp1", ("1", "2"), lambda *a: 0.8, 4, 3)
    f = root / "P03" / "trials.jsonl"
    lines = f.read_text().splitlines()
    f.write_text("\n".join(lines[:5] + lines[6:]) + "\n")  # one main trial never done
    res = an.analyze(an.load([root]))
    assert re.match(
        r"ANOVA pair x direction: not run: unbalanced cells: P03 1/\w+ \(2 of 3\)",
        res["anova"]["skipped"],
    )


def test_bad_folders_are_one_line(tmp_path):
    with pytest.raises(UserError, match="no participant folder"):
        an.load([tmp_path])
    with pytest.raises(UserError, match="no such folder"):
        an.load([tmp_path / "nope"])
    sr.write_flow(tmp_path / "a", "exp1", ("1",), lambda *a: 1.0, 2, 1)
    sr.write_flow(tmp_path / "b", "exp2", ("R1",), lambda *a: 1.0, 2, 1)
    with pytest.raises(UserError, match="different experiments"):
        an.load([tmp_path / "a", tmp_path / "b"])
    bad = tmp_path / "a" / "P01" / "trials.jsonl"
    bad.write_text('{"event": "done", "trial": 0}\n')
    with pytest.raises(UserError, match=r"trials.jsonl: line 1: participant is missing; restore"):
        an.load([tmp_path / "a"])


def test_knob_analysis(tmp_path):
    root = sr.write_knob(tmp_path / "k", 6)
    res = an.analyze(an.load([root]))
    ct = res["knob"]["measures"]["completion_time_s"]
    rows = {r["source"]: r for r in ct["anova"]["rows"]}
    assert len(rows) == 7
    assert rows["sectors"]["p_reported"] < 0.01 and rows["distance_deg"]["p_reported"] < 0.01
    assert rows["condition"]["p"] > 0.01
    post = {(r["factor"], r["A"], r["B"]): r for r in ct["anova"]["posthoc_bonferroni"]}
    assert post[("sectors", 8, 32)]["p-corr"] < 0.05
    assert post[("sectors", 8, 32)]["p-corr"] == pytest.approx(
        min(1.0, 3 * post[("sectors", 8, 32)]["p-unc"])
    )
    rec = res["knob"]["measures"]["recovery_time_s"]["anova"]
    assert "only after an overshoot" in rec.get("skipped", "") or "rows" in rec
    q = res["knob"]["questionnaire"]
    assert set(q) == set(sr.CATEGORIES)
    eff = q["effectiveness"]["anova"][0]
    assert eff["p_reported"] < 0.001
    # pingouin's one-way F and ours agree; the reported p follows our sphericity verdict
    cat = res["knob"]["questionnaire"]["effectiveness"]
    assert eff["sphericity"] in ("assumed", "violated")
    assert eff["p_reported"] == pytest.approx(
        eff["p-unc"] if eff["sphericity"] == "assumed" else eff["p_gg"]
    )
    assert cat["posthoc_bonferroni"]
    sub = res["knob"]["questionnaire"]["effectiveness"]["by_condition"]
    assert {r["condition"] for r in sub} == set(sr.CONDITIONS)


# --------------------------------------------------------------------- report and CLI
def _cli(*args):
    from console.cli.main import main

    return main(["study", "analyze", *map(str, args)])


def test_cli_json_and_report(exp2_dir, tmp_path, capsys):
    out = tmp_path / "report.html"
    assert _cli(exp2_dir, "--json", "--report", out) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["experiment"] == "exp2" and res["report"] == str(out)
    page = out.read_text()
    assert page.count("data:image/png;base64,") == 2
    assert "region * direction" in page and "Mauchly" in page
    assert "Simple main effects" in page


def test_cli_text_says_why_no_anova(tmp_path, capsys):
    root = sr.write_flow(tmp_path / "e", "exp2", REGIONS, _weak_r4_right, 3, 2, drop={"P03": 5})
    assert _cli(root) == 0
    text = capsys.readouterr().out
    assert "not run: missing cells: P03" in text
    assert not re.search(r"region \* direction\s+\d", text)


# --------------------------------------------------------------------- the screen's summary
def test_summary_rows_are_the_anova_and_say_the_correction(exp2_dir):
    from plugins.studies import summary

    res = an.analyze(an.load([exp2_dir]))
    rows = {r[0]: r for r in summary.anova_rows(res)}
    assert set(rows) == {"region", "direction", "region * direction"}
    for src, row in rows.items():
        r = next(x for x in res["anova"]["anova"] if x["source"] == src)
        assert row[1] == f"{r['f']:.2f} ({r['df1']:g}, {r['df2']:g})"
        assert row[3] == r["sphericity"] and row[5] == f"{r['np2']:.3f}"
        p = r["p_reported"]
        assert row[2].startswith("< .001" if p < 0.001 else f"{p:.3f}")
        assert row[2].endswith(" GG") == (r["sphericity"] != "assumed")
    head = summary.headline(res)
    assert head[0].startswith("exp2: 8 participant(s) (P01, P02") and "8 simulated" in head[0]
    assert head[1].startswith(f"accuracy {res['accuracy']['overall_pct']:.1f} % (P01 ")


def test_summary_of_missing_cells_is_the_line_and_no_row(tmp_path):
    from plugins.studies import summary

    root = sr.write_flow(tmp_path / "e", "exp2", REGIONS, _weak_r4_right, 3, 2, drop={"P02": 5})
    res = an.analyze(an.load([root]))
    assert summary.anova_rows(res) == []
    head = summary.headline(res)
    assert any(h.startswith("P02: ") and "trials done" in h for h in head)
    assert any(h.startswith("ANOVA region x direction: not run: missing cells: P02") for h in head)


def test_summary_of_the_knob_has_each_measure_and_category(tmp_path):
    from plugins.studies import summary

    res = an.analyze(an.load([sr.write_knob(tmp_path / "k", 6)]))
    effects = [r[0] for r in summary.anova_rows(res)]
    assert "completion_time_s: sectors" in effects and "overshoots: condition" in effects
    assert "questionnaire effectiveness: condition" in effects
    assert len([e for e in effects if e.startswith("completion_time_s: ")]) == 7


def test_one_experiment_out_of_a_mixed_folder(tmp_path):
    sr.write_flow(tmp_path / "mixed", "exp2", ("R1", "R2"), lambda *a: 0.9, 3, 2)
    sr.write_flow(tmp_path / "other", "exp1", ("1",), lambda *a: 1.0, 2, 1)
    (tmp_path / "other" / "P01").rename(tmp_path / "mixed" / "Q01")
    with pytest.raises(UserError, match="different experiments"):
        an.load([tmp_path / "mixed"])
    assert an.load([tmp_path / "mixed"], experiment="exp2").experiment == "exp2"
    assert set(an.load([tmp_path / "mixed"], experiment="exp1").participants) == {"P01"}
    with pytest.raises(UserError, match=r"mixed: no participant of knob left to analyse; run"):
        an.load([tmp_path / "mixed"], experiment="knob")


# --------------------------------------------------------------------- degenerate cells
def _all_right_in_r4(i, region, direction):
    """Every participant 100 % in R4, 0 % in R1 (no spread at all in either)."""
    return {"R4": 1.0, "R1": 0.0}.get(region, 0.6 + 0.05 * i)


def test_rm_anova_without_variance_has_no_f_and_no_p():
    from statsmodels.stats.anova import AnovaRM

    # every subject the same at every level: no variance at all
    (r,) = rm.rm_anova(np.full((5, 4), 1.0), ["A"])
    assert r.undefined == "no variance" and r.sphericity == "undefined"
    assert all(math.isnan(x) for x in (r.f, r.p, r.p_gg, r.np2, r.p_reported))
    # subjects differ, levels do not: SS and SS_error both zero (to rounding: 0.1 + 0.2)
    y = np.array([[0.1 + 0.2] * 3, [0.3] * 3, [0.7] * 3])
    (r,) = rm.rm_anova(y, ["A"])
    assert r.undefined == "no variance" and math.isnan(r.p)
    # the same differences in every subject: SS_error zero, the effect is not
    y = np.array([[0.1, 0.5, 0.2], [0.3, 0.7, 0.4], [0.0, 0.4, 0.1]]) + 0.1
    (r,) = rm.rm_anova(y, ["A"])
    assert r.undefined == "no error variance" and math.isnan(r.f) and math.isnan(r.p)
    assert r.np2 == 1.0
    assert r.as_dict()["p_reported"] is None and r.as_dict()["f"] is None
    # a normal case is untouched and still agrees with statsmodels
    y = _random_cells((6, 3), seed=4)
    (r,) = rm.rm_anova(y, ["A"])
    ref = AnovaRM(_long(y, ["A"]), "y", "s", within=["A"]).fit().anova_table.loc["A"]
    assert not r.undefined and r.f == pytest.approx(ref["F Value"], rel=1e-9)
    assert r.p == pytest.approx(ref["Pr > F"], rel=1e-7)


def test_a_constant_cell_is_no_significant_simple_main_effect(tmp_path):
    """All participants 100 % in R4: the simple main effect of direction in R4 is
    undefined (no F, no p, a note naming R4), never F = inf, p = 0; the other regions'
    simple main effects agree with statsmodels."""
    from statsmodels.stats.anova import AnovaRM

    root = sr.write_flow(tmp_path / "e", "exp2", REGIONS, _all_right_in_r4, 5, 6, seed=4)
    res = an.analyze(an.load([root]))
    sme = {(e["effect"], e["at"]): e for e in res["anova"]["simple_main_effects"]}
    r4 = sme[("direction", "region = R4")]
    assert r4["f"] is None and r4["p"] is None and r4["p_bonferroni"] is None
    assert r4["np2"] is None
    assert r4["note"].startswith("no variance: every participant scored the same in R4 (100 %")
    r1 = sme[("direction", "region = R1")]
    assert r1["p"] is None and "in R1 (0 % in every direction)" in r1["note"]
    # a normal cell: the same F as statsmodels on the per-participant accuracies
    recs = [json.loads(x) for f in root.glob("*/trials.jsonl") for x in f.read_text().splitlines()]
    df = pd.DataFrame([r for r in recs if r["phase"] == "main" and r["region"] == "R2"])
    cells = df.groupby(["participant", "direction"])["correct"].mean().reset_index()
    ref = AnovaRM(cells, "correct", "participant", within=["direction"]).fit().anova_table
    r2 = sme[("direction", "region = R2")]
    assert r2["note"] is None
    assert r2["f"] == pytest.approx(ref.loc["direction", "F Value"], rel=1e-9)
    # what a user reads: the CLI and the screen's lines say why, no p of 0
    from plugins.studies import summary
    from plugins.studies.analyze_cli import _lines

    text = "\n".join(_lines(res))
    assert "simple main effect of direction at region = R4: no variance: every participant" in text
    assert any("R4 (100 %" in h for h in summary.headline(res))


def test_a_comparison_without_spread_has_no_t_and_no_p(tmp_path):
    """R1 0 % and R4 100 % for everybody: the R1 vs R4 post-hoc test has no t and no p
    (pingouin's T is inf and its p 0), and says why; the others keep theirs."""
    from scipy import stats

    root = sr.write_flow(tmp_path / "e", "exp2", REGIONS, _all_right_in_r4, 5, 6, seed=4)
    res = an.analyze(an.load([root]))
    post = res["anova"]["posthoc_bonferroni"]
    main = {(p["A"], p["B"]): p for p in post if p["Contrast"] == "region"}
    bad = main[("R1", "R4")]
    assert bad["T"] is None and bad["p-unc"] is None and bad["p-corr"] is None
    assert bad["note"] == (
        "R1 vs R4: no spread: every participant's R1 - R4 difference is the same; t and p undefined"
    )
    within_r4 = [p for p in post if p.get("region") == "R4"]
    assert within_r4 and all(p["p-unc"] is None and "no spread" in p["note"] for p in within_r4)
    assert not any(p["p-unc"] == 0 or p["p-corr"] == 0 for p in post)
    # a comparison with spread: the paired t-test of the participants' region means
    ok = main[("R2", "R3")]
    recs = [json.loads(x) for f in root.glob("*/trials.jsonl") for x in f.read_text().splitlines()]
    df = pd.DataFrame([r for r in recs if r["phase"] == "main"])
    m = df.groupby(["participant", "region"])["correct"].mean().unstack()
    t, p = stats.ttest_rel(m["R2"], m["R3"])
    assert ok["note"] is None and ok["T"] == pytest.approx(t) and ok["p-unc"] == pytest.approx(p)


# --------------------------------------------------------------------- runs under way
def test_accuracy_is_the_main_phase_only_and_says_when_there_is_none(tmp_path, capsys):
    """P01 in the practice phase only: no accuracy (the practice's is apart), not the
    practice's number as the accuracy."""
    from plugins.studies import summary

    root = sr.write_flow(tmp_path / "e", "exp2", REGIONS, lambda *a: 0.5, 1, 2, drop={"P01": 32})
    res = an.analyze(an.load([root]))
    acc = res["accuracy"]
    assert acc["overall_pct"] is None and acc["main_phase"] == "no main-phase trials yet"
    assert acc["participants"] == [{"participant": "P01", "accuracy_pct": None, "trials": 0}]
    assert set(acc["practice"]) == {"practice"}
    head = summary.headline(res)
    assert head[1].startswith("accuracy: no main-phase trials yet (practice: practice ")
    assert _cli(root) == 0
    assert "accuracy (main phase): no main-phase trials yet" in capsys.readouterr().out


def test_a_participant_without_main_trials_is_missing_cells_not_left_out(tmp_path):
    """P01 finished, P02 still in the practice phase: the accuracy is P01's, and the ANOVA
    line says P02's cells are missing (not that there is one participant)."""
    from plugins.studies import summary

    root = sr.write_flow(tmp_path / "e", "exp2", REGIONS, lambda *a: 0.8, 2, 2, drop={"P02": 32})
    res = an.analyze(an.load([root]))
    p1 = [
        json.loads(x)["correct"]
        for x in (root / "P01" / "trials.jsonl").read_text().splitlines()
        if json.loads(x)["phase"] == "main"
    ]
    acc = res["accuracy"]
    assert acc["overall_pct"] == pytest.approx(100 * np.mean(p1))
    assert acc["participants"][1] == {"participant": "P02", "accuracy_pct": None, "trials": 0}
    line = res["anova"]["skipped"]
    assert "missing cells: P02 (all 16 cells)" in line and "one participant" not in line
    assert any("P02 no main-phase trial" in h for h in summary.headline(res))


# --------------------------------------------------------------------- order and figures
def _shuffled_with_protocol_levels(root: Path, factors: dict | None, responses=None) -> None:
    """The trial lines in a random order (the first trial R3 or so, as a run's random
    order would have it) and the plan's protocol levels as ``make_plan`` stores them."""
    import random

    for k, d in enumerate(sorted(root.iterdir())):
        lines = (d / "trials.jsonl").read_text().splitlines()
        random.Random(k).shuffle(lines)
        (d / "trials.jsonl").write_text("\n".join(lines) + "\n")
        plan = json.loads((d / "plan.json").read_text())
        if factors is not None:
            plan["factors"] = factors
        if responses is not None:
            plan["responses"] = responses
        (d / "plan.json").write_text(json.dumps(plan))


def test_tables_list_the_levels_in_the_protocol_order(tmp_path):
    from plugins.studies.plan import make_plan
    from plugins.studies.protocol import load as load_protocol

    plan = make_plan(load_protocol("exp2"), "P01")
    assert plan["factors"]["main"] == {
        "region": ["R1", "R2", "R3", "R4"],
        "direction": ["up", "down", "left", "right"],
    }
    root = sr.write_flow(tmp_path / "e", "exp2", REGIONS, _weak_r4_right, 3, 2, seed=1)
    _shuffled_with_protocol_levels(root, {"main": plan["factors"]["main"]})
    res = an.analyze(an.load([root]))
    acc = res["accuracy"]
    order = ["up", "down", "left", "right"]
    assert [r["direction"] for r in acc["by_direction"]] == order
    assert [r["region"] for r in acc["by_region"]] == list(REGIONS)
    assert [(c["region"], c["direction"]) for c in acc["cells"]] == [
        (r, d) for r in REGIONS for d in order
    ]
    sme = [e["at"] for e in res["anova"]["simple_main_effects"]]
    assert sme == [f"direction = {d}" for d in order] + [f"region = {r}" for r in REGIONS]
    # a plan written before the levels were stored: the directions as its responses
    old = sr.write_flow(tmp_path / "o", "exp2", REGIONS, _weak_r4_right, 3, 2, seed=1)
    _shuffled_with_protocol_levels(old, None, responses=order)
    acc = an.analyze(an.load([old]))["accuracy"]
    assert [r["direction"] for r in acc["by_direction"]] == order
    assert [r["region"] for r in acc["by_region"]] == list(REGIONS)


def test_the_legend_of_the_cells_figure_covers_no_bar(exp2_dir):
    from plugins.studies import report

    res = an.analyze(an.load([exp2_dir]))
    fig = report.cells_figure(res["accuracy"], "region")
    fig.canvas.draw()
    (ax,) = fig.axes
    legend = (fig.legends or [ax.get_legend()])[0].get_window_extent()
    bars = [b.get_window_extent() for b in ax.patches]
    assert len(bars) == 16 and max(b.y1 for b in bars) > ax.get_window_extent().y1 - 20
    assert not any(legend.overlaps(b) for b in bars)
    assert legend.y1 <= ax.get_window_extent().y0  # below the axes, outside the plot


def test_a_file_is_not_a_folder_and_the_screen_hears_its_own_words(tmp_path, capsys):
    from plugins.studies.words import SCREEN

    f = tmp_path / "notes.txt"
    f.write_text("x")
    assert _cli(f) == 2
    err = capsys.readouterr().err
    assert f"{f}: is a file, not a folder; give the --out folder of `haptable study run`" in err
    with pytest.raises(UserError) as e:
        an.load([f], words=SCREEN)
    assert str(e.value) == (
        f"{f}: is a file, not a folder; set folder to the study's results folder (the one "
        "holding P01/ ...)"
    )
    with pytest.raises(UserError, match="no such folder; set folder to"):
        an.load([tmp_path / "nope"], words=SCREEN)
    # what to do about missing cells, as the screen can do it
    root = sr.write_flow(tmp_path / "e", "exp2", REGIONS, _weak_r4_right, 3, 2, drop={"P02": 5})
    line = an.analyze(an.load([root], words=SCREEN))["anova"]["skipped"]
    assert line.endswith(
        "finish those runs (s with the same participant resumes) or move their folders out "
        "of the results folder"
    )
    assert "--" not in line and "`" not in line
    cli_line = an.analyze(an.load([root]))["anova"]["skipped"]
    assert "(the same `study run` command resumes)" in cli_line and "--exclude" in cli_line


def test_a_questionnaire_category_without_variance_has_no_f(tmp_path, capsys):
    """Every participant gives 4 in every condition ("ease of use"), or the same scores
    per condition ("effectiveness"): no F, no p (pingouin's inf, NaN or missing columns
    are not passed on), a note each; the CLI prints it without failing."""
    from plugins.studies import summary

    root = sr.write_knob(tmp_path / "k", 4)
    same = {"V": 2, "HD": 5, "HD+CF": 6, "HD+VF": 6}
    for d in root.iterdir():
        f = d / "trials.jsonl"
        recs = [json.loads(x) for x in f.read_text().splitlines()]
        for e in recs:
            if e["event"] == "questionnaire":
                e["score"] = 4 if e["category"] == "ease of use" else same[e["condition"]]
        f.write_text("".join(json.dumps(e) + "\n" for e in recs))
    res = an.analyze(an.load([root]))
    q = res["knob"]["questionnaire"]
    ease, eff = q["ease of use"]["anova"][0], q["effectiveness"]["anova"][0]
    assert ease.get("F") is None and ease["p_reported"] is None and ease["np2"] is None
    assert ease["note"].endswith(
        "no variance: every participant scored the same (4 in every condition); F and p undefined"
    )
    assert eff["F"] is None and eff["p-unc"] is None and eff["np2"] == 1.0
    assert "no error variance" in eff["note"]
    post = {(r["A"], r["B"]): r for r in q["effectiveness"]["posthoc_bonferroni"]}
    assert post[("HD", "V")]["p-corr"] is None and "no spread" in post[("HD", "V")]["note"]
    assert "no difference and no spread" in post[("HD+CF", "HD+VF")]["note"]
    rows = {r[0]: r for r in summary.anova_rows(res)}
    assert rows["questionnaire ease of use: condition"][1:3] == ("- (3, 9)", "-")
    assert _cli(root) == 0
    assert "questionnaire ease of use: F(3, 9) = -, p = - (undefined)" in capsys.readouterr().out
