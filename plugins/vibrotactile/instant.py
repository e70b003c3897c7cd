"""Flows under a hand that start at once: every place's plan chosen before it is asked for.

The hand-flow search (``hand.hand_flow``, staged) costs 60-100 ms per place and direction
on a measured map; a demo that runs it when a hand comes to rest starts the flow seconds
late. A *flow atlas* holds the search's answer (actuator, frequency, amplitude, margin,
active squares per part) for every hand centre on a ``step_mm`` grid over the part of the
table where a hand fits inside the measured grid, in all four directions. Asking for a
flow is then a lookup of the nearest centre plus the synthesis of two tones (the same
``stimuli.tone_segment`` calls the effect makes: the samples are the effect's own).

The resolution: 10 mm by default (``[demos] flow_grid_mm``). A hand at rest is only known
to within the resting detector's ``still_mm`` (12 mm) and the palm tells two touches
apart ~10 mm or more apart (the palm's two-point threshold, a recalled literature value);
the nearest 10 mm centre is at most 7 mm away, below both, and the 40 mm squares under
the hand change by less than a fifth of a square.

The atlas is built in worker processes (``workers``; cancel by raising in ``progress``)
and cached on disk keyed by a hash of everything it depends on: the map's content, the
perception model, the drive cap, band, interpolation, hand geometry, search parameters and
the step; the file carries that key inside it (``console.files.cache_files``). A cache file of
other inputs (another map's atlas under this name), that cannot be read or fails its
checks is logged, deleted and rebuilt: it is never played. Memory: ~100 bytes per place and direction plus at most
``max_plans`` synthesised plans (``nbytes`` says how much).
"""

from __future__ import annotations

import contextlib
import math
import os
import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

import numpy as np

from console.plugin_api import DIRECTIONS, OutputPlan, UserError, VibrationMap, patches_of
from plugins.vibrotactile.cache import cached_entry

#: Bumped when the stored arrays or the search change (old cache files are not read).
ATLAS_VERSION = 1
#: The staged search the atlas stores (the effect's default ``render``).
SEARCH = {"screen_stride": 3, "screen_df_hz": 0.5, "top": 8}
#: Places per task sent to a worker (under a second of work on a busy 2-core machine: the
#: wait before a hand's place is searched, progress and cancel).
CHUNK = 4

Progress = Callable[[int, int, str], None]  # (done, total, what); raising cancels
Focus = Callable[[], "tuple[float, float] | None"]  # where a hand is now (None: nowhere)


# --------------------------------------------------------------------------- synthesis
def plan_from_search(
    m: VibrationMap,
    res: dict,
    center_mm: tuple[float, float],
    direction: str,
    settings: Any,
    band_hz: float,
    hand_mm: float,
    name: str = "",
) -> OutputPlan:
    """The plan (the paper's method) of a hand-flow search result ``res`` (``hand.hand_flow``'s dict with
    ``ok``): two tones with ramps, the gap after part 1, the effect's ``meta``."""
    # lazy: SciPy loads only when this runs
    from plugins.vibrotactile.stimuli import gap_after_part_1, tone_segment

    st = settings
    cx, cy = center_mm
    segs = tuple(
        tone_segment(
            p["frequency_hz"],
            p["amplitude_v"],
            st.part_s,
            st.ramp_ms / 1e3,
            st.sample_rate_hz,
            patches_of(p["actuator"]),
            label=f"part {i + 1} {p['actuator']}",
        )
        for i, p in enumerate(res["parts"])
    )
    gap = gap_after_part_1(m, res["parts"][0], st, band_hz)
    meta = {
        "kind": "hand_flow",
        "ok": True,
        "center_mm": [cx, cy],
        "direction": direction,
        "hand_mm": float(hand_mm),
        "parts": [
            {k: v for k, v in p.items() if k not in ("e", "k", "qa", "qb")} for p in res["parts"]
        ],
        "level_above_3jnd_db": res.get("level_above_3jnd_db"),
        "method": "paper",
        "predicted_contrast_db": float(min(p["margin_db"] for p in res["parts"])),
    }
    if "ringdown" in gap:
        meta["ringdown"] = gap["ringdown"]
    return OutputPlan(
        st.sample_rate_hz,
        segs,
        name=name or f"hand flow {direction} at {cx:g},{cy:g} mm",
        gap_s=gap["gap_s"],
        meta=meta,
    )


def no_flow_error(direction: str, center_mm, reason: str) -> UserError:
    """The effect's line for a place with no flow."""
    return UserError(
        f"no flow {direction} under a hand at {center_mm[0]:g},{center_mm[1]:g} mm: {reason}; "
        "move the hand"
    )


# --------------------------------------------------------------------------- the grid
def atlas_axes(m: VibrationMap, hand_mm: float, step_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """(xs, ys): multiples of ``step_mm`` where a ``hand_mm`` hand lies inside the grid
    (the positions a demo snaps a resting hand to, so both agree)."""
    if step_mm <= 0:
        raise UserError(f"flow atlas step {step_mm:g} mm: give a step > 0 (e.g. 10)")
    lo = m.points_mm.min(axis=0) + hand_mm / 2
    hi = m.points_mm.max(axis=0) - hand_mm / 2
    if np.any(hi < lo):
        raise UserError(f"a {hand_mm:g} mm hand does not fit inside the measured grid")
    axes = []
    for a, b in zip(lo, hi, strict=True):
        k0, k1 = math.ceil(a / step_mm - 1e-9), math.floor(b / step_mm + 1e-9)
        if k1 < k0:  # narrower than one step: the middle
            axes.append(np.array([round((a + b) / 2, 1)]))
        else:
            axes.append(np.round(np.arange(k0, k1 + 1) * step_mm, 6))
    return axes[0], axes[1]


# --------------------------------------------------------------------------- the search
def place_rows(m: VibrationMap, per: Any, center_mm, cap_v: float, **kw) -> list[dict]:
    """The staged search's result at one place for each of ``DIRECTIONS``, equal to
    ``hand.hand_flow(m, center_mm, d, per, cap_v=cap_v, **SEARCH, **kw)`` per direction,
    with the direction-free first stage done once."""
    # lazy: SciPy loads only when this runs
    from plugins.vibrotactile.hand import choose, refine_levels, screen_levels

    sk = {k: v for k, v in SEARCH.items() if k != "top"}
    screened = screen_levels(m, center_mm, **sk, **kw)
    out = []
    for d in DIRECTIONS:
        q, keep = refine_levels(
            m,
            center_mm,
            screened,
            (d,),
            per,
            cap_v,
            screen_stride=SEARCH["screen_stride"],
            top=SEARCH["top"],
            **kw,
        )
        out.append(choose(q, keep, m, d, per, cap_v))
    return out


_WORKER: dict = {}


def _init_worker(m: VibrationMap, per: Any, cap_v: float, kw: dict) -> None:
    try:  # one BLAS thread per process: the processes are the parallelism
        from threadpoolctl import threadpool_limits

        _WORKER["limit"] = threadpool_limits(1)
    except ImportError:
        pass
    _WORKER.update(m=m, per=per, cap_v=cap_v, kw=kw)


#: the atlas's worker processes yield the CPU to everything live (the frame loop, the
#: audio, the projector's heartbeat): the atlas is built behind a running demo
WORKER_NICE = 10
#: the workers at the lowest priority (off: at this process's, as a test on a machine
#: loaded by other tests needs: there nothing would leave them a CPU)
IDLE_WORKERS = True


def _init_pool_worker(m: VibrationMap, per: Any, cap_v: float, kw: dict, idle: bool = True) -> None:
    """A spawned worker: lowest priority first (``idle``; Linux's ``SCHED_IDLE``: it runs
    only on a CPU nothing else wants; elsewhere ``WORKER_NICE``), then ``_init_worker``."""
    if idle:
        with contextlib.suppress(OSError):  # not permitted: the normal priority
            os.nice(WORKER_NICE)
        with contextlib.suppress(AttributeError, OSError):  # not Linux: the nice value only
            os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))
    _init_worker(m, per, cap_v, kw)


def _chunk_rows(args: tuple) -> tuple[int, list[list[dict]]]:
    start, centers = args
    w = _WORKER
    return start, [place_rows(w["m"], w["per"], c, w["cap_v"], **w["kw"]) for c in centers]


def empty_arrays(centers: np.ndarray, squares: int) -> dict:
    """The atlas's arrays for ``centers`` (N, 2) with no place searched yet."""
    n, nd = len(centers), len(DIRECTIONS)
    return {
        "centers_mm": np.asarray(centers, float),
        "ok": np.zeros((n, nd), bool),
        "excitation": np.full((n, nd, 2), -1, np.int8),
        "frequency_hz": np.full((n, nd, 2), np.nan),
        "amplitude_v": np.full((n, nd, 2), np.nan),
        "margin_db": np.full((n, nd, 2), np.nan),
        "x_um": np.full((n, nd, 2), np.nan),
        "active": np.zeros((n, nd, 2, squares, squares), bool),
        "level_db": np.full((n, nd), np.nan),
        "reasons_json": {},
    }


def fill_rows(a: dict, start: int, rows: list[list[dict]]) -> None:
    """Write the search's results of places ``start, start + 1, ...`` into ``a``."""
    for i, per_dir in enumerate(rows, start):
        for j, r in enumerate(per_dir):
            if not r["ok"]:
                a["reasons_json"][f"{i},{j}"] = str(r["reason"])
                continue
            a["ok"][i, j] = True
            a["level_db"][i, j] = r["level_above_3jnd_db"]
            for k, p in enumerate(r["parts"]):
                a["excitation"][i, j, k] = p["e"]
                for key in ("frequency_hz", "amplitude_v", "margin_db", "x_um"):
                    a[key][i, j, k] = p[key]
                a["active"][i, j, k] = np.asarray(p["active"], bool)


def _nearest_chunk(left: list[tuple], focus: Focus | None) -> tuple:
    """Take the chunk to search next out of ``left``: the one with a place nearest the
    place ``focus()`` names (a hand on the table), else the first."""
    f = focus() if focus is not None else None
    if f is None:
        return left.pop(0)
    d = [float(np.min(np.hypot(c[:, 0] - f[0], c[:, 1] - f[1]))) for _, c in left]
    return left.pop(int(np.argmin(d)))


def build_arrays(
    m: VibrationMap,
    per: Any,
    centers: np.ndarray,
    *,
    cap_v: float,
    squares: int,
    workers: int = 2,
    progress: Progress | None = None,
    into: tuple[dict, np.ndarray] | None = None,
    focus: Focus | None = None,
    **kw: Any,
) -> dict:
    """The atlas's arrays for ``centers`` (N, 2), in ``workers`` spawned processes (1: here).
    ``progress(done, total, what)`` per chunk; an exception from it cancels (the workers
    are terminated) and propagates. ``into``: (arrays, known) filled as places come
    (``known[i]`` set once place ``i`` is written: a partial atlas reads them meanwhile).
    ``focus()``: the place a hand is at, whose chunk is searched next."""
    centers = np.asarray(centers, float)
    kw = {**kw, "squares": squares}
    n = len(centers)
    a, known = into if into is not None else (empty_arrays(centers, squares), np.zeros(n, bool))
    left = [(i, centers[i : i + CHUNK]) for i in range(0, n, CHUNK)]
    done = 0

    def take(got: tuple[int, list]) -> None:
        nonlocal done
        start, rows = got
        fill_rows(a, start, rows)
        known[start : start + len(rows)] = True
        done += len(rows)
        tell()

    def tell() -> None:
        if progress is not None:
            progress(done, n, f"flows under a hand: {done}/{n} places x 4 directions")

    tell()
    if workers <= 1 or len(left) <= 1:
        _init_worker(m, per, cap_v, kw)
        while left:
            take(_chunk_rows(_nearest_chunk(left, focus)))
        return a
    import multiprocessing
    import queue

    ctx = multiprocessing.get_context("spawn")  # never fork a threaded process
    pool = ctx.Pool(
        workers, initializer=_init_pool_worker, initargs=(m, per, cap_v, kw, IDLE_WORKERS)
    )
    came: queue.Queue = queue.Queue()
    try:
        # one chunk per worker in flight: the next is chosen when one ends, so a hand
        # placed meanwhile has its place searched after at most one chunk
        busy = 0
        while left or busy:
            while left and busy < workers:
                chunk = _nearest_chunk(left, focus)
                pool.apply_async(_chunk_rows, (chunk,), callback=came.put, error_callback=came.put)
                busy += 1
            got = _next(came, tell)  # (a cancel while the workers search: at once)
            busy -= 1
            if isinstance(got, BaseException):
                raise got
            take(got)
        pool.close()
    except BaseException:
        pool.terminate()  # cancelled (or failed): the workers stop now
        raise
    finally:
        pool.join()
    return a


#: how often a build waiting for its workers asks ``progress`` again (it may cancel)
WAIT_POLL_S = 0.2


def _next(came: Any, still: Callable[[], Any]) -> Any:
    """The next chunk (or error) from ``came``; ``still()`` every ``WAIT_POLL_S`` while
    none comes, so a cancel raised there ends the build at once, not after a chunk."""
    import queue

    while True:
        try:
            return came.get(timeout=WAIT_POLL_S)
        except queue.Empty:
            still()


# --------------------------------------------------------------------------- the atlas
def check_arrays(a: dict, *, n: int, excitations: int, squares: int, cap_v: float) -> None:
    """Raise ``UserError`` unless ``a`` holds a whole atlas of ``n`` places whose flows
    the effect could have chosen (shapes, excitation indices, finite amplitudes within the
    cap, positive frequencies)."""
    nd = len(DIRECTIONS)
    want = {
        "centers_mm": (n, 2),
        "ok": (n, nd),
        "excitation": (n, nd, 2),
        "frequency_hz": (n, nd, 2),
        "amplitude_v": (n, nd, 2),
        "margin_db": (n, nd, 2),
        "x_um": (n, nd, 2),
        "active": (n, nd, 2, squares, squares),
        "level_db": (n, nd),
    }
    for k, shape in want.items():
        if k not in a or np.shape(a[k]) != shape:
            raise UserError(f"key {k!r}: shape {np.shape(a.get(k))}, expected {shape}")
    ok = np.asarray(a["ok"], bool)
    e = np.asarray(a["excitation"])[ok]
    if e.size and (e.min() < 0 or e.max() >= excitations):
        raise UserError(f"key 'excitation': index outside 0..{excitations - 1}")
    v = np.asarray(a["amplitude_v"], float)[ok]
    if v.size and (not np.all(np.isfinite(v)) or v.min() <= 0 or v.max() > cap_v * (1 + 1e-9)):
        raise UserError(f"key 'amplitude_v': not within (0, {cap_v:g}] V")
    f = np.asarray(a["frequency_hz"], float)[ok]
    if f.size and (not np.all(np.isfinite(f)) or f.min() <= 0):
        raise UserError("key 'frequency_hz': not a positive frequency")
    reasons = a.get("reasons_json")
    if not isinstance(reasons, dict) or len(reasons) != int((~ok).sum()):
        raise UserError("key 'reasons_json': not one reason per place without a flow")


class FlowAtlas:
    """Every flow under a hand on a ``step_mm`` grid: ``nearest(pos_mm)`` -> the centre
    serving a hand there (or ``None``), ``plan(center_mm, direction)`` -> its plan (the
    effect's, sample for sample; a place with no flow raises the effect's ``UserError``).
    At most ``max_plans`` synthesised plans are kept (least recently used dropped).
    While it is built (``known``: a mask of the places searched so far, ``None`` once all
    are) ``has`` is true of the places already searched only."""

    def __init__(
        self,
        m: VibrationMap,
        arrays: dict,
        xs: np.ndarray,
        ys: np.ndarray,
        *,
        settings: Any,
        band_hz: float,
        hand_mm: float,
        step_mm: float,
        max_plans: int = 8,
        build_s: float = 0.0,
        from_cache: bool = False,
        known: np.ndarray | None = None,
    ) -> None:
        self.m, self.a = m, arrays
        self.known = known
        self.xs, self.ys = xs, ys
        self.settings, self.band_hz, self.hand_mm = settings, band_hz, hand_mm
        self.step_mm = float(step_mm)
        self.max_plans = max(1, int(max_plans))
        self.build_s, self.from_cache = build_s, from_cache
        self._plans: OrderedDict[tuple, OutputPlan] = OrderedDict()
        self._lock = threading.Lock()

    @property
    def places(self) -> int:
        return int(self.xs.size * self.ys.size)

    @property
    def nbytes(self) -> int:
        """Bytes held: the stored choices plus the synthesised plans kept."""
        arrays = sum(v.nbytes for v in self.a.values() if isinstance(v, np.ndarray))
        with self._lock:
            plans = sum(
                s.piezo_v.nbytes + s.screen_v.nbytes
                for p in self._plans.values()
                for s in p.segments
            )
        return int(arrays + plans)

    def _index(self, center_mm) -> int | None:
        ix = np.flatnonzero(np.abs(self.xs - float(center_mm[0])) < 1e-6)
        iy = np.flatnonzero(np.abs(self.ys - float(center_mm[1])) < 1e-6)
        if ix.size == 0 or iy.size == 0:
            return None
        return int(iy[0] * self.xs.size + ix[0])

    def nearest(self, pos_mm) -> tuple[float, float] | None:
        """The centre nearest ``pos_mm``; ``None`` when ``pos_mm`` lies more than one step
        outside the places where a hand fits (no flow can be computed there)."""
        x, y = float(pos_mm[0]), float(pos_mm[1])
        out = []
        for v, axis in ((x, self.xs), (y, self.ys)):
            if v < axis[0] - self.step_mm or v > axis[-1] + self.step_mm:
                return None
            out.append(float(axis[int(np.argmin(np.abs(axis - v)))]))
        return out[0], out[1]

    def has(self, center_mm) -> bool:
        i = self._index(center_mm)
        known = self.known
        return i is not None and (known is None or bool(known[i]))

    @property
    def complete(self) -> bool:
        """Every place searched (a built or cached atlas; not one still being built)."""
        return self.known is None

    def result(self, center_mm, direction: str) -> dict:
        """The search's result at an atlas centre, as ``hand.hand_flow`` gives it."""
        i = self._index(center_mm)
        if i is None or not self.has(center_mm):
            what = "is not one of its places" if i is None else "is not searched yet"
            raise UserError(
                f"flow atlas: {center_mm[0]:g},{center_mm[1]:g} mm {what} "
                f"(a {self.step_mm:g} mm grid); use nearest() and has()"
            )
        if direction not in DIRECTIONS:
            raise UserError(f"flow direction {direction!r}: use one of {', '.join(DIRECTIONS)}")
        j = DIRECTIONS.index(direction)
        a = self.a
        if not a["ok"][i, j]:
            return {"ok": False, "reason": a["reasons_json"][f"{i},{j}"]}
        parts = []
        for k in range(2):
            parts.append(
                {
                    "actuator": self.m.excitations[int(a["excitation"][i, j, k])],
                    "frequency_hz": float(a["frequency_hz"][i, j, k]),
                    "margin_db": float(a["margin_db"][i, j, k]),
                    "x_um": float(a["x_um"][i, j, k]),
                    "amplitude_v": float(a["amplitude_v"][i, j, k]),
                    "active": a["active"][i, j, k].tolist(),
                }
            )
        return {"ok": True, "parts": parts, "level_above_3jnd_db": float(a["level_db"][i, j])}

    def plan(self, center_mm, direction: str) -> OutputPlan:
        key = (round(float(center_mm[0]), 6), round(float(center_mm[1]), 6), direction)
        with self._lock:
            hit = self._plans.get(key)
            if hit is not None:
                self._plans.move_to_end(key)
                return hit
        res = self.result(center_mm, direction)
        c = (float(center_mm[0]), float(center_mm[1]))
        if not res["ok"]:
            raise no_flow_error(direction, c, res["reason"])
        plan = plan_from_search(
            self.m, res, c, direction, self.settings, self.band_hz, self.hand_mm
        )
        with self._lock:
            self._plans[key] = plan
            while len(self._plans) > self.max_plans:
                self._plans.popitem(last=False)
        return plan


def atlas_key(m: VibrationMap, per: Any, *, cap_v: float, step_mm: float, **kw: Any) -> dict:
    """Everything an atlas depends on (the cache key)."""
    return {
        "atlas": ATLAS_VERSION,
        "map": m.content_hash(),
        "perception": repr(per),
        "cap_v": float(cap_v),
        "step_mm": float(step_mm),
        **SEARCH,
        **{k: (float(v) if isinstance(v, float) else v) for k, v in sorted(kw.items())},
    }


def load_or_build(
    m: VibrationMap,
    per: Any,
    cache_dir: str | os.PathLike | None,
    *,
    step_mm: float,
    cap_v: float,
    settings: Any,
    hand_mm: float,
    squares: int,
    subgrid: int,
    band_hz: float,
    method: str,
    workers: int = 2,
    progress: Progress | None = None,
    max_plans: int = 8,
    partial: Callable[[FlowAtlas], None] | None = None,
    focus: Focus | None = None,
) -> FlowAtlas:
    """The atlas of ``m``: read from ``cache_dir`` when a valid file for these inputs is
    there, else built (``build_arrays``) and stored. A file made from other inputs (it
    carries their key: ``console.files.cache_files``), that cannot be read or fails
    ``check_arrays`` is logged, deleted and rebuilt, never played.
    A build hands ``partial`` the atlas at once, its places usable as they are searched
    (the place ``focus()`` names first); the same object is returned, complete."""
    import time

    xs, ys = atlas_axes(m, hand_mm, step_mm)
    centers = np.array([(x, y) for y in ys for x in xs], float)
    kw = {"hand_mm": hand_mm, "subgrid": subgrid, "band_hz": band_hz, "method": method}
    key = atlas_key(m, per, cap_v=cap_v, step_mm=step_mm, squares=squares, **kw)
    checks = {
        "n": len(centers),
        "excitations": len(m.excitations),
        "squares": squares,
        "cap_v": cap_v,
    }
    common = {
        "settings": settings,
        "band_hz": band_hz,
        "hand_mm": hand_mm,
        "step_mm": step_mm,
        "max_plans": max_plans,
    }

    def check(arrays: dict) -> None:
        check_arrays(arrays, **checks)
        if not np.allclose(arrays["centers_mm"], centers):
            raise UserError("key 'centers_mm': not this grid's places")

    took: list[float] = []
    growing: list[FlowAtlas] = []

    def build() -> dict:
        t0 = time.perf_counter()
        arrays, known = empty_arrays(centers, squares), np.zeros(len(centers), bool)
        atlas = FlowAtlas(m, arrays, xs, ys, known=known, **common)
        growing.append(atlas)
        if partial is not None:
            partial(atlas)
        build_arrays(
            m,
            per,
            centers,
            cap_v=cap_v,
            squares=squares,
            workers=workers,
            progress=progress,
            into=(arrays, known),
            focus=focus,
            **kw,
        )
        took.append(time.perf_counter() - t0)
        check_arrays(arrays, **checks)
        return arrays

    arrays, from_cache = cached_entry(
        cache_dir, "flowatlas", key, build, what="flow atlas cache entry", check=check
    )
    if from_cache:
        return FlowAtlas(m, arrays, xs, ys, from_cache=True, **common)
    atlas = growing[-1]
    atlas.a, atlas.build_s, atlas.known = arrays, took[0], None  # complete
    return atlas
