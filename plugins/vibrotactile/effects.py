"""The registered vibrotactile effects: ``flow``, ``hand_flow`` and ``point``.

``factory(profile)`` reads ``[vibrotactile]``, ``[perception]``, ``[audio]
sample_rate_hz`` and the safety ``[limits]`` once; ``render(**request) -> OutputPlan``
(volts at the piezo). Tables, pair answers and flow-under-hand maps are built only when
asked for and cached on disk (``[vibrotactile] cache_dir``; ``lazy``/``cache``), plans
in memory per effect object.

The request vocabulary, shared by the three effects:

- the map: ``vmap`` = a vibration-map file, a tables file or a ``VibrationMap``;
  ``tables`` = a ``Tables`` (its map and ranking are used) or a tables file. One of
  them is required.
- a point: a point id of the map (``int``, the measurement's node number) or ``(x, y)`` in mm.
- ``name``: the plan's name (default: a description of the request).

Consumers (scenes, demos, benchmarks) reach these only through
``plugins.get("effect", name).factory(profile)``.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from console.errors import UserError
from console.types import OutputPlan
from console.vibration_map import VibrationMap

Progress = Callable[[int, int, str], None]  # (done, total, what)


@dataclass(frozen=True)
class Setup:
    """What every vibrotactile effect reads from the profile."""

    settings: Any  # stimuli.StimulusSettings
    perception: Any  # perception.Perception
    piezo_min_v: float
    piezo_max_v: float
    band_hz: float
    min_contrast_db: float
    cache_dir: Path | None
    hand: dict = field(default_factory=dict)  # hand_mm, squares, subgrid
    max_plan_s: float = 3600.0  # [limits] max_plan_s: longer plans are refused unbuilt
    table_rule: str = "paper"  # [vibrotactile] table_rule: perceptual or paper
    perceptual: Any = None  # perceptual.PerceptualRule of the profile
    map_error_rel: float = 0.05  # [vibrotactile] map_error_rel (independent patches)
    method: str = "paper"  # [vibrotactile] method, "auto" resolved for the profile

    def rule_of(self, min_contrast_db: float | None, rule: str | None) -> tuple[float, Any]:
        """(min_contrast_db, PerceptualRule or None) of a request. An explicit
        ``min_contrast_db`` (0 included) without ``rule`` selects the paper's rule, as
        before there were two; nothing given: the profile's ``min_contrast_db`` (> 0:
        the paper's rule with that floor) else its ``table_rule``."""
        if rule is None:
            if min_contrast_db is not None:
                return float(min_contrast_db), None
            if self.min_contrast_db > 0:
                return self.min_contrast_db, None
            rule = self.table_rule
        if rule == "paper":
            c = self.min_contrast_db if min_contrast_db is None else float(min_contrast_db)
            return c, None
        if rule != "perceptual":
            raise UserError(f"table rule {rule!r}: give 'perceptual' or 'paper'")
        if min_contrast_db:
            raise UserError(
                f"min_contrast_db {min_contrast_db:g} applies to the paper's rule only; the "
                "perceptual rule weighs contrast itself"
            )
        if self.perceptual is None:
            raise UserError("perceptual tables need the profile's rule (setup_from_profile)")
        return 0.0, self.perceptual

    @property
    def cap_v(self) -> float:
        from plugins.vibrotactile.stimuli import drive_cap_v

        return drive_cap_v(self.settings, self.piezo_min_v, self.piezo_max_v)

    @property
    def limits(self) -> dict:
        return {
            "piezo_min_v": self.piezo_min_v,
            "piezo_max_v": self.piezo_max_v,
            "max_plan_s": self.max_plan_s,
        }


def setup_from_profile(profile: Any) -> Setup:
    """Settings, perception, piezo range, band, ranking, cache and hand geometry."""
    from console.safety import Limits
    from plugins.vibrotactile.cache import default_cache_dir
    from plugins.vibrotactile.perception import Perception
    from plugins.vibrotactile.perceptual import rule_from_profile
    from plugins.vibrotactile.stimuli import StimulusSettings

    vt = profile.section("vibrotactile")
    st = StimulusSettings(
        sample_rate_hz=int(profile.get("audio.sample_rate_hz")),
        part_s=float(vt["part_s"]),
        ramp_ms=max(float(vt["ramp_ms"]), float(profile.get("limits.ramp_min_ms"))),
        gap_s=float(vt["gap_ms"]) / 1e3,
        pulse_s=float(vt["pulse_s"]),
        sensation_level_db=float(vt["sensation_level_db"]),
        drive_max_v=float(vt["drive_max_v"]),
        interpolation=str(vt["interpolation"]),
        ringdown_gap_k=float(vt.get("ringdown_gap_k", 0.0)),
        ringdown_zeta=float(vt.get("ringdown_zeta", 0.0)),
    )
    lo, hi = Limits.from_profile(profile).piezo_range()
    cache = None if str(vt.get("cache_dir", "") or "") == "none" else default_cache_dir()
    return Setup(
        settings=st,
        perception=Perception.from_section(profile.section("perception")),
        piezo_min_v=float(lo),
        piezo_max_v=float(hi),
        band_hz=float(vt["band_hz"]),
        min_contrast_db=float(vt.get("min_contrast_db", 0.0)),
        cache_dir=cache,
        hand={
            "hand_mm": float(vt["hand_mm"]),
            "squares": int(vt["hand_squares"]),
            "subgrid": int(vt["hand_subgrid"]),
        },
        max_plan_s=float(profile.get("limits.max_plan_s")),
        table_rule=str(vt.get("table_rule", "perceptual")),
        perceptual=rule_from_profile(profile),
        map_error_rel=float(vt.get("map_error_rel", 0.05)),
        method=_default_method(profile, str(vt.get("method", "auto"))),
    )


def _default_method(profile: Any, method: str) -> str:
    """``auto``: independent patches when each has its own channel, else the paper's."""
    from plugins.vibrotactile.independent_plans import per_patch_channels

    if method != "auto":
        return method
    return "independent" if per_patch_channels(profile) else "paper"


class _MapUser:
    """Map and tables loading shared by the effects (memoised per effect object)."""

    def __init__(self, profile: Any, setup: Setup | None = None) -> None:
        self.profile = profile
        self.setup = setup or setup_from_profile(profile)
        self._maps: dict[tuple, VibrationMap] = {}
        self._tables: dict[tuple, Any] = {}
        self._plans: dict[tuple, OutputPlan] = {}
        self._lock = threading.RLock()

    # ---------------------------------------------------------------- sources
    def vibration_map(self, vmap: Any = None, tables: Any = None) -> VibrationMap:
        """The map of a request (``vmap`` or ``tables``), loaded once per file version."""
        if tables is not None:
            return self.tables(tables=tables).vmap
        if vmap is None:
            raise UserError(
                "vibrotactile effect: give vmap= (a vibration map or tables file) or tables="
            )
        if isinstance(vmap, VibrationMap):
            return vmap
        p = Path(vmap)
        if not p.is_file():
            raise UserError(f"{p}: no such vibration map; measure or import one (haptable frf)")
        st = p.stat()
        key = (str(p.resolve()), st.st_mtime_ns, st.st_size)
        with self._lock:
            if key not in self._maps:
                from plugins.vibrotactile.tables import load_map_or_tables

                if len(self._maps) >= 4:
                    self._maps.pop(next(iter(self._maps)))
                self._maps[key] = load_map_or_tables(p, require_all=False, **self._file_checks())
            return self._maps[key]

    def _file_checks(self) -> dict:
        """What a map or tables file is checked against: the sample rate (Nyquist). Point
        ids are the measurement's node numbers, not checked against the profile's grid."""
        return {"sample_rate_hz": self.setup.settings.sample_rate_hz}

    def tables(
        self,
        vmap: Any = None,
        tables: Any = None,
        *,
        min_contrast_db: float | None = None,
        progress: Callable[[float, str], None] | None = None,
        rule: str | None = None,
        steps: int = 1,
    ):
        """Lookup tables (paper Fig. 8) of a map, built once and cached on disk.

        ``tables`` given: used as is (a ``Tables`` or a tables file). Else built from
        ``vmap`` with the profile's ``[vibrotactile] band_hz`` under ``rule``
        (``perceptual`` or ``paper``; ``Setup.rule_of`` says which when not given)."""
        from plugins.vibrotactile.tables import Tables, load_tables

        if tables is not None:
            if isinstance(tables, Tables):
                t = tables
            else:
                p = Path(tables)
                st = p.stat() if p.is_file() else None
                key = ("file", str(p), st.st_mtime_ns if st else 0)
                with self._lock:
                    if key not in self._tables:
                        self._tables[key] = load_tables(p, **self._file_checks())
                    t = self._tables[key]
            if vmap is not None:  # both given: the tables must come from that map
                from plugins.vibrotactile.tables import check_tables_map

                check_tables_map(
                    t,
                    self.vibration_map(vmap),
                    tables_where=str(tables) if not isinstance(tables, Tables) else "tables",
                    map_where=str(vmap) if not isinstance(vmap, VibrationMap) else "the map",
                )
            return t
        m = self.vibration_map(vmap)
        c, per = self.setup.rule_of(min_contrast_db, rule)
        key = ("map", id(m), c, per)
        with self._lock:
            hit = self._tables.get(key)
            if hit is None or hit.vmap is not m:
                from plugins.vibrotactile.lazy import tables_cached

                hit = tables_cached(
                    m,
                    self.setup.band_hz,
                    self.setup.cache_dir,
                    progress,
                    min_contrast_db=c,
                    perceptual=per,
                    steps=steps,
                )
                self._tables[key] = hit
            return hit

    def _source_key(self, vmap: Any, tables: Any) -> tuple:
        """Both sources name a plan: tables given with another map are checked again."""

        def one(src: Any) -> tuple:
            if isinstance(src, (str, os.PathLike)):
                return ("path", str(src))
            return ("obj", id(src))

        return one(tables) if vmap is None else (*one(tables), *one(vmap))

    def method_of(self, method: str | None, what: str) -> str:
        """The request's rendering method (default ``[vibrotactile] method``); a method
        with per-patch drives on a bus profile is refused in one line."""
        from plugins.vibrotactile.independent_plans import refuse_on_bus

        m = self.setup.method if method is None else str(method)
        if m not in ("paper", "independent", "time_reversal"):
            raise UserError(f"{what} method {m!r}: use paper, independent or time_reversal")
        refuse_on_bus(self.profile, what, m)
        return m

    def _settings(self, ringdown_gap_k: float | None):
        st = self.setup.settings
        if ringdown_gap_k is not None:
            st = replace(st, ringdown_gap_k=float(ringdown_gap_k))
        return st


def _point(m: VibrationMap, p: Any) -> int | tuple[float, float]:
    """A grid number -> map index; (x, y) mm -> a tuple of floats."""
    if isinstance(p, (int, np.integer)) and not isinstance(p, bool):
        return m.point_index(int(p))
    try:
        x, y = (float(v) for v in p)
    except (TypeError, ValueError):
        raise UserError(
            f"point {p!r}: give a grid number (1..{m.points.size}) or (x, y) in mm"
        ) from None
    return (x, y)


def _label(p: Any) -> str:
    return str(int(p)) if isinstance(p, (int, np.integer)) else f"{p[0]:g},{p[1]:g}"


class FlowEffect(_MapUser):
    """Effect ``flow``: a two-part flow between two points (paper Fig. 9).

    ``render(from_point=, to_point=, vmap= | tables=, name="", min_contrast_db=None,
    ringdown_gap_k=None) -> OutputPlan``. ``from_point``/``to_point``: grid numbers or
    (x, y) mm (``active``/``passive`` are accepted as synonyms: part 1's active point is
    ``from_point``). ``min_contrast_db``: the tables' ranking (default ``[vibrotactile]
    min_contrast_db``; 0 = the paper's largest absolute difference; ignored with
    ``tables=``, which carry their own); ``rule``: ``perceptual`` or ``paper`` (default
    ``[vibrotactile] table_rule``). ``ringdown_gap_k``: the silence between the
    parts is at least ``k`` decay times of part 1's mode (default ``[vibrotactile]
    ringdown_gap_k``; 0 = relay gap only). The plan's ``meta`` has ``parts`` (table
    answer, ``active_um_per_v``, ``passive_um_per_v``, ``contrast_db``, ``amplitude_v``
    per part), ``sensation_level_db``, ``notes``, ``from``/``to``, ``ringdown``,
    ``method`` and ``predicted_contrast_db``. ``method``: ``paper`` (the tables),
    ``independent`` or ``time_reversal`` (a drive per patch, ``independent_plans``;
    refused on a bus profile); default ``[vibrotactile] method``.
    """

    def _key(self, a, b, vmap, tables, min_contrast_db, ringdown_gap_k, rule=None) -> tuple:
        norm = [
            tuple(map(float, p)) if not isinstance(p, (int, np.integer)) else int(p) for p in (a, b)
        ]
        src = self._source_key(vmap, tables)
        return ("flow", *norm, src, min_contrast_db, ringdown_gap_k, rule)

    def cached(
        self,
        from_point: Any = None,
        to_point: Any = None,
        *,
        active: Any = None,
        passive: Any = None,
        vmap: Any = None,
        tables: Any = None,
        min_contrast_db: float | None = None,
        ringdown_gap_k: float | None = None,
        rule: str | None = None,
        method: str | None = None,
        **_: Any,
    ) -> OutputPlan | None:
        """The plan if this effect already rendered it (no work, never raises)."""
        a, b = (from_point, to_point) if from_point is not None else (active, passive)
        try:
            k = self._key(a, b, vmap, tables, min_contrast_db, ringdown_gap_k, rule)
        except (TypeError, ValueError):
            return None
        how = self.setup.method if method is None else method
        return self._plans.get(k if how == "paper" else (*k, how))

    def render(
        self,
        from_point: Any = None,
        to_point: Any = None,
        *,
        active: Any = None,
        passive: Any = None,
        vmap: Any = None,
        tables: Any = None,
        name: str = "",
        min_contrast_db: float | None = None,
        ringdown_gap_k: float | None = None,
        rule: str | None = None,
        method: str | None = None,
    ) -> OutputPlan:
        from plugins.vibrotactile.stimuli import flow_plan

        a, b = (from_point, to_point) if from_point is not None else (active, passive)
        if a is None or b is None:
            raise UserError("flow: give from_point= and to_point= (grid numbers or (x, y) mm)")
        how = self.method_of(method, "flow")
        key = self._key(a, b, vmap, tables, min_contrast_db, ringdown_gap_k, rule)
        key = key if how == "paper" else (*key, how)
        hit = self._plans.get(key)
        if hit is not None:
            return hit
        if how != "paper":
            return self._render_patches(a, b, vmap, tables, name, how, key)
        t = self.tables(vmap, tables, min_contrast_db=min_contrast_db, rule=rule)
        pa, pb = _point(t.vmap, a), _point(t.vmap, b)
        plan = flow_plan(
            t,
            pa,
            pb,
            self.setup.perception,
            self._settings(ringdown_gap_k),
            name=name or f"flow {_label(a)}->{_label(b)}",
            **self.setup.limits,
        )
        xy = [t.vmap.points_mm[p] if isinstance(p, int) else p for p in (pa, pb)]
        plan.meta["from_mm"] = [float(v) for v in xy[0]]
        plan.meta["to_mm"] = [float(v) for v in xy[1]]
        with self._lock:
            self._plans[key] = plan
        return plan

    def _render_patches(self, a, b, vmap, tables, name, how, key) -> OutputPlan:
        """The flow with a drive per patch (``independent_plans.flow_plan``)."""
        from plugins.vibrotactile import independent_plans

        m = self.vibration_map(vmap, tables)
        pa, pb = _point(m, a), _point(m, b)
        if pa == pb or (not isinstance(pa, int) and np.allclose(pa, pb)):
            raise UserError("flow: the two points are the same; a flow needs two points")
        s = self.setup
        plan = independent_plans.flow_plan(
            m, pa, pb, s.perception, s.settings, method=how, cap_v=s.cap_v, band_hz=s.band_hz,
            map_error_rel=s.map_error_rel, max_plan_s=s.max_plan_s,
            name=name or f"flow {_label(a)}->{_label(b)} ({how})",
        )  # fmt: skip
        xy = [m.points_mm[p] if isinstance(p, int) else p for p in (pa, pb)]
        plan.meta["from_mm"] = [float(v) for v in xy[0]]
        plan.meta["to_mm"] = [float(v) for v in xy[1]]
        with self._lock:
            self._plans[key] = plan
        return plan

    def render_flow(self, a: int, b: int, vmap: Any) -> OutputPlan:
        """The flow from grid point ``a`` to ``b`` of ``vmap``
        (``console.contracts.FlowEffect``)."""
        return self.render(int(a), int(b), vmap=vmap)

    def patch_drives(
        self, pairs: Iterable, *, vmap: Any = None, tables: Any = None, method: str = "independent"
    ) -> list[dict | None]:
        """Per (active, passive) pair of map indices: the part's ``frequency_hz`` and
        ``weights`` (4,) complex drive of PA..PD (1 V peak on the strongest patch),
        predicted ``contrast_db`` and ``amplitude_v``, by ``method``: ``paper`` (the
        paper's tables), ``independent`` or ``time_reversal``
        (``plugins.vibrotactile.independent``); ``None`` where there is no flow."""
        from plugins.vibrotactile import independent as ind

        s = self.setup
        kw = {"cap_v": s.cap_v, "target_sl_db": s.settings.sensation_level_db}
        if method == "paper":
            t = self.tables(vmap, tables, rule="paper")
            return ind.paper_pair_drives(t, list(pairs), s.perception, **kw)
        return ind.solve_pairs(
            self.vibration_map(vmap, tables), pairs, s.perception, band_hz=s.band_hz,
            method=method, map_error_rel=s.map_error_rel, **kw,
        )  # fmt: skip

    def query(
        self,
        active: Any,
        passive: Any,
        *,
        vmap: Any = None,
        tables: Any = None,
        min_contrast_db: float | None = None,
        rule: str | None = None,
    ) -> dict:
        """The lookup-table entry of a pair (grid numbers or (x, y) mm): the
        ``max_difference_um_per_v``, its ``frequency_hz`` and ``actuator`` (``None`` for
        the same point twice), under the tables' ranking (``min_contrast_db``)."""
        from plugins.vibrotactile.tables import query_indices, query_points

        t = self.tables(vmap, tables, min_contrast_db=min_contrast_db, rule=rule)
        a, b = _point(t.vmap, active), _point(t.vmap, passive)
        if isinstance(a, int) and isinstance(b, int):
            ans = query_indices(t, a, b)
        else:
            xy = [t.vmap.points_mm[p] if isinstance(p, int) else p for p in (a, b)]
            ans = query_points(
                t, tuple(xy[0]), tuple(xy[1]), method=self.setup.settings.interpolation
            )
        return {**ans, "min_contrast_db": float(t.min_contrast_db)}

    def prepare(
        self,
        pairs: Iterable = (),
        *,
        vmap: Any = None,
        tables: Any = None,
        progress: Progress | None = None,
        **request: Any,
    ) -> list[OutputPlan]:
        """Render the flows of ``pairs`` ((from, to), ...) ahead of time (a scene's
        ``needs``); ``progress(done, total, what)`` per pair. Pairs the map cannot make
        a flow for are skipped (``None`` in the list)."""
        pairs = list(pairs)
        out: list = []
        self.tables(
            vmap, tables, min_contrast_db=request.get("min_contrast_db"), rule=request.get("rule")
        )
        for i, (a, b) in enumerate(pairs):
            if progress is not None:
                progress(i, len(pairs), f"flow {_label(a)}->{_label(b)}")
            try:
                out.append(self.render(a, b, vmap=vmap, tables=tables, **request))
            except UserError:
                out.append(None)
        if progress is not None:
            progress(len(pairs), len(pairs), "flows ready")
        return out


class HandFlowEffect(_MapUser):
    """Effect ``hand_flow``: the flow under a hand (paper 5.2.2, Figs. 11 and 14).

    ``render(center_mm=(x, y), direction="left|right|up|down", vmap=, hand_mm=None,
    exhaustive=False, screen_stride=None, name="", ringdown_gap_k=None) -> OutputPlan``.
    ``hand_mm``: the hand's square (default ``[vibrotactile] hand_mm``). ``exhaustive``:
    every bin and subgrid point (the reference, seconds); else the staged search
    (``screen_stride``, default 3). The centre is rounded to 0.1 mm. ``meta``:
    ``center_mm``, ``direction``, ``parts`` (``actuator``, ``frequency_hz``,
    ``amplitude_v``, ``margin_db``, ``x_um`` the 3-JND line, ``active`` squares),
    ``level_above_3jnd_db`` and ``ringdown`` when a ring-down gap applies.
    A place with no flow is a ``UserError`` saying why. ``method`` as for ``flow``
    (``independent``: the max-min solve over the hand's squares).
    """

    def _key(self, center_mm, direction, vmap, hand_mm, exhaustive, stride, k) -> tuple:
        c = (round(float(center_mm[0]), 1), round(float(center_mm[1]), 1))
        return ("hand", c, direction, self._source_key(vmap, None), hand_mm, exhaustive, stride, k)

    def cached(
        self,
        center_mm: Any,
        direction: str,
        *,
        vmap: Any = None,
        hand_mm: float | None = None,
        exhaustive: bool = False,
        screen_stride: int | None = None,
        ringdown_gap_k: float | None = None,
        method: str | None = None,
        **_: Any,
    ) -> OutputPlan | None:
        """The plan if already rendered for this place (either search), else ``None``."""
        how = self.setup.method if method is None else method
        for ex in (exhaustive, not exhaustive):
            k = self._key(center_mm, direction, vmap, hand_mm, ex, screen_stride, ringdown_gap_k)
            k = k if how == "paper" else (*k, how)
            if k in self._plans:
                return self._plans[k]
        return None

    def _kw(self, hand_mm: float | None) -> dict:
        s = self.setup
        return {
            **s.hand,
            **({"hand_mm": float(hand_mm)} if hand_mm else {}),
            "band_hz": s.band_hz,
            "method": s.settings.interpolation,
        }

    def render(
        self,
        center_mm: Any = None,
        direction: str = "",
        *,
        vmap: Any = None,
        hand_mm: float | None = None,
        exhaustive: bool = False,
        screen_stride: int | None = None,
        name: str = "",
        ringdown_gap_k: float | None = None,
        method: str | None = None,
    ) -> OutputPlan:
        from plugins.vibrotactile.hand import DIRECTIONS
        from plugins.vibrotactile.instant import no_flow_error, plan_from_search
        from plugins.vibrotactile.lazy import hand_flow_cached

        if direction not in DIRECTIONS:
            raise UserError(f"flow direction {direction!r}: use one of {', '.join(DIRECTIONS)}")
        if center_mm is None:
            raise UserError("hand_flow: give center_mm=(x, y) in mm")
        how = self.method_of(method, "hand flow")
        key = self._key(
            center_mm, direction, vmap, hand_mm, exhaustive, screen_stride, ringdown_gap_k
        )
        key = key if how == "paper" else (*key, how)
        hit = self._plans.get(key)
        if hit is not None:
            return hit
        if how != "paper":
            return self._render_patches(key, direction, vmap, hand_mm, name, how)
        m = self.vibration_map(vmap)
        cx, cy = key[1]
        stride = 1 if exhaustive else int(screen_stride or 3)
        kw = {**self._kw(hand_mm), "cap_v": self.setup.cap_v, "screen_stride": stride}
        res = hand_flow_cached(
            m, (cx, cy), direction, self.setup.perception, self.setup.cache_dir, **kw
        )
        if not res["ok"]:
            raise no_flow_error(direction, (cx, cy), res["reason"])
        st = self._settings(ringdown_gap_k)
        plan = plan_from_search(
            m, res, (cx, cy), direction, st, self.setup.band_hz, kw["hand_mm"], name
        )
        with self._lock:
            self._plans[key] = plan
        return plan

    def _render_patches(self, key, direction, vmap, hand_mm, name, how) -> OutputPlan:
        """The flow under a hand with a drive per patch (``independent.solve_region``)."""
        from plugins.vibrotactile.independent_plans import hand_flow_plan

        (cx, cy), hm = key[1], float(hand_mm or self.setup.hand["hand_mm"])
        parts = self.patch_drives((cx, cy), direction, vmap=vmap, method=how, hand_mm=hm)
        plan = hand_flow_plan(parts, (cx, cy), direction, hm, self.setup.settings, how, name)
        with self._lock:
            self._plans[key] = plan
        return plan

    def render_hand_flow(self, center_mm: Any, direction: str, vmap: Any) -> OutputPlan:
        """The flow under a hand at ``center_mm`` toward ``direction`` on ``vmap``, the
        staged search (``console.contracts.HandFlowEffect``)."""
        return self.render(center_mm=center_mm, direction=direction, vmap=vmap, screen_stride=3)

    def hand_flow_atlas(
        self,
        vmap: Any,
        step_mm: float = 10.0,
        *,
        progress: Progress | None = None,
        workers: int | None = None,
    ):
        """Every flow ``render_hand_flow`` gives on a ``step_mm`` grid of hand centres, in
        all directions, chosen ahead (``plugins.vibrotactile.instant.FlowAtlas``; cached
        on disk; ``progress`` raising cancels; ``workers`` processes, default up to 2)."""
        from plugins.vibrotactile.instant import load_or_build

        how = self.method_of(None, "hand flow")
        if how != "paper":
            raise UserError(
                f"flow atlas: this profile's hand flows use the {how!r} method; the atlas "
                "holds the paper's search only (flows are planned when asked)"
            )
        s = self.setup
        return load_or_build(
            self.vibration_map(vmap),
            s.perception,
            s.cache_dir,
            step_mm=float(step_mm),
            cap_v=s.cap_v,
            settings=s.settings,
            **self._kw(None),
            workers=min(2, os.cpu_count() or 1) if workers is None else int(workers),
            progress=progress,
        )

    def prepare(
        self,
        regions: Iterable = (),
        *,
        vmap: Any = None,
        progress: Progress | None = None,
        exhaustive: bool = True,
        **request: Any,
    ) -> list[OutputPlan | None]:
        """Render the flows of ``regions`` (((x, y), direction), ...) ahead of time (a
        scene's ``flow_regions``), exhaustive by default; ``progress(done, total, what)``
        per region. A region with no flow is ``None`` in the list."""
        regions = list(regions)
        out: list = []
        for i, (c, d) in enumerate(regions):
            if progress is not None:
                progress(i, len(regions), f"flow {d} at {c[0]:g},{c[1]:g} mm")
            try:
                out.append(self.render(c, d, vmap=vmap, exhaustive=exhaustive, **request))
            except UserError:
                out.append(None)
        if progress is not None:
            progress(len(regions), len(regions), "flows ready")
        return out

    def patch_drives(
        self,
        center_mm: Any,
        direction: str,
        *,
        vmap: Any = None,
        method: str = "independent",
        hand_mm: float | None = None,
    ) -> list[dict]:
        """The two parts of the flow under a hand as per-patch drives: ``frequency_hz``,
        ``weights`` (4,) complex (1 V peak on the strongest patch), ``amplitude_v``,
        ``x_um`` (3-JND line); ``paper``: the staged search's answer on its actuator."""
        from plugins.vibrotactile import independent as ind

        if method == "paper":
            plan = self.render(
                center_mm=center_mm, direction=direction, vmap=vmap, hand_mm=hand_mm, method="paper"
            )
            return [
                {**p, "weights": ind.actuator_weights(p["actuator"])} for p in plan.meta["parts"]
            ]
        s = self.setup
        return ind.solve_region(
            self.vibration_map(vmap), center_mm, direction, s.perception, cap_v=s.cap_v,
            hand_mm=float(hand_mm or s.hand["hand_mm"]), squares=s.hand["squares"],
            subgrid=s.hand["subgrid"],
            band_hz=s.band_hz, method=method, map_error_rel=s.map_error_rel,
            interpolation=s.settings.interpolation,
        )  # fmt: skip

    # ------------------------------------------------------ for checks and scenes
    def sides(self, direction: str) -> tuple[np.ndarray, np.ndarray]:
        """(start side, end side) square masks [row(y), col(x)] for ``direction``:
        part 1 activates the start side, part 2 the end side."""
        from plugins.vibrotactile.hand import side_masks

        return side_masks(direction, int(self.setup.hand["squares"]))

    def square_levels_um_per_v(
        self, center_mm: Any, actuator: str, frequency_hz: float, *, vmap: Any = None, hand_mm=None
    ) -> np.ndarray:
        """(squares, squares) level of each square per volt on ``actuator`` at the map bin
        nearest ``frequency_hz``: the displacement at least half of the square's subgrid
        points reach (the map's prediction, interpolated)."""
        from plugins.vibrotactile.hand import square_levels

        m = self.vibration_map(vmap)
        k = int(np.argmin(np.abs(m.freq_hz - frequency_hz)))
        q, _ = square_levels(m, center_mm, bins=np.array([k]), **self._kw(hand_mm))
        return q[m.excitation_index(actuator), :, :, 0]

    def region_centers(self, step_mm: float, *, vmap: Any = None, hand_mm=None) -> list:
        """Hand centres (x, y) mm at ``step_mm`` steps where the hand lies inside the grid."""
        from plugins.vibrotactile.hand import region_centers

        m = self.vibration_map(vmap)
        hm = float(hand_mm or self.setup.hand["hand_mm"])
        return [tuple(map(float, c)) for c in region_centers(m, hm, step_mm)]


class PointEffect(_MapUser):
    """Effect ``point``: a localized pulse at one point (paper 4.1).

    ``render(point=, vmap= | tables=, name="") -> OutputPlan``: the excitation and
    frequency where the point's displacement per volt is largest, at the target
    sensation level; ``meta`` has ``frequency_hz``, ``actuator``, ``amplitude_v``,
    ``um_per_v``, ``sensation_level_db`` and ``median_grid_um_per_v``. ``method`` as for
    ``flow`` (``independent``: the drive focusing on the point against the whole grid).
    """

    def cached(
        self, point: Any = None, *, vmap: Any = None, tables: Any = None, method=None, **_: Any
    ):
        try:
            k = ("point", _label(point), self._source_key(vmap, tables))
        except (TypeError, ValueError, IndexError):
            return None
        how = self.setup.method if method is None else method
        return self._plans.get(k if how == "paper" else (*k, how))

    def render_point(self, point: Any, vmap: Any) -> OutputPlan:
        """The pulse at ``point`` (a grid number or (x, y) mm) of ``vmap``
        (``console.contracts.PointEffect``)."""
        return self.render(point=point, vmap=vmap)

    def render(
        self,
        point: Any = None,
        *,
        vmap: Any = None,
        tables: Any = None,
        name: str = "",
        method: str | None = None,
    ) -> OutputPlan:
        from plugins.vibrotactile.stimuli import point_plan

        if point is None:
            raise UserError("point: give point= (a grid number or (x, y) mm)")
        how = self.method_of(method, "point")
        key = ("point", _label(point), self._source_key(vmap, tables))
        key = key if how == "paper" else (*key, how)
        if key in self._plans:
            return self._plans[key]
        if how != "paper":
            from plugins.vibrotactile import independent_plans

            m, s = self.vibration_map(vmap, tables), self.setup
            plan = independent_plans.point_plan(
                m, _point(m, point), s.perception, s.settings, cap_v=s.cap_v,
                band_hz=s.band_hz, map_error_rel=s.map_error_rel, max_plan_s=s.max_plan_s,
                method=how, name=name or f"point {_label(point)} ({how})",
            )  # fmt: skip
            with self._lock:
                self._plans[key] = plan
            return plan
        if tables is None:  # a pulse needs the map only, not the pair tables
            from plugins.vibrotactile.tables import Tables

            t = Tables(
                np.zeros((0, 0)),
                np.zeros((0, 0)),
                np.zeros((0, 0), np.int8),
                self.setup.band_hz,
                self.vibration_map(vmap),
            )
        else:
            t = self.tables(vmap, tables)
        plan = point_plan(
            t,
            _point(t.vmap, point),
            self.setup.perception,
            self.setup.settings,
            name=name or f"point {_label(point)}",
            **self.setup.limits,
        )
        with self._lock:
            self._plans[key] = plan
        return plan
