"""The analysis in a few lines and one ANOVA table: what the Studies screen shows after
``analyse`` (``analysis.analyze``'s result; the HTML report has the rest)."""

from __future__ import annotations

import math
from typing import Any

#: The ANOVA table's columns: the effect, F with its degrees of freedom, the p to report
#: (Greenhouse-Geisser corrected unless sphericity holds), Mauchly's verdict, epsilon,
#: partial eta squared.
COLUMNS = ("effect", "F (df)", "p", "sphericity", "eps GG", "np2")


def _num(v: Any, fmt: str = ".2f") -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return format(v, fmt)


def _p(v: Any) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return "< .001" if v < 0.001 else f"{v:.3f}"


def _df(v: Any) -> str:
    return _num(v, "g") if v is not None else "-"


def _row(effect: str, r: dict[str, Any], p: Any) -> tuple[str, ...]:
    corrected = r.get("sphericity") not in (None, "assumed")
    return (
        effect,
        f"{_num(r.get('f'))} ({_df(r.get('df1'))}, {_df(r.get('df2'))})",
        _p(p) + (" GG" if corrected and p is not None else ""),
        str(r.get("sphericity") or "-"),
        _num(r.get("eps_gg")),
        _num(r.get("np2"), ".3f"),
    )


def anova_rows(res: dict[str, Any]) -> list[tuple[str, ...]]:
    """The rows of every ANOVA in ``res`` (``COLUMNS``); an ANOVA not run gives none."""
    rows: list[tuple[str, ...]] = []
    aov = res.get("anova")
    if isinstance(aov, dict) and "anova" in aov:
        for r in aov["anova"]:
            rows.append(_row(str(r["source"]), r, r.get("p_reported", r.get("p"))))
    knob = res.get("knob") or {}
    for measure, m in (knob.get("measures") or {}).items():
        a = m.get("anova", m)
        for r in a.get("rows", []):
            rows.append(_row(f"{measure}: {r['source']}", r, r.get("p_reported")))
    q = knob.get("questionnaire") or {}
    for cat, c in q.items() if "skipped" not in q else ():
        a = c.get("anova") if isinstance(c, dict) else None
        if isinstance(a, list) and a:
            top = a[0]
            r = {
                "f": top.get("F"),
                "df1": top.get("DF"),
                "df2": a[1].get("DF") if len(a) > 1 else None,
                "np2": top.get("np2"),
                "eps_gg": top.get("eps_gg"),
                "sphericity": top.get("sphericity"),
            }
            rows.append(_row(f"questionnaire {cat}: condition", r, top.get("p_reported")))
    return rows


def undefined_notes(aov: dict[str, Any]) -> list[str]:
    """Why a row of a two-way ANOVA (its table, simple main effects, post-hoc tests) has
    no F, t or p: one line each."""
    notes = [r["note"] for r in aov.get("anova", []) if r.get("note")]
    notes += [
        f"simple main effect of {r['effect']} at {r['at']}: {r['note']}"
        for r in aov.get("simple_main_effects", [])
        if r.get("note")
    ]
    post = [r["note"] for r in aov.get("posthoc_bonferroni", []) if r.get("note")]
    if len(post) > 3:  # often every pair of a constant cell: the report lists them all
        post = [*post[:2], f"and {len(post) - 2} more post-hoc comparisons without spread"]
    return notes + post


def headline(res: dict[str, Any]) -> list[str]:
    """Who was analysed, the overall accuracy, and every note or ANOVA not run."""
    who = res["participants"]
    sim = len(res.get("simulated", []))
    lines = [
        f"{res['experiment']}: {len(who)} participant(s) ({', '.join(who)})"
        + (f", {sim} simulated" if sim else "")
    ]
    acc = res.get("accuracy")
    if acc:
        part = "; ".join(
            f"{r['participant']} "
            + ("no main-phase trial" if r["accuracy_pct"] is None else f"{r['accuracy_pct']:.1f} %")
            for r in acc.get("participants", [])
        )
        overall = acc["overall_pct"]
        if overall is None:
            practice = "; ".join(f"{ph} {v:.1f} %" for ph, v in acc.get("practice", {}).items())
            lines.append(
                f"accuracy: {acc.get('main_phase')}"
                + (f" (practice: {practice})" if practice else "")
            )
        else:
            lines.append(f"accuracy {overall:.1f} %" + (f" ({part})" if part else ""))
    lines += list(res.get("notes", []))
    aov = res.get("anova")
    if isinstance(aov, dict) and "skipped" in aov:
        lines.append(aov["skipped"])
    elif isinstance(aov, dict):
        lines += undefined_notes(aov)
    knob = res.get("knob") or {}
    for m in (knob.get("measures") or {}).values():
        a = m.get("anova", m)
        if "skipped" in a:
            lines.append(a["skipped"])
        lines += [r["note"] for r in a.get("rows", []) if r.get("note")]
    q = knob.get("questionnaire") or {}
    if "skipped" in q:
        lines.append(q["skipped"])
    else:
        for cat, c in q.items():
            a = c.get("anova") if isinstance(c, dict) else None
            if isinstance(a, dict) and "skipped" in a:
                lines.append(f"questionnaire {cat}: {a['skipped']}")
            elif isinstance(a, list) and a and a[0].get("note"):
                lines.append(a[0]["note"])
    return lines


def screen_lines(res: dict[str, Any]) -> tuple[str, list[str]]:
    """What the Studies screen shows around its ANOVA table at 80 x 24: a title line (who,
    the accuracy) and the notes, those about the ANOVA first (a test not run, an effect
    without F), then the runs' notes and each participant's accuracy."""
    who = res["participants"]
    sim = len(res.get("simulated", []))
    title = f"{res['experiment']}: {len(who)} participant(s)" + (
        f", {sim} simulated" if sim else ""
    )
    acc = res.get("accuracy")
    lines = headline(res)
    if acc:
        overall = acc["overall_pct"]
        title += (
            f"; accuracy: {acc.get('main_phase')}"
            if overall is None
            else f"; accuracy {overall:.1f} %"
        )
    run_notes = list(res.get("notes", []))
    notes = [x for x in lines[2 if acc else 1 :] if x not in run_notes] + run_notes
    if acc:
        notes.append(lines[1].replace("accuracy", "accuracy (main phase)", 1))
    notes.append("participants: " + ", ".join(who))
    return title, notes
