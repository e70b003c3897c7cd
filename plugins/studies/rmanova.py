"""Repeated-measures ANOVA from orthonormal contrasts (the textbook method, any number of
within-subject factors), with Mauchly's test and the Greenhouse-Geisser epsilon.

For an effect (a set of factors) the cell means ``Y`` (subjects x cells, the cells in
C order of the factors' levels) are projected on ``C = kron_f C_f``: ``C_f`` the
orthonormal Helmert contrasts of factor ``f`` when it is in the effect, else its
normalised mean ``1 / sqrt(k_f)``. With ``Z = Y C^T`` (n x p):

    SS_effect = n |mean Z|^2,  SS_error = sum |Z - mean Z|^2,
    F = (SS_effect / p) / (SS_error / (p (n - 1))),  partial eta^2 = SS_e / (SS_e + SS_err)

and with ``S`` the covariance of ``Z``: Greenhouse-Geisser ``eps = tr(S)^2 / (p tr(S^2))``,
Mauchly ``W = det S / (tr S / p)^p``, ``chi2 = -(n - 1 - (2p^2 + p + 2) / (6p)) ln W``
on ``p (p + 1) / 2 - 1`` degrees of freedom with the second-order term of its
distribution (Mauchly 1940; Anderson 1958; Greenhouse & Geisser 1959).
pingouin's two-way ``rm_anova`` gives the same F (tests/studies/test_analysis.py); it
warns its interaction epsilon may be inaccurate when both factors have more than two
levels, and it has no three-way design: this module covers both.

A degenerate effect has no F: when ``SS_error`` is zero (to rounding: below ``1e-20``
of the data's sum of squares) every subject shows the same contrasts, so the F ratio
divides by zero. With ``SS_effect`` zero too there is no variance at all (``undefined =
"no variance"``: F, p, epsilon and partial eta squared are NaN, never a p of 0); with
``SS_effect`` above zero (``"no error variance"``) F and p are NaN as well (an infinite
F is no test) while partial eta squared is 1, which it is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import combinations

import numpy as np
from scipy import stats


def helmert(k: int) -> np.ndarray:
    """(k - 1, k) orthonormal contrasts (rows orthogonal to the mean and to each other)."""
    c = np.zeros((k - 1, k))
    for i in range(1, k):
        c[i - 1, :i] = 1.0
        c[i - 1, i] = -float(i)
        c[i - 1] /= np.linalg.norm(c[i - 1])
    return c


@dataclass(frozen=True)
class EffectRow:
    source: str
    ss: float
    df1: int
    df2: int
    ss_error: float
    f: float
    p: float
    np2: float
    eps_gg: float
    p_gg: float
    mauchly_w: float
    mauchly_chi2: float
    mauchly_df: int
    mauchly_p: float
    #: why F and p are undefined (module docstring): "" (they are defined), "no variance"
    #: or "no error variance"
    undefined: str = ""

    @property
    def sphericity(self) -> str:
        """``assumed`` (Mauchly p >= 0.05 or one df), ``violated`` (p < 0.05),
        ``untestable`` (fewer subjects than the effect's df + 1: no Mauchly test) or
        ``undefined`` (no F: ``undefined`` says why)."""
        if self.undefined:
            return "undefined"
        if self.df1 < 2:
            return "assumed"
        if not np.isfinite(self.mauchly_p):
            return "untestable"
        return "violated" if self.mauchly_p < 0.05 else "assumed"

    @property
    def p_reported(self) -> float:
        """The p to report: Greenhouse-Geisser corrected unless sphericity holds."""
        return self.p if self.sphericity == "assumed" else self.p_gg

    def as_dict(self) -> dict:
        d = {k: getattr(self, k) for k in self.__dataclass_fields__}
        d["sphericity"] = self.sphericity
        d["p_reported"] = self.p_reported
        return {
            k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in d.items()
        }


def mauchly(z: np.ndarray) -> tuple[float, float, int, float]:
    """(W, chi2, df, p) of Mauchly's test on the contrast scores ``z`` (n x p); p = 1: W = 1."""
    n, p = z.shape
    if p < 2:
        return 1.0, 0.0, 0, 1.0
    if n - 1 < p:
        return math.nan, math.nan, p * (p + 1) // 2 - 1, math.nan
    s = np.cov(z, rowvar=False)
    tr = np.trace(s)
    w = float(np.linalg.det(s) / (tr / p) ** p) if tr > 0 else math.nan
    df = p * (p + 1) // 2 - 1
    if not (w > 0):
        return w, math.nan, df, math.nan
    nu = n - 1
    f = 1 - (2 * p * p + p + 2) / (6 * p * nu)
    chi2 = -nu * f * math.log(w)
    # the second-order term of the chi-square approximation (Anderson 1958, sec. 10.7)
    w2 = (p + 2) * (p - 1) * (p - 2) * (2 * p**3 + 6 * p**2 + 3 * p + 2) / (288 * (p * nu * f) ** 2)
    p1, p2 = stats.chi2.sf(chi2, df), stats.chi2.sf(chi2, df + 4)
    return w, float(chi2), df, float(min(1.0, max(0.0, p1 + w2 * (p2 - p1))))


def gg_epsilon(z: np.ndarray) -> float:
    """Greenhouse-Geisser epsilon of the contrast scores ``z`` (n x p)."""
    p = z.shape[1]
    if p < 2:
        return 1.0
    s = np.cov(z, rowvar=False)
    return float(np.trace(s) ** 2 / (p * np.trace(s @ s)))


def rm_anova(cells: np.ndarray, factors: list[str]) -> list[EffectRow]:
    """Every main effect and interaction of ``cells`` (subjects x k_1 x ... x k_m: one
    mean per subject and cell, no missing value) in the order A, B, A * B, C, ..."""
    y = np.asarray(cells, float)
    if y.ndim != len(factors) + 1:
        raise ValueError(f"cells has {y.ndim - 1} factor axes, {len(factors)} names")
    if not np.all(np.isfinite(y)):
        raise ValueError("a cell has no value")
    n, ks = y.shape[0], y.shape[1:]
    if n < 2:
        raise ValueError("need at least two subjects")
    flat = y.reshape(n, -1)
    # below this a sum of squares is rounding: contrasts of equal values give ~1e-32
    tiny = 1e-20 * float((flat**2).sum())
    rows = []
    effects = [e for r in range(1, len(factors) + 1) for e in combinations(range(len(factors)), r)]
    for eff in effects:
        c = np.ones((1, 1))
        for f, k in enumerate(ks):
            cf = helmert(k) if f in eff else np.full((1, k), 1 / math.sqrt(k))
            c = np.kron(c, cf)
        z = flat @ c.T
        p = z.shape[1]
        m = z.mean(axis=0)
        ss = float(n * m @ m)
        sse = float(((z - m) ** 2).sum())
        df1, df2 = p, p * (n - 1)
        undefined = ""
        if sse <= tiny:
            undefined = "no variance" if ss <= tiny else "no error variance"
            f = pv = eps = pgg = math.nan
            np2 = math.nan if ss <= tiny else 1.0
        else:
            f = (ss / df1) / (sse / df2)
            pv = float(stats.f.sf(f, df1, df2))
            eps = gg_epsilon(z)
            pgg = float(stats.f.sf(f, df1 * eps, df2 * eps))
            np2 = ss / (ss + sse)
        w, chi2, mdf, mp = mauchly(z)
        rows.append(
            EffectRow(
                " * ".join(factors[i] for i in eff),
                ss,
                df1,
                df2,
                sse,
                f,
                pv,
                np2,
                eps,
                pgg,
                w,
                chi2,
                mdf,
                mp,
                undefined,
            )
        )
    return rows
