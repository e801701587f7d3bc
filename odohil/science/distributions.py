"""The few distribution functions the package needs, over ``scipy.special``.

Each is the function ``scipy.stats`` would give (``chi2.sf``, ``chi2.isf``,
``chi2.ppf``, ``norm.cdf``, ``norm.sf``, ``norm.isf``, ``t.ppf``, ``f.sf``,
``f.isf``),
computed by the same ``scipy.special`` routine ``scipy.stats`` calls, so the
numbers are the same (tests/science/test_distributions.py compares them on a
grid); two more have no scipy.stats twin: the noncentral chi^2's
noncentrality for a given probability (``scipy.special.chndtrinc``), and the
survival of a weighted sum of noncentral chi^2's (:func:`quadratic_form_sf`,
Imhof's integral by ``scipy.integrate.quad``, imported at its first call). ``scipy.stats``
itself is not imported: it costs about 1 s of CPU at every process's start
(it pulls in scipy.optimize, scipy.spatial, ...) and each of its calls is
some 50 times slower than the routine underneath. Nor is ``scipy.special``
imported with this module: it is imported at the first call (:func:`_special`),
as it costs about 0.3 s of CPU (scipy's array-API layer imports numpy.f2py,
numpy.testing, numpy.ma, ...), which a command that computes no
probability (``--help``, ``odohil emulate``, a refused option) need not pay.

As in ``scipy.stats``: a non-positive number of degrees of freedom gives NaN;
a point below the support (x < 0 for chi^2 and F) has survival 1.
Probabilities are plain fractions; the statistics are dimensionless.
"""

from __future__ import annotations

import functools
import importlib
import math
from types import ModuleType

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


@functools.cache
def _special() -> ModuleType:
    """``scipy.special``, imported at the first call (module docstring)."""
    return importlib.import_module("scipy.special")


def chi2_sf(x: float, dof: float) -> float:
    """P(X > x) for X ~ chi^2(dof)."""
    if not dof > 0:
        return math.nan
    return float(_special().chdtrc(dof, max(x, 0.0)))


def chi2_sf_each(x: FloatArray, dof: float) -> FloatArray:
    """:func:`chi2_sf` of each element of ``x`` (same shape)."""
    values = np.asarray(x, dtype=np.float64)
    if not dof > 0:
        return np.full(values.shape, math.nan)
    out: FloatArray = np.asarray(_special().chdtrc(dof, np.maximum(values, 0.0)), dtype=np.float64)
    return out


def chi2_isf(q: float, dof: float) -> float:
    """The x with P(X > x) = q for X ~ chi^2(dof)."""
    if not dof > 0:
        return math.nan
    return float(_special().chdtri(dof, q))


def chi2_ppf(p: float, dof: float) -> float:
    """The x with P(X <= x) = p for X ~ chi^2(dof)."""
    if not dof > 0:
        return math.nan
    return float(2.0 * _special().gammaincinv(dof / 2.0, p))


def norm_cdf(z: float) -> float:
    """P(Z <= z) for Z standard normal."""
    return float(_special().ndtr(z))


def norm_sf(z: float) -> float:
    """P(Z > z) for Z standard normal."""
    return float(_special().ndtr(-z))


def norm_isf(q: float) -> float:
    """The z with P(Z > z) = q for Z standard normal."""
    return float(-_special().ndtri(q))


def t_ppf(p: float, dof: float) -> float:
    """The x with P(T <= x) = p for T ~ Student's t(dof); dof may be infinite."""
    if not dof > 0:
        return math.nan
    if p == 0.0:  # stdtrit gives +inf there
        return -math.inf
    return float(_special().stdtrit(dof, p))


def ncx2_noncentrality(x: float, dof: float, cdf: float) -> float:
    """The noncentrality nc with P(X <= x) = cdf for X ~ noncentral chi^2(dof, nc)
    (``scipy.special.chndtrinc``; scipy.stats has no such inverse)."""
    if not dof > 0:
        return math.nan
    return float(_special().chndtrinc(x, dof, cdf))


def ncx2_sf(x: float, dof: float, nc: float) -> float:
    """P(X > x) for X ~ noncentral chi^2(dof, nc) (``scipy.special.chndtr``)."""
    if not dof > 0:
        return math.nan
    return float(1.0 - _special().chndtr(max(x, 0.0), dof, max(nc, 0.0)))


def f_sf(x: float, dof_num: float, dof_den: float) -> float:
    """P(X > x) for X ~ F(dof_num, dof_den)."""
    if not (dof_num > 0 and dof_den > 0):
        return math.nan
    return float(_special().fdtrc(dof_num, dof_den, max(x, 0.0)))


@functools.cache
def _integrate() -> ModuleType:
    """``scipy.integrate``, imported at the first call (about 0.16 s of CPU)."""
    return importlib.import_module("scipy.integrate")


def quadratic_form_sf(
    x: float,
    weights: npt.ArrayLike,
    dofs: npt.ArrayLike,
    noncentralities: npt.ArrayLike | None = None,
) -> float:
    """P(Q > x) for Q = sum_j w_j X_j, X_j ~ noncentral chi^2(h_j, nc_j)
    independent, w_j >= 0: the law of a Gaussian vector's quadratic form.

    Imhof (1961): P(Q > x) = 1/2 + (1/pi) int_0^inf sin(t(u)) / (u r(u)) du with
    t(u) = 1/2 sum_j (h_j atan(w_j u) + nc_j w_j u / (1 + w_j^2 u^2)) - x u / 2 and
    r(u) = prod_j (1 + w_j^2 u^2)^(h_j / 4) exp(1/2 sum_j nc_j w_j^2 u^2 / (1 + w_j^2 u^2)).
    Equal weights are the noncentral chi^2 itself (:func:`ncx2_sf`). Accurate
    to about 1e-8 (tests/science/test_distributions.py checks it against
    draws of the sum).
    """
    w = np.asarray(weights, dtype=np.float64).ravel()
    h = np.broadcast_to(np.asarray(dofs, dtype=np.float64), w.shape).copy()
    nc = np.zeros_like(w)
    if noncentralities is not None:
        nc = np.broadcast_to(np.asarray(noncentralities, dtype=np.float64), w.shape).copy()
    keep = w > 1e-14 * (float(w.max()) if w.size else 0.0)
    w, h, nc = w[keep], h[keep], nc[keep]
    if w.size == 0 or not np.all(h > 0):
        return math.nan if w.size else float(x < 0)
    if float(w.max() - w.min()) <= 1e-12 * float(w.max()):
        return ncx2_sf(x / float(w[0]), float(h.sum()), float(nc.sum()))

    terms = list(zip(w.tolist(), h.tolist(), nc.tolist(), strict=True))  # floats: fast

    def log_r(u: float) -> float:
        out = 0.0
        for wj, hj, ncj in terms:
            wu2 = (wj * u) ** 2
            out += 0.25 * hj * math.log1p(wu2) + 0.5 * ncj * wu2 / (1.0 + wu2)
        return out

    def phase(u: float) -> float:
        out = 0.0
        for wj, hj, ncj in terms:
            wu = wj * u
            out += hj * math.atan(wu) + ncj * wu / (1.0 + wu * wu)
        return 0.5 * out

    def integrand(u: float) -> float:
        return math.sin(phase(u) - 0.5 * x * u) * math.exp(-log_r(u)) / u

    if x <= 0.0:
        return 1.0
    # Q <= max(w) chi^2(sum h, sum nc): far beyond the bulk (a threshold of a
    # spread with few degrees of freedom) that bound is the answer to 1e-12,
    # where Imhof's integrand would oscillate too fast to integrate
    bound = ncx2_sf(x / float(w.max()), float(h.sum()), float(nc.sum()))
    if bound < 1e-12:
        return bound
    quad = _integrate().quad
    # the bulk on doubling pieces from its scale up to u = 10 / max(w) (or
    # until r(u) has grown by e^30); beyond, sin(phase - x u / 2) is split into
    # Fourier integrals of smooth functions (QAWF): accurate to about 1e-8
    edge = 1.0 / (float(w.max()) * math.sqrt(float(h.sum()) + float(nc.sum()) + 1.0))
    total = float(quad(integrand, 0.0, edge, limit=400, epsabs=1e-9)[0])
    while log_r(edge) < 30.0 and edge * float(w.max()) < 10.0:
        total += float(quad(integrand, edge, 2.0 * edge, limit=400, epsabs=1e-9)[0])
        edge *= 2.0
    if log_r(edge) < 30.0:

        def even(u: float) -> float:
            return math.sin(phase(u)) * math.exp(-log_r(u)) / u

        def odd(u: float) -> float:
            return math.cos(phase(u)) * math.exp(-log_r(u)) / u

        tail = quad(even, edge, math.inf, weight="cos", wvar=0.5 * x, limlst=100)[0]
        tail -= quad(odd, edge, math.inf, weight="sin", wvar=0.5 * x, limlst=100)[0]
        total += float(tail)
    return min(1.0, max(0.0, 0.5 + total / math.pi))


def f_isf(q: float, dof_num: float, dof_den: float) -> float:
    """The x with P(X > x) = q for X ~ F(dof_num, dof_den), by the beta law of
    dof_den / (dof_den + dof_num X) (accurate in the far tail, where 1 - q
    would round); ``dof_den`` infinite is chi^2(dof_num) / dof_num."""
    if not (dof_num > 0 and dof_den > 0):
        return math.nan
    if math.isinf(dof_den):
        return chi2_isf(q, dof_num) / dof_num
    w = float(_special().betaincinv(0.5 * dof_den, 0.5 * dof_num, q))
    return math.inf if w <= 0.0 else dof_den * (1.0 - w) / (dof_num * w)


def chi2_estimated_scale_sf(x: float, dof: float, scale_dof: float) -> float:
    """P(X > x) for X = Y / (V / scale_dof), Y ~ chi^2(dof), V ~ chi^2(scale_dof)
    independent: a chi^2 statistic whose variance was divided by an estimate
    of it from ``scale_dof`` squares (X / dof ~ F(dof, scale_dof)); an
    infinite ``scale_dof`` is :func:`chi2_sf`."""
    if math.isinf(scale_dof):
        return chi2_sf(x, dof)
    return f_sf(x / dof, dof, scale_dof) if dof > 0 else math.nan


def chi2_estimated_scale_isf(q: float, dof: float, scale_dof: float) -> float:
    """The x with :func:`chi2_estimated_scale_sf` (x, dof, scale_dof) = q."""
    return dof * f_isf(q, dof, scale_dof) if dof > 0 else math.nan
