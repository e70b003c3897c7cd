"""``haptable study analyze DIR...``: the runs' files read back and analysed.

Reads each participant's ``participant.json``, ``plan.json`` and the ``done`` and
``questionnaire`` lines of ``trials.jsonl`` (the last ``done`` per trial; the columns in
this package's README.md). Experiments 1 and 2 (the ``main`` phase; practice phases are
reported apart): accuracy per participant, direction, pair or region and cell; a two-way
repeated-measures ANOVA on the per-participant cell accuracies (pingouin ``rm_anova``,
Mauchly's test, Greenhouse-Geisser, partial eta squared), Bonferroni post-hoc
comparisons (pingouin ``pairwise_tests``) and simple main effects (a one-way RM-ANOVA of
each factor at each level of the other, Bonferroni over the levels). The knob:
completion time, overshoots and recovery time by condition x sectors x distance and a
three-way RM-ANOVA of each (``rmanova.py``: pingouin stops at two factors), and a one-way
RM-ANOVA of each questionnaire category over the conditions.

An ANOVA needs every participant in every cell with the plan's number of trials: missing
cells or unequal counts give one line saying who and what (``skipped``), never an F.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np

from console.plugin_api import UserError

from .rmanova import rm_anova
from .runs import Study, load, participant_dirs
from .words import CLI, Words

__all__ = ["Study", "analyze", "load", "participant_dirs"]

#: Factors of each experiment's main phase (the plan's trial keys).
FACTORS = {"exp1": ("pair", "direction"), "exp2": ("region", "direction")}
KNOB_MEASURES = ("completion_time_s", "overshoots", "recovery_time_s")
KNOB_FACTORS = ("condition", "sectors", "distance_deg")


# --------------------------------------------------------------------------- order
def level_order(study: Study, factor: str, phase: str = "main") -> list[Any]:
    """The levels of ``factor`` in the protocol's order: the plan's ``factors`` of
    ``phase`` (plans written before it was stored: the plan's ``responses`` for the
    direction, else none: natural order)."""
    plan = next(iter(study.plans.values()))
    levels = (plan.get("factors") or {}).get(phase, {}).get(factor)
    if levels is None and factor == "direction":
        levels = plan.get("responses")
    return [_level(v) for v in levels or []]


def _natural(v: Any) -> tuple:
    """``R2`` before ``R10``; numbers by value."""
    import re

    if isinstance(v, (int, float)):
        return (0, v, ())
    parts = re.split(r"(\d+)", str(v))
    return (1, 0, tuple((0, int(x), "") if x.isdigit() else (1, 0, x) for x in parts))


def in_protocol_order(df, study: Study, factors: tuple[str, ...], phase: str = "main"):
    """``df``'s rows sorted (stably) by ``factors`` in the protocol's level order, so that
    tables grouped in order of appearance (``groupby(sort=False)``) list the protocol's
    order, not the first trial's."""
    if df.empty:
        return df
    ranks = {}
    for f in factors:
        listed = level_order(study, f, phase)
        rest = sorted((v for v in set(df[f]) if v not in listed), key=_natural)
        ranks[f] = {v: i for i, v in enumerate([*listed, *rest])}
    return df.sort_values(list(factors), key=lambda col: col.map(ranks[col.name]), kind="mergesort")


# --------------------------------------------------------------------------- accuracy
def _summary(df, by: str) -> list[dict[str, Any]]:
    """Mean, SD and SEM over participants of their accuracy per level of ``by``."""
    per = df.groupby(["participant", by], sort=False)["correct"].mean().unstack(by)
    out = []
    for level in per.columns:
        col = per[level].dropna() * 100
        n = int(col.size)
        sd = float(col.std(ddof=1)) if n > 1 else math.nan
        out.append(
            {
                by: level,
                "accuracy_pct": float(col.mean()),
                "sd_pct": _num(sd),
                "sem_pct": _num(sd / math.sqrt(n) if n > 1 else math.nan),
                "participants": n,
                "trials": int(df[df[by] == level].shape[0]),
            }
        )
    return out


def _num(x: float) -> float | None:
    return None if x is None or not math.isfinite(float(x)) else float(x)


#: what the accuracy of the main phase is before any main-phase trial is done
NO_MAIN = "no main-phase trials yet"


def accuracy(study: Study) -> dict[str, Any]:
    """Accuracy tables of experiment 1 or 2: the main phase only (practice phases apart,
    ``practice``); before any main-phase trial ``overall_pct`` is None and ``main_phase``
    says so (``NO_MAIN``), and a participant without one has ``accuracy_pct`` None."""
    df = study.trials
    df = df.assign(correct=df["correct"].astype(bool))
    a, b = FACTORS[study.experiment]
    main = in_protocol_order(df[df["phase"] == "main"], study, (a, b))
    practice = df[df["phase"] != "main"]
    per_p = main.groupby("participant")["correct"].agg(["mean", "size"])
    people = []
    for p in sorted(study.plans):
        if p in per_p.index:
            r = per_p.loc[p]
            people.append({"participant": p, "accuracy_pct": 100 * float(r["mean"])})
            people[-1]["trials"] = int(r["size"])
        else:
            people.append({"participant": p, "accuracy_pct": None, "trials": 0})
    out: dict[str, Any] = {
        "participants": people,
        "overall_pct": 100 * float(main["correct"].mean()) if len(main) else None,
        "main_phase": f"{len(main)} trials" if len(main) else NO_MAIN,
        f"by_{b}": _summary(main, b) if len(main) else [],
        f"by_{a}": _summary(main, a) if len(main) else [],
        "cells": [
            {a: ka, b: kb, **row}
            for ka, sub in main.groupby(a, sort=False)
            for row in _summary(sub, b)
            for kb in [row[b]]
        ],
    }
    if not practice.empty:
        out["practice"] = {
            ph: 100 * float(sub["correct"].mean()) for ph, sub in practice.groupby("phase")
        }
    if "replays" in main:
        out["replays_mean"] = float(main["replays"].fillna(0).mean())
    if "response_time_s" in main:
        rt = main["response_time_s"].dropna()
        out["response_time_s_median"] = float(rt.median()) if rt.size else None
    return out


# --------------------------------------------------------------------------- balance
def design_counts(study: Study, factors: tuple[str, ...], phase: str | None) -> dict[tuple, int]:
    """Trials per cell the plans ask for (the first participant's plan; the plans of
    one protocol have the same cells)."""
    counts: dict[tuple, int] = {}
    plan = next(iter(study.plans.values()))
    for t in plan["trials"]:
        if phase is not None and t.get("phase") != phase:
            continue
        key = tuple(_level(t.get(f) if f in t else t["stimulus"].get(f)) for f in factors)
        counts[key] = counts.get(key, 0) + 1
    return counts


def _level(v: Any) -> Any:
    return int(v) if isinstance(v, float) and v.is_integer() else v


def balance_problem(
    df,
    factors: tuple[str, ...],
    want: dict[tuple, int],
    *,
    exact: bool = True,
    participants: list[str] | None = None,
    words: Words = CLI,
) -> str | None:
    """Why the cells are not complete and (``exact``) balanced (None: they are).
    ``participants``: everyone who should be in every cell (default: those in ``df``;
    give the study's: a participant without a row in ``df`` is missing every cell).
    ``words``: how the fix is named."""
    have = df.groupby(["participant", *factors]).size() if len(df) else {}
    pids = sorted(set(df["participant"]) if participants is None else set(participants))
    missing, short = [], []
    for pid in pids:
        gone = [c for c in want if int(have.get((pid, *c), 0)) == 0]
        if want and len(gone) == len(want) and len(want) > 1:
            missing.append(f"{pid} (all {len(want)} cells)")
            continue
        for cell, n in want.items():
            got = int(have.get((pid, *cell), 0))
            label = "/".join(map(str, cell))
            if got == 0:
                missing.append(f"{pid} {label}")
            elif exact and got != n:
                short.append(f"{pid} {label} ({got} of {n})")
    if missing:
        more = f" and {len(missing) - 3} more" if len(missing) > 3 else ""
        return (
            f"missing cells: {', '.join(missing[:3])}{more}; finish those runs "
            f"({words.resume}) or {words.exclude}"
        )
    if short:
        more = f" and {len(short) - 3} more" if len(short) > 3 else ""
        return (
            f"unbalanced cells: {', '.join(short[:3])}{more}; finish those runs or {words.exclude}"
        )
    if len(pids) < 2:
        return "one participant: an ANOVA needs at least two"
    return None


# --------------------------------------------------------------------------- two-way
def _clean(df) -> list[dict[str, Any]]:
    out = []
    for rec in df.to_dict("records"):
        out.append(
            {
                str(k): (
                    _num(v)
                    if isinstance(v, (float, np.floating))
                    else (v.item() if isinstance(v, np.generic) else v)
                )
                for k, v in rec.items()
            }
        )
    return out


def two_way(df, dv: str, a: str, b: str) -> dict[str, Any]:
    """Two-way RM-ANOVA of ``dv`` (one value per participant and cell) with sphericity,
    post-hoc and simple main effects."""
    import pingouin as pg

    cells = df.groupby(["participant", a, b], sort=False)[dv].mean().reset_index()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        aov = pg.rm_anova(
            cells, dv=dv, within=[a, b], subject="participant", detailed=True, effsize="np2"
        )
    # sphericity per effect from the contrasts (pingouin's interaction epsilon is
    # approximate when both factors have more than two levels; it has no Mauchly there)
    la, lb = list(dict.fromkeys(cells[a])), list(dict.fromkeys(cells[b]))
    pids = list(dict.fromkeys(cells["participant"]))
    arr = (
        cells.set_index(["participant", a, b])[dv]
        .reindex([(p, x, y) for p in pids for x in la for y in lb])
        .to_numpy()
        .reshape(len(pids), len(la), len(lb))
    )
    sph = {r.source: r for r in rm_anova(arr, [a, b])}
    table = []
    for rec in _clean(aov):
        src = str(rec["Source"])
        r = sph.get(src)
        row = {
            "source": src,
            "ss": rec.get("SS"),
            "df1": rec.get("DF") if "DF" in rec else rec.get("ddof1"),
            "df2": rec.get("ddof2") or (r.df2 if r else None),
            "f": rec.get("F"),
            "p": rec.get("p-unc"),
            "np2": rec.get("np2"),
            "note": None,
        }
        if r is not None:
            row.update(
                {
                    "df1": r.df1,
                    "df2": r.df2,
                    "eps_gg": _num(r.eps_gg),
                    "p_gg": _num(r.p_gg),
                    "mauchly_w": _num(r.mauchly_w),
                    "mauchly_p": _num(r.mauchly_p),
                    "sphericity": r.sphericity,
                }
            )
            if r.undefined:  # pingouin divides by a zero error term: inf or NaN, p 0
                row.update(f=None, p=None, p_gg=None, np2=_num(r.np2))
                row["note"] = f"{src}: " + no_f_note(r.undefined, src, None)
            row["p_reported"] = row["p"] if r.sphericity == "assumed" else row["p_gg"]
        table.append(row)
    table = [r for r in table if r["source"] in sph]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = pg.pairwise_tests(cells, dv=dv, within=[a, b], subject="participant", padjust="bonf")
    keep = [c for c in ("Contrast", a, "A", "B", "T", "dof", "p-unc", "p-corr") if c in post]
    return {
        "dv": dv,
        "factors": [a, b],
        "participants": len(pids),
        "anova": table,
        "posthoc_bonferroni": posthoc(post[keep], a),
        "simple_main_effects": simple_main_effects(cells, dv, a, b)
        + simple_main_effects(cells, dv, b, a),
    }


def posthoc(post, level: str | None = None) -> list[dict[str, Any]]:
    """pingouin's pairwise tests as JSON values. A comparison with no spread (every
    participant's difference the same: pingouin's T is +-inf, or NaN when that difference
    is 0 too) has no t: T, p-unc and p-corr are None (never a p of 0) and ``note`` says
    why, naming the comparison (``level``: the column of the factor it is within)."""
    out = []
    for raw, rec in zip(post.to_dict("records"), _clean(post), strict=True):
        rec["note"] = None
        t = raw.get("T", math.nan)  # no T column at all: every score the same
        if isinstance(t, (float, np.floating)) and not math.isfinite(float(t)):
            rec.update({"T": None, "p-unc": None, "p-corr": None})
            lev = rec.get(level) if level else None
            where = f"{lev}: " if lev not in (None, "-") else ""
            a, b = rec.get("A"), rec.get("B")
            if math.isnan(float(t)):
                why = (
                    f"no difference and no spread: every participant scored the same in {a} and {b}"
                )
            else:
                why = f"no spread: every participant's {a} - {b} difference is the same"
            rec["note"] = f"{where}{a} vs {b}: {why}; t and p undefined"
        out.append(rec)
    return out


def simple_main_effects(cells, dv: str, of: str, at: str) -> list[dict[str, Any]]:
    """One-way RM-ANOVA of ``of`` at each level of ``at`` (GG-corrected p when Mauchly's
    test rejects sphericity), p Bonferroni-corrected over the levels of ``at``."""
    levels = list(dict.fromkeys(cells[at]))
    out = []
    for lev in levels:
        sub = cells[cells[at] == lev]
        pids = list(dict.fromkeys(sub["participant"]))
        lo = list(dict.fromkeys(sub[of]))
        arr = (
            sub.set_index(["participant", of])[dv]
            .reindex([(p, x) for p in pids for x in lo])
            .to_numpy()
            .reshape(len(pids), len(lo))
        )
        (r,) = rm_anova(arr, [of])
        p = r.p_reported
        out.append(
            {
                "effect": of,
                "at": f"{at} = {lev}",
                "f": _num(r.f),
                "df1": r.df1,
                "df2": r.df2,
                "eps_gg": _num(r.eps_gg),
                "p": _num(p),
                "p_bonferroni": _num(min(1.0, p * len(levels)) if math.isfinite(p) else p),
                "np2": _num(r.np2),
                "note": no_f_note(r.undefined, of, lev, arr, dv) if r.undefined else None,
            }
        )
    return out


def no_f_note(why: str, of: str, where: Any, values: Any = None, dv: str = "") -> str:
    """Why an effect of ``of`` (at the level ``where`` of the other factor, or over all
    of it: None) has no F and no p (``rmanova``: ``no variance``, ``no error variance``):
    one line naming the cell. ``values``: the subjects x levels array, to say the one
    value every participant had."""
    cell = f" in {where}" if where is not None else ""
    if " * " in of:  # an interaction: the differences along one factor at the other's levels
        a, b = of.split(" * ", 1)
        if why == "no variance":
            return (
                f"no variance: no participant's {b} differences change with {a}; F and p undefined"
            )
        return (
            f"no error variance: every participant's {b} differences change with {a} the same "
            "way; F and p undefined (an F over zero error is no test)"
        )
    if why == "no variance":
        v = np.asarray(values, float) if values is not None else np.array([0.0, 1.0])
        if v.size and np.ptp(v) == 0:
            same = f"{100 * v.flat[0]:.0f} %" if dv == "accuracy" else f"{v.flat[0]:g}"
            what = f"every participant scored the same{cell} ({same} in every {of})"
        else:
            what = f"each participant scored the same in every {of}{cell}"
        return f"no variance: {what}; F and p undefined"
    return (
        f"no error variance: every participant shows the same differences between {of} "
        f"levels{cell}; F and p undefined (an F over zero error is no test)"
    )


# --------------------------------------------------------------------------- knob
def knob(study: Study) -> dict[str, Any]:
    """Knob measures by condition x sectors x distance, their three-way RM-ANOVA, and
    the questionnaire's one-way RM-ANOVA per category."""
    import pingouin as pg

    df = study.trials.copy()
    for k in ("sectors", "distance_deg"):
        if k not in df:
            df[k] = [s.get(k) for s in df["stimulus"]]
        df[k] = df[k].map(_level)
    df = in_protocol_order(df, study, KNOB_FACTORS)
    out: dict[str, Any] = {"measures": {}, "questionnaire": {}}
    want = design_counts(study, KNOB_FACTORS, None)
    for m in KNOB_MEASURES:
        if m not in df:
            out["measures"][m] = {"skipped": f"no {m} column in the trials"}
            continue
        d = df[df[m].notna()].assign(**{m: lambda x, m=m: x[m].astype(float)})
        desc = (
            d.groupby(list(KNOB_FACTORS), sort=False)[m]
            .agg(["mean", "std", "count"])
            .reset_index()
            .rename(columns={"std": "sd", "count": "trials"})
        )
        res: dict[str, Any] = {"by_cell": _clean(desc)}
        res["by_condition"] = _clean(
            d.groupby("condition", sort=False)[m].agg(["mean", "std"]).reset_index()
        )
        # recovery time exists only for trials with an overshoot: a mean per cell over
        # those, every participant needs at least one in every cell
        exact = m != "recovery_time_s"
        why = balance_problem(
            d, KNOB_FACTORS, want, exact=exact, participants=list(study.plans), words=study.words
        )
        if why and not exact:
            why = (
                "recovery time exists only after an overshoot, and "
                + why.split(";")[0].replace("missing cells", "these cells had none")
                + "; the three-way ANOVA needs one in every cell of every participant "
                "(the means above use the trials that had one)"
            )
        if why:
            res["anova"] = {"skipped": f"{m}: {why}"}
        else:
            cells = d.groupby(["participant", *KNOB_FACTORS])[m].mean()
            pids = sorted(set(d["participant"]))
            levels = [sorted(set(d[f]), key=_order) for f in KNOB_FACTORS]
            idx = [
                (p, a, b, c) for p in pids for a in levels[0] for b in levels[1] for c in levels[2]
            ]
            arr = cells.reindex(idx).to_numpy().reshape(len(pids), *map(len, levels))
            rows = []
            for r in rm_anova(arr, list(KNOB_FACTORS)):
                why = r.undefined and f"{m}: {r.source}: " + no_f_note(r.undefined, r.source, None)
                rows.append({**r.as_dict(), "note": why or None})
            res["anova"] = {
                "participants": len(pids),
                "rows": rows,
                "posthoc_bonferroni": _main_effect_pairs(cells.reset_index(), m),
            }
        out["measures"][m] = res
    q = study.questionnaire
    if q is None or q.empty:
        out["questionnaire"] = {"skipped": "no questionnaire answers in the runs"}
        return out
    q = in_protocol_order(q.assign(score=q["score"].astype(float)), study, ("condition",))
    cat = (
        q.groupby(["participant", "category", "condition"], sort=False)["score"]
        .mean()
        .reset_index()
    )
    for c, sub in cat.groupby("category", sort=False):
        counts = sub.groupby("participant")["condition"].nunique()
        ncond = sub["condition"].nunique()
        res = {
            "by_condition": _clean(
                sub.groupby("condition", sort=False)["score"].agg(["mean", "std"]).reset_index()
            )
        }
        lacking = counts[counts < ncond]
        if len(lacking) or sub["participant"].nunique() < 2:
            res["anova"] = {
                "skipped": (
                    f"{c}: {', '.join(lacking.index)} rated only {int(lacking.min())} of "
                    f"{ncond} conditions; finish those runs or {study.words.exclude}"
                    if len(lacking)
                    else f"{c}: one participant: an ANOVA needs at least two"
                )
            }
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                aov = pg.rm_anova(
                    sub,
                    dv="score",
                    within="condition",
                    subject="participant",
                    correction=True,
                    detailed=True,
                    effsize="np2",
                )
                post = pg.pairwise_tests(
                    sub, dv="score", within="condition", subject="participant", padjust="bonf"
                )
            res["anova"] = _clean(aov)
            # sphericity as for the other effects (pingouin tests it even with fewer
            # participants than conditions, where Mauchly's test is not defined)
            conds = list(dict.fromkeys(sub["condition"]))
            pids = list(dict.fromkeys(sub["participant"]))
            arr = (
                sub.set_index(["participant", "condition"])["score"]
                .reindex([(p, x) for p in pids for x in conds])
                .to_numpy()
                .reshape(len(pids), len(conds))
            )
            (r,) = rm_anova(arr, ["condition"])
            top = res["anova"][0]
            top.update(
                {
                    "sphericity": r.sphericity,
                    "mauchly_p": _num(r.mauchly_p),
                    "eps_gg": _num(r.eps_gg),
                    "p_gg": _num(r.p_gg),
                    "p_reported": _num(r.p_reported),
                    "note": None,
                }
            )
            if r.undefined:  # pingouin's F over a zero error term: inf or NaN, p 0
                for k in ("F", "p-unc", "p-GG-corr"):
                    if k in top:
                        top[k] = None
                top["np2"] = _num(r.np2)
                top["note"] = f"questionnaire {c}: " + no_f_note(
                    r.undefined, "condition", None, arr
                )
            res["posthoc_bonferroni"] = posthoc(
                post[[k for k in ("A", "B", "T", "p-unc", "p-corr") if k in post]]
            )
        out["questionnaire"][str(c)] = res
    return out


def _main_effect_pairs(cells, dv: str) -> list[dict[str, Any]]:
    """Bonferroni-corrected paired t-tests between the levels of each knob factor, on
    each participant's mean over the other factors."""
    import pingouin as pg

    out = []
    for f in KNOB_FACTORS:
        marg = cells.groupby(["participant", f])[dv].mean().reset_index()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            post = pg.pairwise_tests(marg, dv=dv, within=f, subject="participant", padjust="bonf")
        for rec in posthoc(post[[k for k in ("A", "B", "T", "p-unc", "p-corr") if k in post]]):
            out.append({"factor": f, **rec})
    return out


def _order(v: Any) -> tuple:
    return (0, v, "") if isinstance(v, (int, float)) else (1, 0, str(v))


# --------------------------------------------------------------------------- all
def analyze(study: Study) -> dict[str, Any]:
    """The analysis as JSON values (``--json``)."""
    res: dict[str, Any] = {
        "experiment": study.experiment,
        "participants": sorted(study.participants),
        "simulated": sorted(p for p, d in study.participants.items() if d.get("simulated")),
        "notes": list(study.notes),
    }
    if study.experiment == "knob":
        res["knob"] = knob(study)
        return res
    if study.experiment not in FACTORS:
        raise UserError(f"experiment {study.experiment!r}: the analysis knows exp1, exp2 and knob")
    res["accuracy"] = accuracy(study)
    a, b = FACTORS[study.experiment]
    df = study.trials
    main = in_protocol_order(df[df["phase"] == "main"], study, (a, b))
    main = main.assign(correct=main["correct"].astype(float))
    want = design_counts(study, (a, b), "main")
    why = balance_problem(main, (a, b), want, participants=list(study.plans), words=study.words)
    single = [f for f in (a, b) if main[f].nunique() < 2]
    if single and not why:
        why = f"{single[0]} has one level ({main[single[0]].iloc[0]}); nothing to compare"
    if why:
        res["anova"] = {"skipped": f"ANOVA {a} x {b}: not run: {why}"}
    else:
        res["anova"] = two_way(main.assign(accuracy=main["correct"]), "accuracy", a, b)
    return res
