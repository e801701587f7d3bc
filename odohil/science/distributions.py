"""The few distribution functions the package needs, over ``scipy.special``.

Each is the function ``scipy.stats`` would give (``chi2.sf``, ``chi2.isf``,
``chi2.ppf``, ``norm.cdf``, ``norm.sf``, ``norm.isf``, ``t.ppf``, ``f.sf``),
computed by the same ``scipy.special`` routine ``scipy.stats`` calls, so the
numbers are the same (tests/science/test_distributions.py compares them on a
grid); one more, the noncentral chi^2's noncentrality for a given probability
(``scipy.special.chndtrinc``), has no scipy.stats twin. ``scipy.stats``
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
