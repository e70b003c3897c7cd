"""The analysis as one self-contained HTML page (``study analyze --report out.html``):
the tables of ``analysis.analyze`` and figures (matplotlib, Agg, embedded as PNG):
accuracy per direction and per region or pair with standard errors (as the paper's
Fig. 13) and per cell; the knob's measures by sectors x distance per condition; the
questionnaire's category scores per condition (as Fig. 17)."""

from __future__ import annotations

import base64
import html
import io
import math
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import UserError, write_text_atomic


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    import matplotlib.pyplot as plt

    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _bars(ax, rows: list[dict], key: str, title: str) -> None:
    labels = [str(r[key]) for r in rows]
    means = [r["accuracy_pct"] for r in rows]
    sem = [r["sem_pct"] or 0.0 for r in rows]
    ax.bar(labels, means, yerr=sem, capsize=4, color="#4878a8")
    ax.set_ylim(0, 105)
    ax.set_ylabel("correct (%)")
    ax.set_title(title)
    for i, m in enumerate(means):
        ax.text(i, min(m + 3, 101), f"{m:.1f}", ha="center", fontsize=8)


def accuracy_figures(res: dict[str, Any]) -> list[tuple[str, str]]:
    """(caption, base64 PNG): per direction and per place (Fig. 13), per cell."""
    plt = _plt()
    acc = res["accuracy"]
    place = "region" if "by_region" in acc else "pair"
    fig, axs = plt.subplots(1, 2, figsize=(9, 3.4))
    _bars(axs[0], acc["by_direction"], "direction", "(a) per direction")
    _bars(axs[1], acc[f"by_{place}"], place, f"(b) per {place}")
    out = [(f"Correct responses per direction and per {place} (mean, SEM bars)", _png(fig))]
    out.append((f"Correct responses per {place} and direction", _png(cells_figure(acc, place))))
    return out


def cells_figure(acc: dict[str, Any], place: str):
    """Accuracy per place and direction: a bar per cell, grouped by place (the protocol's
    order), the legend below the axes where it covers no bar."""
    plt = _plt()
    cells = acc["cells"]
    places = list(dict.fromkeys(c[place] for c in cells))
    dirs = list(dict.fromkeys(c["direction"] for c in cells))
    fig, ax = plt.subplots(figsize=(9, 3.6), layout="constrained")
    width = 0.8 / max(1, len(dirs))
    for j, d in enumerate(dirs):
        xs = np.arange(len(places)) + (j - (len(dirs) - 1) / 2) * width
        m = [
            next(
                (c["accuracy_pct"] for c in cells if c[place] == p and c["direction"] == d), np.nan
            )
            for p in places
        ]
        e = [
            next(((c["sem_pct"] or 0) for c in cells if c[place] == p and c["direction"] == d), 0)
            for p in places
        ]
        ax.bar(xs, m, width, yerr=e, capsize=2, label=d)
    ax.set_xticks(np.arange(len(places)), places)
    ax.set_ylim(0, 105)
    ax.set_ylabel("correct (%)")
    _legend_below(ax, len(dirs))
    return fig


def _legend_below(ax, n: int) -> None:
    """The legend in one row below the axes and their tick labels (the figure's
    constrained layout makes room): bars reach the top, a legend inside covers them."""
    ax.figure.legend(loc="outside lower center", ncols=max(1, n), fontsize=8, frameon=False)


def knob_figures(res: dict[str, Any]) -> list[tuple[str, str]]:
    plt = _plt()
    out = []
    meas = res["knob"]["measures"]
    for m, r in meas.items():
        cells = r.get("by_cell")
        if not cells:
            continue
        conds = list(dict.fromkeys(c["condition"] for c in cells))
        fig, axs = plt.subplots(1, len(conds), figsize=(3 * len(conds), 3), sharey=True)
        axs = np.atleast_1d(axs)
        for ax, cond in zip(axs, conds, strict=True):
            sub = [c for c in cells if c["condition"] == cond]
            for dist in sorted({c["distance_deg"] for c in sub}):
                pts = sorted((c["sectors"], c["mean"]) for c in sub if c["distance_deg"] == dist)
                ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=f"{dist:g} deg")
            ax.set_title(cond)
            ax.set_xlabel("sectors")
            ax.set_xscale("log", base=2)
            ticks = sorted({c["sectors"] for c in sub})
            ax.set_xticks(ticks, [str(t) for t in ticks])
            ax.minorticks_off()
        axs[0].set_ylabel(m)
        axs[-1].legend(fontsize=7)
        out.append((f"Knob: {m} by sectors and distance, per condition", _png(fig)))
    q = res["knob"].get("questionnaire", {})
    cats = [c for c, v in q.items() if isinstance(v, dict) and "by_condition" in v]
    if cats:
        conds = list(dict.fromkeys(r["condition"] for c in cats for r in q[c]["by_condition"]))
        fig, ax = plt.subplots(figsize=(max(6, 1.4 * len(cats)), 3.6), layout="constrained")
        width = 0.8 / len(conds)
        for j, cond in enumerate(conds):
            xs = np.arange(len(cats)) + (j - (len(conds) - 1) / 2) * width
            m = [
                next((r["mean"] for r in q[c]["by_condition"] if r["condition"] == cond), np.nan)
                for c in cats
            ]
            ax.bar(xs, m, width, label=cond)
        ax.set_xticks(np.arange(len(cats)), cats, rotation=20, ha="right", fontsize=8)
        ax.set_ylim(1, 7)
        ax.set_ylabel("score (1-7)")
        _legend_below(ax, len(conds))
        out.append(("Questionnaire: mean score per category and condition (as Fig. 17)", _png(fig)))
    return out


def _fmt(v: Any) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        if not math.isfinite(v):
            return "-"
        return f"{v:.3g}" if abs(v) < 1e-3 or abs(v) >= 1e4 else f"{v:.3f}".rstrip("0").rstrip(".")
    return html.escape(str(v))


def table(rows: list[dict], cols: list[str] | None = None) -> str:
    if not rows:
        return "<p>(none)</p>"
    cols = cols or list(rows[0])
    head = "".join(f"<th>{html.escape(c)}</th>" for c in cols)
    body = "".join(
        "<tr>" + "".join(f"<td>{_fmt(r.get(c))}</td>" for c in cols) + "</tr>" for r in rows
    )
    return f"<table><tr>{head}</tr>{body}</table>"


def _skipped(x: Any) -> str:
    return f'<p class="skip">{html.escape(x["skipped"])}</p>'


ANOVA_COLS = [
    "source",
    "df1",
    "df2",
    "f",
    "p",
    "np2",
    "mauchly_w",
    "mauchly_p",
    "sphericity",
    "eps_gg",
    "p_gg",
    "p_reported",
    "note",
]


def render(res: dict[str, Any], title: str = "") -> str:
    """The report's HTML."""
    parts = [f"<h1>{html.escape(title or 'Study ' + res['experiment'])}</h1>"]
    parts.append(
        f"<p>Experiment <b>{html.escape(res['experiment'])}</b>, "
        f"{len(res['participants'])} participant(s): {html.escape(', '.join(res['participants']))}"
        + (f" (simulated: {html.escape(', '.join(res['simulated']))})" if res["simulated"] else "")
        + "</p>"
    )
    for n in res.get("notes", []):
        parts.append(f'<p class="note">{html.escape(n)}</p>')
    figs: list[tuple[str, str]] = []
    if "accuracy" in res:
        acc = res["accuracy"]
        overall = acc["overall_pct"]
        said = acc.get("main_phase") if overall is None else f"{overall:.1f} %"
        parts.append(f"<h2>Accuracy</h2><p>Overall (main phase): {html.escape(str(said))}</p>")
        if acc.get("practice"):
            practice = ", ".join(f"{k} {v:.1f} %" for k, v in acc["practice"].items())
            parts.append(f"<p>Practice phases (apart): {html.escape(practice)}</p>")
        place = "region" if "by_region" in acc else "pair"
        figs = accuracy_figures(res) if overall is not None else []
        for cap, png in figs[:1]:
            parts.append(_fig(cap, png))
        parts.append("<h3>Per participant</h3>" + table(acc["participants"]))
        parts.append("<h3>Per direction</h3>" + table(acc["by_direction"]))
        parts.append(f"<h3>Per {place}</h3>" + table(acc[f"by_{place}"]))
        for cap, png in figs[1:]:
            parts.append(_fig(cap, png))
        parts.append(f"<h3>Per {place} and direction</h3>" + table(acc["cells"]))
        aov = res["anova"]
        parts.append("<h2>Two-way repeated-measures ANOVA</h2>")
        if "skipped" in aov:
            parts.append(_skipped(aov))
        else:
            parts.append(
                f"<p>{' x '.join(aov['factors'])} on accuracy, {aov['participants']} "
                "participants; Mauchly's test per effect; p reported Greenhouse-Geisser "
                "corrected unless sphericity holds.</p>"
            )
            parts.append(table(aov["anova"], ANOVA_COLS))
            parts.append("<h3>Simple main effects (Bonferroni over levels)</h3>")
            parts.append(table(aov["simple_main_effects"]))
            parts.append("<h3>Post-hoc pairwise t-tests (Bonferroni)</h3>")
            parts.append(table(aov["posthoc_bonferroni"]))
    if "knob" in res:
        k = res["knob"]
        figs = knob_figures(res)
        parts.append("<h2>Knob</h2>")
        for m, r in k["measures"].items():
            parts.append(f"<h3>{html.escape(m)}</h3>")
            if "skipped" in r:
                parts.append(_skipped(r))
                continue
            parts.append(table(r["by_condition"]))
            a = r["anova"]
            if "skipped" in a:
                parts.append(_skipped(a))
            else:
                parts.append(
                    f"<p>Three-way RM-ANOVA, {a['participants']} participants:</p>"
                    + table(a["rows"], ANOVA_COLS)
                    + "<p>Post-hoc pairwise t-tests per factor (Bonferroni):</p>"
                    + table(a.get("posthoc_bonferroni", []))
                )
        for cap, png in figs:
            parts.append(_fig(cap, png))
        parts.append("<h2>Questionnaire (one-way RM-ANOVA per category)</h2>")
        q = k["questionnaire"]
        if "skipped" in q:
            parts.append(_skipped(q))
        else:
            for c, r in q.items():
                parts.append(f"<h3>{html.escape(c)}</h3>" + table(r["by_condition"]))
                parts.append(_skipped(r["anova"]) if "skipped" in r["anova"] else table(r["anova"]))
                if "posthoc_bonferroni" in r:
                    parts.append(table(r["posthoc_bonferroni"]))
    style = (
        "body{font-family:sans-serif;max-width:70em;margin:1em auto}"
        "table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #bbb;"
        "padding:2px 6px;font-size:90%;text-align:right}.skip{color:#a00}.note{color:#555}"
    )
    return (
        "<!doctype html><html><head><meta charset='utf-8'>"
        f"<title>{html.escape(title or res['experiment'])}</title><style>{style}</style>"
        f"</head><body>{''.join(parts)}</body></html>"
    )


def _fig(caption: str, png: str) -> str:
    return (
        f"<figure><img alt='{html.escape(caption)}' src='data:image/png;base64,{png}'>"
        f"<figcaption>{html.escape(caption)}</figcaption></figure>"
    )


def write(res: dict[str, Any], path: Path, title: str = "") -> Path:
    """Write the report (atomically: the old file or the new one, never half)."""
    path = Path(path).expanduser()
    if path.parent and not path.parent.is_dir():
        raise UserError(f"--report {path}: folder {path.parent} does not exist; create it first")

    write_text_atomic(path, render(res, title))
    return path
