"""Closed forms of the observables' means for the forth-and-back motion (section 4).

The robot drives M = 2k straight legs of length l (k a multiple of 1/2). With

    z = K_theta l / 2 + i E_R l                                   (eq. 35)

and the entire functions phi_1(w) = (e^w - 1)/w, phi_2(w) = (e^w - 1 - w)/w^2,
every mean is a short expression in z. The forms used here are derived from
the path integrals eqs. (29), (30), (32) with the decay e^{-K_theta s/2}
(see docs/science.md); they are written so that z -> 0 and the removable
singularities of the printed geometric sums (e^{-z} = -1, e.g. E_R l = pi)
evaluate to their limits rather than to 0/0:

- ``turn``: <x> - i<y> = (1+E_T) l phi_1(-z) S(-e^{-z}, M)  (eqs. 36-39 for
  any M), with S(q, M) = sum_{m<M} q^m;
  <phi5> = K_rho rho + 2 (1+E_T)^2 l^2 Re[M phi_2(-z) - phi_1(-z)^2 W(-e^{-z}, M)]
  with W(q, M) = sum_{d=1}^{M-1} (M-d) q^{d-1}. For even M this equals eq. (40)
  with e^{2kz} replaced by e^{-2kz}: the printed sign is wrong.
- ``reverse``: backward legs flip the translation and run the E_R drift
  backwards (see :mod:`odohil.science.paths`); the means are derived the same
  way and given in :func:`forth_and_back_means`.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import asdict, dataclass

import numpy as np

from odohil.science.parameters import ErrorParameters
from odohil.science.paths import Design

_DIRECT_SUM_RADIUS = 0.5
"""Geometric sums with |1 - q| below this are summed term by term: the closed
form divides by (1 - q) and would lose digits there."""

_PHI2_SERIES_RADIUS = 1.0
_PHI2_SERIES_TERMS = 24


@dataclass(frozen=True)
class ObservableMeans:
    """Expected values of the observables of one design (eqs. 15-19), SI.

    Attributes:
        phi1: mean heading change minus the winding, rad.
        phi2: variance of the heading change, rad^2.
        phi3: mean x of the end point, m (= x).
        phi4: mean y of the end point, m (= y).
        phi5: mean squared distance from start to end point, m^2.
        x: mean x of the end point, m.
        y: mean y of the end point, m.
    """

    phi1: float
    phi2: float
    phi3: float
    phi4: float
    phi5: float
    x: float
    y: float

    def as_dict(self) -> dict[str, float]:
        """The seven values, keyed phi1..phi5, x, y (SI)."""
        return asdict(self)


def phi1(w: complex) -> complex:
    """(e^w - 1)/w, with its limit 1 at w = 0; accurate for small |w|."""
    if w == 0:
        return 1.0 + 0.0j
    return complex(np.expm1(complex(w))) / w


def phi2(w: complex) -> complex:
    """(e^w - 1 - w)/w^2, with its limit 1/2 at w = 0; accurate for small |w|."""
    if abs(w) < _PHI2_SERIES_RADIUS:
        # sum_n w^n / (n+2)!, Horner from the highest term
        total = 0.0 + 0.0j
        for n in range(_PHI2_SERIES_TERMS, -1, -1):
            total = total * w + 1.0 / math.factorial(n + 2)
        return total
    return (complex(np.expm1(complex(w))) - w) / (w * w)


def geometric_sum(q: complex, m: int) -> complex:
    """S(q, m) = sum_{j=0}^{m-1} q^j."""
    if m <= 0:
        return 0.0j
    if abs(1.0 - q) < _DIRECT_SUM_RADIUS:
        powers = np.power(complex(q), np.arange(m))
        return complex(powers.sum())
    return (1.0 - q**m) / (1.0 - q)


def weighted_geometric_sum(q: complex, m: int) -> complex:
    """W(q, m) = sum_{d=1}^{m-1} (m - d) q^(d-1): pairs of legs d apart, weighted
    by how many such pairs there are."""
    if m <= 1:
        return 0.0j
    if abs(1.0 - q) < _DIRECT_SUM_RADIUS:
        d = np.arange(1, m)
        return complex(((m - d) * np.power(complex(q), d - 1)).sum())
    return (m * (1.0 - q) - (1.0 - q**m)) / ((1.0 - q) ** 2)


def z_parameter(design: Design, params: ErrorParameters) -> complex:
    """z = K_theta l/2 + i E_R l (eq. 35), no unit."""
    return complex(params.k_theta * design.l_m / 2.0, params.e_r * design.l_m)


def forth_and_back_means(design: Design, params: ErrorParameters) -> ObservableMeans:
    """Expected phi1..phi5, <x>, <y> of one forth-and-back design (SI).

    ``turn`` (eqs. 33-40, corrected and generalised to M = 2k legs): see the
    module docstring.

    ``reverse``: with kappa = K_theta l/2, eps = E_R l (z = kappa + i eps),
    M_e = ceil(M/2) forward and M_o = floor(M/2) backward legs,

        <x> + i<y> = (1+E_T) l [S(e^{-2 kappa}, M_e) phi_1(-conj z)
                                 - e^{-conj z} phi_1(-z) S(e^{-2 kappa}, M_o)]
        <phi5> = K_rho rho + 2 (1+E_T)^2 l^2 Re[M phi_2(-z)
                  + e^{i eps} phi_1(-z)^2 W_even - |phi_1(-z)|^2 W_odd]

    where W_even, W_odd are the parts of W(e^{-kappa}, M) with even and odd
    leg distance d. phi1 is E_R times the signed distance (0 for even M).

    A backward design is the mirror image (see :mod:`odohil.science.paths`):
    phi1 and <x> change sign, the rest is unchanged.
    """
    if design.backward:
        ahead = forth_and_back_means(design.forward, params)
        return ObservableMeans(
            phi1=-ahead.phi1 + 0.0,
            phi2=ahead.phi2,
            phi3=-ahead.phi3,
            phi4=ahead.phi4,
            phi5=ahead.phi5,
            x=-ahead.x,
            y=ahead.y,
        )
    m = design.n_legs
    length = design.l_m
    gain = 1.0 + params.e_t
    rho = design.distance_m
    z = z_parameter(design, params)
    kappa, eps = z.real, z.imag
    if design.variant == "turn":
        conj_mean = gain * length * phi1(-z) * geometric_sum(-cmath.exp(-z), m)
        mean = conj_mean.conjugate()
        drift = m * phi2(-z) - phi1(-z) ** 2 * weighted_geometric_sum(-cmath.exp(-z), m)
        signed = rho
    else:
        q = math.exp(-2.0 * kappa)
        n_forward, n_backward = (m + 1) // 2, m // 2
        mean = (
            gain
            * length
            * (
                geometric_sum(q, n_forward) * phi1(-z.conjugate())
                - cmath.exp(-z.conjugate()) * phi1(-z) * geometric_sum(q, n_backward)
            )
        )
        r = math.exp(-kappa)
        w_plus = weighted_geometric_sum(r, m)
        w_minus = weighted_geometric_sum(-r, m)
        w_odd, w_even = (w_plus + w_minus) / 2.0, (w_plus - w_minus) / 2.0
        p = phi1(-z)
        drift = m * phi2(-z) + cmath.exp(1j * eps) * p * p * w_even - abs(p) ** 2 * w_odd
        signed = length if m % 2 else 0.0
    phi5 = params.k_rho * rho + 2.0 * gain**2 * length**2 * drift.real
    return ObservableMeans(
        phi1=params.e_r * signed + 0.0,  # no -0.0 for a closed reverse path
        phi2=params.k_theta * rho,
        phi3=mean.real,
        phi4=mean.imag,
        phi5=phi5,
        x=mean.real,
        y=mean.imag,
    )
