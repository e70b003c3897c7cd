"""Gesture classifiers: static vs dynamic from the motion over a short window (an SVM on
the motion features; the single best motion-score threshold is kept for reference),
then one SVM for static poses and one for dynamic gestures (scikit-learn Pipelines:
StandardScaler + SVC, RBF).

Hyper-parameters are searched (``grid_search``) on the training data only (inside each
outer fold when evaluating: nested cross-validation), on folds of whole subjects that a
sample more or fewer does not re-deal (``BySubject``). The static SVM takes, of the grid
points within one standard error of the best inner-CV accuracy, the most regularised
(smallest C, then smallest gamma: the one-standard-error rule, ``SIMPLEST``), so a lead of
a sample or two does not decide it; the kind and dynamic SVMs take the best mean (the
rule lowered their leave-one-subject-out dynamic accuracy). Saved models are unchanged in
form (``MODEL_FORMAT``): only which C and gamma they hold. Models are saved with skops
(never pickle) and loaded against an explicit allow-list of types.
"""

from __future__ import annotations

import json
import os
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from console.plugin_api import AT_CLI, AT_CONSOLE, Placed, UserError

from .model_checks import check_classifiers, check_settings, check_widths, retrain
from .sketch import DYNAMIC, STATIC

GESTURES = STATIC + DYNAMIC
SVC_GRID = {"svc__C": [1.0, 10.0, 100.0], "svc__gamma": ["scale", 0.003, 0.03]}
#: the classifiers whose settings ``one_standard_error`` chooses (the rest: the best mean):
#: on the kind and dynamic SVMs it took C=1 and lost 2-5 of 250 dynamic samples in the
#: twin sets' leave-one-subject-out; on the static SVM it lost none and kept the phalanx
#: renderer's closed hands apart from open ones in silhouette images (113: 24 -> 5 wrong)
SIMPLEST: tuple[str, ...] = ("static",)
#: the saved model's format; /2: one decision window (``n_frames``) for the static,
#: kind and dynamic features, the contact count as a category
MODEL_FORMAT = "haptable-gestures/9"  # 3: touching skin in mm; 4: touching = sharp (touch.py);
#: 5: soft contacts as sharp as the frame's sharpest touch, flat from 3000 mm^2, tips from 20
#: mm^2, the window's fingertip count for dynamic gestures, fingertips at their far end, the
#: moving fingertips counted (for the dynamic classifier); 6: the fingertips that met or
#: parted over the window counted (for the dynamic classifier); 7: the second and third largest
#: fingertip displacements (for the dynamic classifier); 8: the window's fingertip count is
#: the most two of its frames show (a region flickering into one frame is none); 9: pieces of
#: a fingertip joined, the static fingertip count and spacings the window's median, each
#: track's jitter pooled over the hand's tracks, the motion's shares of shift, arc and spacing
#: change, the fingertips that met or parted from what two frames at each end show (for the
#: dynamic classifier)

#: Types a saved model may contain; anything else refuses to load.
TRUSTED_TYPES = (
    "sklearn.pipeline.Pipeline",
    "sklearn.preprocessing._data.StandardScaler",
    "sklearn.svm._classes.SVC",
    "numpy.ndarray",
    "numpy.dtype",
    "numpy.float64",
    "numpy.int64",
    "numpy.int32",
    "numpy.str_",
    "builtins.str",
    "builtins.float",
    "builtins.int",
    "builtins.tuple",
    "builtins.list",
    "builtins.dict",
    "builtins.bool",
    "builtins.NoneType",
)


#: Size limits checked from the zip's directory before anything is read (a model is a
#: few hundred kB; a zip bomb declares gigabytes).
MAX_MODEL_BYTES = 64 * 1024 * 1024
MAX_SCHEMA_BYTES = 16 * 1024 * 1024
MAX_UNPACKED_BYTES = 256 * 1024 * 1024


def read_schema(path: Path) -> dict:
    """A skops file's ``schema.json``, after checking the file's and its members'
    declared sizes; ``ValueError`` (with what is wrong) if it cannot be used."""
    size = path.stat().st_size
    if size > MAX_MODEL_BYTES:
        raise ValueError(f"{size / 1e6:.0f} MB, more than a model's {MAX_MODEL_BYTES / 1e6:.0f} MB")
    with zipfile.ZipFile(path) as z:
        infos = {i.filename: i for i in z.infolist()}
        if "schema.json" not in infos:
            raise ValueError("no schema.json inside")
        unpacked = sum(i.file_size for i in infos.values())
        if infos["schema.json"].file_size > MAX_SCHEMA_BYTES or unpacked > MAX_UNPACKED_BYTES:
            raise ValueError(
                f"it unpacks to {unpacked / 1e6:.0f} MB (schema.json "
                f"{infos['schema.json'].file_size / 1e6:.0f} MB), far more than a model's few MB"
            )
        raw = z.read("schema.json")
        for name, info in infos.items():
            if name.endswith(".npy"):
                _check_npy_header(z, info)
    try:
        schema = json.loads(raw)
    except RecursionError:
        raise ValueError("schema.json nested too deeply") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"schema.json is not JSON: {e}") from None
    if not isinstance(schema, dict):
        raise ValueError("schema.json is not an object")
    return schema


def _check_npy_header(z: zipfile.ZipFile, info: zipfile.ZipInfo) -> None:
    """An array member's ``.npy`` header: a plain dtype (never objects) whose shape
    fits the member's size, read before skops builds (and allocates) the array."""
    from numpy.lib import format as npformat

    with z.open(info) as fh:
        try:
            version = npformat.read_magic(fh)
            read = {(1, 0): npformat.read_array_header_1_0, (2, 0): npformat.read_array_header_2_0}
            if version not in read:
                raise ValueError(f"npy version {version}")
            shape, _fortran, dtype = read[version](fh)
        except ValueError as e:
            raise ValueError(f"array {info.filename}: bad header ({e})") from None
    if dtype.hasobject or dtype.kind not in "biufcUS":
        raise ValueError(f"array {info.filename}: dtype {dtype} is not plain numbers or text")
    need = int(np.prod(shape, dtype=object)) * dtype.itemsize
    if need > info.file_size:
        raise ValueError(
            f"array {info.filename} declares shape {shape} ({need / 1e6:.3g} MB) in "
            f"{info.file_size} bytes"
        )


def file_types(path: Path) -> set[str]:
    """Every type (``module.Class``) a skops file would build, read from its schema
    without building anything (skops itself trusts scikit-learn types by default; this
    allow-list is stricter)."""
    schema = read_schema(path)
    out: set[str] = set()
    stack = [schema]
    while stack:
        n = stack.pop()
        if isinstance(n, dict):
            if "__class__" in n:
                out.add(f"{n.get('__module__')}.{n['__class__']}")
            stack.extend(n.values())
        elif isinstance(n, list):
            stack.extend(n)
    return out


def read_settings(path: str | Path) -> dict:
    """A saved model's settings and metadata (``meta``), read from its skops schema
    without building (or importing) anything; a one-line ``UserError`` if unreadable."""
    p = Path(path)
    try:
        content = read_schema(p)["content"]
        _check_format(json.loads(content["format"]["content"]))
        return json.loads(json.loads(content["settings"]["content"]))
    except (OSError, ValueError, KeyError, TypeError, zipfile.BadZipFile) as e:
        raise retrain(f"{p}: not a readable gesture model ({e})") from None


def _check_format(fmt: object) -> None:
    """``ValueError`` saying what the file is when ``fmt`` is not ``MODEL_FORMAT``."""
    if fmt == MODEL_FORMAT:
        return
    if isinstance(fmt, str) and fmt.startswith("haptable-gestures/"):
        raise ValueError(
            f"a {fmt} model from an older HapTable (this one reads {MODEL_FORMAT}: features "
            "changed)"
        )
    raise ValueError(f"not a {MODEL_FORMAT} model")


def make_pipeline(seed: int = 0):
    from sklearn.pipeline import Pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVC

    return Pipeline(
        [
            ("scale", StandardScaler()),
            ("svc", SVC(kernel="rbf", random_state=seed)),
        ]
    )


def inner_splitter(y: np.ndarray, groups: np.ndarray | None, folds: int, seed: int = 0):
    """Folds for choosing settings on training data: by group (subject) when there are
    at least 2, so a choice is judged on people it was not tuned on (what the outer
    leave-one-subject-out and a new user ask of it; ``BySubject``); else stratified by
    class. None when no split is possible."""
    from sklearn.model_selection import StratifiedKFold

    classes, counts = np.unique(y, return_counts=True)
    if groups is not None and len(np.unique(groups)) >= 2:
        # a gesture only one subject performed would be missing from a fold's training
        # side: by group only when every gesture has at least 2 subjects
        g = np.asarray(groups)
        per_class = min(len(np.unique(g[y == c])) for c in classes)
        k = int(min(folds, len(np.unique(g)), per_class))
        if k >= 2:
            return BySubject(k, seed)
    k = int(min(folds, counts.min()))
    return _Ungrouped(StratifiedKFold(k, shuffle=True, random_state=seed)) if k >= 2 else None


@dataclass
class BySubject:
    """``k`` folds of whole subjects, dealt round-robin in a seeded order of their names:
    a sample more or fewer moves no subject to another fold, so it changes one fold's
    scores by that sample (``StratifiedGroupKFold`` balanced the folds' class counts and
    on dropping one sample re-dealt the subjects, which flipped the chosen C)."""

    k: int
    seed: int = 0

    def split(self, x, y, groups):
        g = np.asarray(groups)
        names = np.unique(g)
        order = np.random.RandomState(self.seed).permutation(len(names))
        fold = np.empty(len(names), dtype=int)
        fold[order] = np.arange(len(names)) % self.k
        of = fold[np.searchsorted(names, g)]
        for i in range(self.k):
            yield np.flatnonzero(of != i), np.flatnonzero(of == i)


@dataclass
class _Ungrouped:
    """A class-stratified splitter that takes (and ignores) the groups argument."""

    inner: object

    def split(self, x, y, groups=None):
        return self.inner.split(x, y)


def fit_svm(
    x: np.ndarray,
    y: np.ndarray,
    *,
    groups: np.ndarray | None = None,
    inner_folds: int = 3,
    seed: int = 0,
    simplest: bool = True,
):
    """The SVM pipeline with C and gamma chosen by ``inner_folds``-fold CV on (x, y) only
    (``inner_splitter``: by subject when ``groups`` names them); returns the refitted best
    pipeline. One class: a constant predictor."""
    classes = np.unique(y)
    if len(classes) < 2:
        return _Constant(str(classes[0])) if len(classes) else None
    cv = inner_splitter(y, groups, inner_folds, seed)
    folds = [] if cv is None else list(cv.split(x, y, groups))
    # every training side needs two classes, or each of its fits fails
    if not folds or any(len(np.unique(y[tr])) < 2 for tr, _ in folds):
        return make_pipeline(seed).fit(x, y)
    best = grid_search(x, y, folds, seed, simplest=simplest)
    return make_pipeline(seed).set_params(**best).fit(x, y)


def grid_search(
    x: np.ndarray, y: np.ndarray, folds: list, seed: int = 0, *, simplest: bool = True
) -> dict:
    """The ``SVC_GRID`` point ``one_standard_error`` takes from the accuracies
    ``grid_scores`` measures over ``folds``: the most regularised of those as good as the
    best within its noise, not the best by a sample or two."""
    grid, scores = grid_scores(x, y, folds, seed)
    if not simplest:
        return grid[int(np.argmax(scores.mean(axis=1)))]
    return one_standard_error(grid, scores, scale_gamma(x))


def grid_scores(
    x: np.ndarray, y: np.ndarray, folds: list, seed: int = 0
) -> tuple[list[dict], np.ndarray]:
    """Every ``SVC_GRID`` point (in ``ParameterGrid`` order) and its accuracy on each of
    ``folds`` (points x folds): what ``GridSearchCV(make_pipeline(seed), SVC_GRID,
    cv=folds)`` scores, without its per-fit overhead (a fold's scaling is fitted once
    for its nine SVMs; a selection runs some 1500 of these small fits)."""
    from sklearn import config_context
    from sklearn.model_selection import ParameterGrid
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVC

    grid = list(ParameterGrid(SVC_GRID))
    scores = np.zeros((len(grid), len(folds)))
    x = np.ascontiguousarray(x, dtype=np.float64)
    if not np.isfinite(x).all():  # checked once here, not in each of the fits below
        raise ValueError("gesture features hold NaN or infinite values")
    # the grid's values and the arrays are checked once above: sklearn's per-call checks
    # were most of each small fit's time
    with config_context(assume_finite=True, skip_parameter_validation=True):
        for j, (tr, te) in enumerate(folds):
            scale = StandardScaler().fit(x[tr])
            xtr, xte = scale.transform(x[tr]), scale.transform(x[te])
            ytr = y[tr]
            for i, p in enumerate(grid):
                svc = SVC(kernel="rbf", C=p["svc__C"], gamma=p["svc__gamma"], random_state=seed)
                scores[i, j] = np.mean(svc.fit(xtr, ytr).predict(xte) == y[te])
    return grid, scores


def scale_gamma(x: np.ndarray) -> float:
    """The value SVC's ``gamma='scale'`` takes on ``x`` once standardised (1 / (features
    x variance)), to place 'scale' among the grid's numeric gammas."""
    from sklearn.preprocessing import StandardScaler

    z = StandardScaler().fit_transform(np.asarray(x, dtype=np.float64))
    var = float(z.var())
    return 1.0 / (z.shape[1] * var) if var > 0 else 1.0


def one_standard_error(grid: list[dict], scores: np.ndarray, scale: float) -> dict:
    """The one-standard-error rule (Hastie, Tibshirani & Friedman, ESL 7.10): among the
    points whose mean accuracy over the folds (``scores``: points x folds) is within one
    standard error of the best's, the most regularised: smallest C, then smallest gamma
    ('scale' as ``scale``), so a lead of a sample or two does not decide the model. The
    standard error is the folds' spread pooled over every point / sqrt(folds): the best
    point's own three folds near 100% spread by one sample, and its rule flipped the
    static SVM on 6 of 10 one-sample-smaller twin sets (pooled: 1 of 10)."""
    mean = scores.mean(axis=1)
    best = int(np.argmax(mean))
    k = scores.shape[1]
    se = float(np.sqrt(np.mean(np.var(scores, axis=1, ddof=1))) / np.sqrt(k)) if k > 1 else 0.0
    near = np.flatnonzero(mean >= mean[best] - se - 1e-12)

    def strength(i: int) -> tuple[float, float]:
        g = grid[i]["svc__gamma"]
        return float(grid[i]["svc__C"]), scale if isinstance(g, str) else float(g)

    return grid[int(min(near, key=strength))]


def _part(groups: np.ndarray | None, mask: np.ndarray) -> np.ndarray | None:
    return None if groups is None else groups[mask]


@dataclass
class _Constant:
    label: str

    def predict(self, x):
        return np.array([self.label] * len(x))


def fit_threshold(score: np.ndarray, dynamic: np.ndarray) -> float:
    """The motion threshold with the fewest errors (static: score <= threshold)."""
    s = np.sort(np.unique(score))
    if len(s) == 0:
        return 0.1
    cands = np.concatenate([[s[0] - 1e-6], (s[:-1] + s[1:]) / 2, [s[-1] + 1e-6]])
    errs = [np.sum((score > c) != dynamic) for c in cands]
    best = np.flatnonzero(np.array(errs) == min(errs))
    return float(cands[best[len(best) // 2]])


@dataclass
class GestureModel:
    """Fitted classifiers and the settings their features were built with."""

    static_svm: object
    dynamic_svm: object
    kind_svm: object
    motion_threshold: float
    n_harmonics: int = 2
    n_frames: int = 4  # every decision is made from the first n_frames frames
    meta: dict = field(default_factory=dict)

    @classmethod
    def fit(
        cls,
        xs: np.ndarray,
        xd: np.ndarray,
        xk: np.ndarray,
        score: np.ndarray,
        labels: np.ndarray,
        *,
        n_harmonics: int,
        n_frames: int,
        seed: int = 0,
        meta: dict | None = None,
        kind_svm: object | None = None,
        groups: np.ndarray | None = None,
    ) -> GestureModel:
        """Fit on static features ``xs``, dynamic ``xd``, motion (kind) features ``xk``
        and the motion ``score`` (``kind_svm``: one already fitted on the same samples;
        ``groups``: each sample's subject, so C and gamma are chosen across people)."""
        labels = np.asarray(labels).astype(str)
        is_dyn = np.isin(labels, DYNAMIC)
        thr = fit_threshold(score, is_dyn)
        g = None if groups is None else np.asarray(groups)
        kind = kind_svm
        if kind is None:
            y = np.where(is_dyn, "dynamic", "static")
            kind = fit_svm(xk, y, groups=g, seed=seed, simplest="kind" in SIMPLEST)
        st = dy = None
        if np.any(~is_dyn):
            st = fit_svm(
                xs[~is_dyn], labels[~is_dyn], groups=_part(g, ~is_dyn), seed=seed,
                simplest="static" in SIMPLEST,
            )  # fmt: skip
        if np.any(is_dyn):
            dy = fit_svm(
                xd[is_dyn], labels[is_dyn], groups=_part(g, is_dyn), seed=seed,
                simplest="dynamic" in SIMPLEST,
            )  # fmt: skip
        return cls(st, dy, kind, thr, n_harmonics, n_frames, dict(meta or {}))

    def svm_settings(self) -> dict[str, dict[str, float | str] | None]:
        """C and gamma each SVM was fitted with (chosen by cross-validation in ``fit_svm``),
        by classifier (``static``, ``dynamic``, ``kind``)."""
        from sklearn.pipeline import Pipeline

        out: dict[str, dict[str, float | str] | None] = {}
        for name, svm in (
            ("static", self.static_svm),
            ("dynamic", self.dynamic_svm),
            ("kind", self.kind_svm),
        ):
            out[name] = None
            if isinstance(svm, Pipeline):
                svc = svm.named_steps["svc"]
                gamma = svc.gamma if isinstance(svc.gamma, str) else float(svc.gamma)
                out[name] = {"C": float(svc.C), "gamma": gamma}
        return out

    def kind(self, xk: np.ndarray) -> np.ndarray:
        """True where the motion says dynamic."""
        if self.kind_svm is None:
            return np.zeros(len(xk), dtype=bool)
        return np.asarray(self.kind_svm.predict(xk)) == "dynamic"

    def predict(self, xs: np.ndarray, xd: np.ndarray, xk: np.ndarray) -> np.ndarray:
        dyn = self.kind(xk)
        out = np.empty(len(dyn), dtype=object)
        if np.any(~dyn):
            out[~dyn] = self._pred(self.static_svm, xs[~dyn], STATIC[0])
        if np.any(dyn):
            out[dyn] = self._pred(self.dynamic_svm, xd[dyn], DYNAMIC[0])
        return out.astype(str)

    @staticmethod
    def _pred(svm, x, default):
        if svm is None:
            return np.array([default] * len(x))
        return svm.predict(x)

    def confidence(self, xs, xd, xk) -> np.ndarray:
        """A 0..1 margin-based confidence per sample (1 - exp(-margin))."""
        dyn = self.kind(xk)
        out = np.zeros(len(dyn))
        for mask, svm, x in ((~dyn, self.static_svm, xs), (dyn, self.dynamic_svm, xd)):
            if np.any(mask) and hasattr(svm, "decision_function"):
                d = np.atleast_2d(svm.decision_function(x[mask]))
                top = np.sort(d, axis=1)
                margin = top[:, -1] - (top[:, -2] if top.shape[1] > 1 else 0)
                out[mask] = 1 - np.exp(-np.abs(margin))
        return out

    # ------------------------------------------------------------------ persistence
    def save(self, path: str | Path) -> Path:
        import skops.io as sio

        for svm in (self.static_svm, self.dynamic_svm, self.kind_svm):
            if isinstance(svm, _Constant):
                raise UserError("gesture model: a class set of one cannot be saved; train on more")
        obj = {
            "format": MODEL_FORMAT,
            "static_svm": self.static_svm,
            "dynamic_svm": self.dynamic_svm,
            "kind_svm": self.kind_svm,
            "settings": json.dumps(
                {
                    "motion_threshold": self.motion_threshold,
                    "n_harmonics": self.n_harmonics,
                    "n_frames": self.n_frames,
                    "meta": self.meta,
                }
            ),
        }
        p = Path(path)
        tmp = p.with_name(f".{p.name}.partial")
        try:  # write then rename: a reader never sees half a model
            sio.dump(obj, tmp)
            os.replace(tmp, p)
        finally:
            tmp.unlink(missing_ok=True)
        return p

    @classmethod
    def load(cls, path: str | Path, *, check_features: bool = True) -> GestureModel:
        """Load a saved model: types against the allow-list, settings, every
        classifier's arrays, and (``check_features``) their widths against the features
        the vision pipeline makes; a one-line ``UserError`` for anything wrong."""
        import skops.io as sio

        p = Path(path)
        if not p.is_file():
            raise Placed(
                f"{p}: no gesture model there",
                {
                    AT_CLI: "make one with `haptable gestures train`",
                    AT_CONSOLE: "train one: Camera (F2), g, then t",
                },
            )
        try:
            found = file_types(p)
        except (OSError, ValueError, KeyError, zipfile.BadZipFile) as e:
            raise retrain(f"{p}: not a skops gesture model ({e})") from None
        except RecursionError:
            raise retrain(f"{p}: skops schema nested too deeply") from None
        bad = sorted(found - set(TRUSTED_TYPES))
        if bad:
            raise retrain(
                f"{p}: contains types outside the allow-list ({', '.join(bad)}); "
                "refusing to load it"
            )
        try:
            obj = sio.load(p, trusted=sorted(found))
        except Exception as e:
            raise retrain(f"{p}: cannot load the gesture model ({e})") from None
        try:
            _check_format(obj.get("format") if isinstance(obj, dict) else None)
        except ValueError as e:
            raise retrain(f"{p}: {e}") from None
        s = check_settings(obj.get("settings"), p)
        svms = {k: obj.get(k) for k in ("static_svm", "dynamic_svm", "kind_svm")}
        check_classifiers(svms, p)
        model = cls(
            svms["static_svm"],
            svms["dynamic_svm"],
            svms["kind_svm"],
            s["motion_threshold"],
            s["n_harmonics"],
            s["n_frames"],
            s["meta"],
        )
        if check_features:
            check_widths(model, p)
        return model
