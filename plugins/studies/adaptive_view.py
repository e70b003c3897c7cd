"""The Studies screen's plot of an adaptive run: one track at a time (a frequency x
waveform), its level (dB) against the track's trials, correct answers ``+``, wrong ones
``x``, reversals ``◆`` and the estimate as a line; above it one line: which track, its
trials, the estimate (staircase: the mean of the last reversals so far; QUEST+: the
posterior's mean and 95 % interval). For QUEST+ on a wide screen (>= ``WIDE`` columns)
the posterior's marginal over threshold is drawn beside it.

Presentation only: ``snapshot(d)`` takes what ``adaptive_console`` reports (``tracks``:
all of them, ``track``: the one just answered, ``start`` / ``paused``: the trial in play
or next) and redraws then, never on a timer. The plot follows the track of the trial in
play (the one the status names) until ``[`` / ``]`` (``cycle``) picks one; then a second
line says where the run is (its track and trial), whole at 80 columns.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from textual.app import ComposeResult
from textual.containers import Horizontal, Vertical
from textual.widgets import Static

from console.plugin_api.tui import Chart, Series

#: columns from which a QUEST+ track's posterior marginal is drawn beside its levels
WIDE = 110
#: rows from which the levels plot has its own title and a legend (else the line above
#: names the track, the help the marks)
TALL = 14


def next_view(current: str, has_plot: bool) -> str:
    """The view ``t`` shows after ``current``: trials and the plot of an adaptive run
    (which has no ANOVA analysis), else trials and the analysis (``n`` shows it too)."""
    order = ["trials", "plot" if has_plot else "analysis"]
    return order[(order.index(current) + 1) % 2] if current in order else order[0]


def track_title(v: dict[str, Any]) -> str:
    """``sine_60Hz (3/16)``: the protocol's name of the track, as the status says it."""
    return f"{v['track']} ({v['index'] + 1}/{v['count']})"


def estimate_text(v: dict[str, Any]) -> str:
    """The track's estimate now, in words."""
    est = v.get("estimate_db")
    unit = "dB" if v["measure"] == "detection" else "dB over the reference"
    if v["method"] == "quest+":
        if est is None:
            return "no answer yet"
        lo, hi = v["ci_db"]
        return f"threshold {est:.1f} {unit} (posterior mean, 95 % {lo:.0f}..{hi:.0f})"
    n = len(v["reversals"])
    if est is None:
        return f"{n} reversal{'' if n == 1 else 's'}: no estimate before 2"
    return f"threshold {est:.1f} {unit} (mean of {v['used_reversals']} reversals; {n} so far)"


def head_text(v: dict[str, Any]) -> str:
    """The line above the plot."""
    n = len(v["levels"])
    state = f"done after {n} trials" if v["done"] else f"{n}/{v['max_trials']} trials"
    return f"{track_title(v)}: {state}, {estimate_text(v)}"


class LevelsChart(Chart):
    """A track's levels per trial: the staircase line, ``+`` correct, ``x`` wrong, ``◆``
    reversals and the estimate (a horizontal line)."""

    def show(self, v: dict[str, Any]) -> None:
        self.view = v
        x = np.arange(1, len(v["levels"]) + 1, dtype=float)
        if not x.size:
            self.title = track_title(v)
            self.clear(f"{track_title(v)}: no trial yet")
            return
        self.set_series([Series("level", x, np.asarray(v["levels"], float))], title=track_title(v))

    def render(self):  # noqa: ANN201 - Textual's RenderResult
        if not self.series:
            return super().render()
        v = self.view
        plt = self.plt
        plt.clear_figure()
        tall = self.size.height >= TALL  # a title and a legend only where rows are left
        if tall:
            plt.title(self.title)  # the line above says it at 80 x 24
        plt.xlabel(self.x_axis_label)
        plt.ylabel(self.y_axis_label)
        lv = np.asarray(v["levels"], float)
        x = np.arange(1, lv.size + 1, dtype=float)
        ok = np.asarray(v["correct"], bool)
        est = v.get("estimate_db")
        top = max(lv.max(), est if est is not None else -np.inf)
        bottom = min(lv.min(), est if est is not None else np.inf)
        lo, hi = math.floor(bottom) - 1, math.ceil(top) + 1
        step = max(1, math.ceil((hi - lo) / 4))  # whole dB, at most 5 ticks
        plt.ylim(lo, hi)
        plt.yticks(list(range(lo, hi + 1, step)))
        n = max(x.size, 2)
        plt.xlim(0.5, n + 0.5)
        plt.xticks(np.unique(np.linspace(1, n, min(n, 8)).round()).tolist())
        plt.plot(x.tolist(), lv.tolist(), color="gray", marker="braille")
        legend = []  # below the plot (Chart.figure_and_legend), never on it
        if ok.any():
            plt.scatter(
                x[ok].tolist(),
                lv[ok].tolist(),
                marker="+",
                color="green",
            )
            legend.append(("correct", "green", "+"))
        if (~ok).any():
            plt.scatter(
                x[~ok].tolist(),
                lv[~ok].tolist(),
                marker="x",
                color="red",
            )
            legend.append(("wrong", "red", "x"))
        rev = [i for i in v["reversals"] if i < lv.size]
        if rev:
            plt.scatter(
                x[rev].tolist(),
                lv[rev].tolist(),
                marker="◆",
                color="yellow",
            )
            legend.append(("reversal", "yellow", "◆"))
        if est is not None:
            plt.hline(est, "cyan")
        return self.figure_and_legend(legend if tall else [])


class AdaptiveView(Vertical):
    """The plot of an adaptive run (hidden until one starts)."""

    DEFAULT_CSS = """
    AdaptiveView { height: 1fr; display: none; }
    AdaptiveView #adaptive-head { height: auto; text-wrap: nowrap; text-overflow: ellipsis; }
    AdaptiveView #adaptive-charts { height: 1fr; }
    AdaptiveView #adaptive-posterior { width: 40%; display: none; }
    """

    def __init__(self, **kw: Any) -> None:
        super().__init__(**kw)
        self.tracks: dict[str, dict[str, Any]] = {}
        self.order: list[str] = []
        self.current = 0
        self.follow = True  # the newest trial's track, until [ or ] picks one
        self.picked: str | None = None  # the track [ or ] picked (kept over a resume)
        self.running: str | None = None  # the track of the trial in play (else answered)
        self.trial: int | None = None  # the number of the trial in play (1 = the first)

    def compose(self) -> ComposeResult:
        yield Static("", id="adaptive-head", markup=False)
        with Horizontal(id="adaptive-charts"):
            yield LevelsChart(x_label="trial of the track", y_label="level", y_unit="dB")
            yield Chart(
                id="adaptive-posterior",
                x_label="threshold",
                x_unit="dB",
                y_label="posterior",
            )

    @property
    def has_plot(self) -> bool:
        return bool(self.order)

    def reset(self) -> None:
        """A new run: nothing drawn until its tracks come."""
        self.tracks, self.order, self.current = {}, [], 0
        self.follow, self.running = self.picked is None, None  # a pick stays until [ ]
        self.trial = None
        self.query_one("#adaptive-head", Static).update("")
        self.query_one(LevelsChart).clear("waiting for the run's tracks")

    def snapshot(self, d: dict[str, Any]) -> None:
        """``tracks`` (all of them), ``track`` (one, just answered) or ``start`` /
        ``paused`` (the trial in play or next, ``trial_row``'s): redraw."""
        if d.get("kind") in ("start", "paused"):
            t = d.get("trial")
            if isinstance(t, dict) and t.get("phase") in self.tracks:
                self._in_play(str(t["phase"]), int(t["index"]) + 1)
            return
        if d.get("kind") == "tracks":
            self.tracks = {v["track"]: v for v in d["tracks"]}
            self.order = list(self.tracks)
            if self.picked not in self.tracks:  # another protocol's: the run is followed
                self.picked, self.follow = None, True
            self.current = self.order.index(self.picked) if self.picked else 0
        elif d.get("kind") == "track":
            v = d["track"]
            if v["track"] not in self.tracks:
                self.order.append(v["track"])
            self.tracks[v["track"]] = v
            moved, self.running = self.running != v["track"], v["track"]
            if self.follow:
                self.current = self.order.index(v["track"])
            elif self.order[self.current] != v["track"]:
                if moved:  # the line above says where the run is now
                    self.draw()
                return  # another track than the one picked: the plot stays on it
        self.draw()

    def _in_play(self, track: str, trial: int) -> None:
        """The run plays (or stands before) ``trial`` of ``track``: followed, or said on
        the line above a track picked."""
        self.running, self.trial = track, trial
        if self.follow:
            self.current = self.order.index(track)
        self.draw()

    def run_stopped(self) -> None:
        """The run stopped: no line says where it is any more (a pick stays shown)."""
        self.running = self.trial = None
        self.draw()

    def where_run_is(self) -> str:
        """The line saying where the run is, while a track it is not on is picked."""
        v = self.tracks.get(self.running or "")
        if self.follow or v is None or self.running == self.order[self.current]:
            return ""
        trial = f", trial {self.trial}" if self.trial else ""
        return f"picked with [ ]: the run is on {track_title(v)}{trial} ([ ] back to it)"

    def cycle(self, step: int) -> str:
        """``[`` / ``]``: the previous / next track (the plot stops following the newest
        trial); returns what to say when there is none."""
        if not self.order:
            return "no adaptive run to plot: s starts one"
        self.current = (self.current + step) % len(self.order)
        self.picked = self.order[self.current]
        if self.picked == self.running:  # back on the run's track: it follows it again
            self.picked = None
        self.follow = self.picked is None
        self.draw()
        return ""

    def draw(self) -> None:
        if not self.order:
            return
        v = self.tracks[self.order[self.current]]
        where = self.where_run_is()
        head = head_text(v) + (f"\n{where}" if where else "")
        self.query_one("#adaptive-head", Static).update(head)
        self.query_one(LevelsChart).show(v)
        post = self.query_one("#adaptive-posterior", Chart)
        m = v.get("marginal")
        post.display = bool(m) and self.size.width >= WIDE
        if m and post.display:
            post.set_series(
                [Series("P(threshold)", np.asarray(m["threshold_db"]), np.asarray(m["p"]))],
                title="posterior over threshold",
            )

    def on_resize(self) -> None:
        self.draw()  # the marginal beside the levels only on a wide screen
