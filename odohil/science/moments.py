"""Exact moments of one trial's pose change for any encoder path (N -> infinity).

Model (eqs. 1-14 in the continuum limit), s the distance driven:

    theta(s) = thetatilde(s) + W(s),   thetatilde(s) = thetabar(s) + E_R u(s)
    Z = x + i y = int_0^rho e^{i theta(s)} (sigma(s) (1+E_T) ds + dW_rho(s))

with W a Brownian motion of variance K_theta s, W_rho one of variance K_rho s,
u(s) the signed encoder distance and sigma(s) = +-1 the travel sign. Delta is
the heading change minus the path's winding, as the simulator reports it.
Writing A(s) = (1+E_T) sigma(s) e^{i thetatilde(s)}:

    E[Z]        = int A(s) e^{-K s/2} ds                            (eqs. 29, 30)
    E|Z|^2      = int int A(s) conj A(s') e^{-K|s-s'|/2} + K_rho rho  (eq. 32)
    E[Z^2]      = int int A(s) A(s') e^{-(4K min(s,s') + K|s-s'|)/2}
                  + K_rho int e^{2 i thetatilde(s)} e^{-2 K s} ds
    Cov(Delta,Z)= int A(s) (i K s) e^{-K s/2} ds                      (Stein's lemma)
    Var Delta   = K rho,   E[Delta] = net turn - winding + E_R u(rho)

(K = K_theta).

Turn errors (a differential drive, :class:`TurnErrors`): a turn of encoder
angle a in class c (spin or arc, ccw or cw: odohil/science/paths.py
TURN_CLASSES) really turns a (1 + e_c), and a spin adds N(0, K_spin |a|).
Then thetatilde(s) gains sum_c e_c P_c(s) (P_c(s) the signed angle of the
class-c turns before s), and the heading noise X(s) = W(s) + the spins'
noise before s has the variance V(s) = K s + K_spin S(s) (S(s) the |angle|
spun before s), with independent increments. Every factor above is
E[e^{i(X(s) -+ X(s'))}], so the formulas hold with K s replaced by V(s):
e^{-K|s - s'|/2} by e^{-|V(s) - V(s')|/2}, e^{-(4K min + K|s - s'|)/2} by
e^{-(3 V(s) + V(s'))/2} (s < s'), the K_rho term's e^{-2Ks} by e^{-2V(s)},
and Cov(Delta, Z) = int A(s) i V(s) e^{-V(s)/2} ds (Stein's lemma again:
Delta's noise is X(s) plus later independent increments). Var Delta =
K rho + K_spin S(rho), E[Delta] gains sum_c e_c P_c(rho). V jumps only
between legs, so on every leg it is K s plus a constant and the one-leg
integrals below are unchanged; only the factors between legs gain the jumps.
tests/science/test_turn_moments.py checks all of it against a Monte Carlo
simulation of the discrete model (odohil/science/diff_drive.py
:func:`~odohil.science.diff_drive.simulate_turn_errors`).

On a leg A is a complex exponential in s, and for s < s' both
kernels factorise, so pairs of distinct legs reduce to products of one-leg
integrals (a recurrence over legs, O(legs)); same-leg double integrals reduce
to one-dimensional ones. A one-leg integral whose integrand turns or decays
by a bounded amount ((2|E_R| + 2K) L <= 2) is done by one 12-node
Gauss-Legendre panel (about 1e-13 relative accuracy); a longer leg's by closed
forms in phi1(z) = (e^z - 1)/z and phi2(z) = (e^z - 1 - z)/z^2, whose
arguments then have |z| >= 1/3. So a leg costs the same whatever its length,
and a path costs O(legs).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any

import numpy as np
import numpy.typing as npt

from odohil.science.closed_forms import ObservableMeans
from odohil.science.parameters import ErrorParameters
from odohil.science.paths import TURN_CLASSES, EncoderPath, FloatArray

_NODES = 12
"""Gauss-Legendre nodes per panel."""
_PANEL_RATE_LENGTH = 2.0
"""Largest |rate| * length of a leg done by quadrature: with 12 nodes the
error is below 1e-14; longer legs use the closed forms."""

ComplexArray = npt.NDArray[np.complexfloating[Any, Any]]
IntArray = npt.NDArray[np.intp]


@dataclass(frozen=True)
class PoseMoments:
    """Mean and covariance of one trial's pose change (x m, y m, Delta rad).

    Attributes:
        mean: shape (3,): <x> (m), <y> (m), <Delta> (rad).
        cov: shape (3, 3): covariance of (x, y, Delta), units m^2, m rad, rad^2.
    """

    mean: FloatArray
    cov: FloatArray

    @property
    def mean_square_distance(self) -> float:
        """<x^2 + y^2>, m^2: the expected phi5 (a raw second moment)."""
        return float(self.cov[0, 0] + self.cov[1, 1] + self.mean[0] ** 2 + self.mean[1] ** 2)


@dataclass(frozen=True)
class TurnErrors:
    """A differential drive's turn errors (module docstring), per turn class.

    Attributes:
        spin_ccw, spin_cw, arc_ccw, arc_cw: e_turn of the turns of that class
            (no unit; a turn of encoder angle a really turns a (1 + e_turn)).
        k_spin: heading variance per radian spun in place, rad^2/rad (arcs
            carry none of their own: their noise is K_theta's along the legs).
    """

    spin_ccw: float = 0.0
    spin_cw: float = 0.0
    arc_ccw: float = 0.0
    arc_cw: float = 0.0
    k_spin: float = 0.0

    @classmethod
    def uniform(cls, e_turn: float, k_spin: float = 0.0) -> TurnErrors:
        """One e_turn for every turn."""
        return cls(e_turn, e_turn, e_turn, e_turn, k_spin)

    @classmethod
    def of(cls, scales: FloatArray, k_spin: float = 0.0) -> TurnErrors:
        """From the (4,) e_turn of :attr:`scales`' order and K_spin."""
        spin_ccw, spin_cw, arc_ccw, arc_cw = (float(v) for v in scales)
        return cls(spin_ccw, spin_cw, arc_ccw, arc_cw, k_spin)

    @property
    def scales(self) -> FloatArray:
        """(4,) e_turn in the order of odohil/science/paths.py TURN_CLASSES."""
        return np.array([self.spin_ccw, self.spin_cw, self.arc_ccw, self.arc_cw])

    @property
    def exact(self) -> bool:
        """Whether every turn is exact (all zero)."""
        return not np.any(self.scales) and self.k_spin == 0.0


@lru_cache(maxsize=1)
def _gauss_legendre() -> tuple[FloatArray, FloatArray]:
    """Nodes and weights on [0, 1]."""
    x, w = np.polynomial.legendre.leggauss(_NODES)
    return (x + 1.0) / 2.0, w / 2.0


def _expm1_over(w: ComplexArray) -> ComplexArray:
    """phi_1(w) = (e^w - 1)/w elementwise, 1 where w = 0."""
    out = np.ones_like(w)
    nonzero = w != 0
    out[nonzero] = np.expm1(w[nonzero]) / w[nonzero]
    return out


def _phi1(z: ComplexArray) -> ComplexArray:
    """(e^z - 1)/z for |z| >= 1/3 (the long legs' arguments)."""
    out: ComplexArray = np.expm1(z) / z
    return out


def _phi2(z: ComplexArray) -> ComplexArray:
    """(e^z - 1 - z)/z^2 for |z| >= 1/3."""
    out: ComplexArray = (np.expm1(z) - z) / (z * z)
    return out


def _long_leg_integrals(
    length: FloatArray, omega: FloatArray, k: float | FloatArray
) -> tuple[ComplexArray, ...]:
    """The seven one-leg integrals of :func:`pose_moments` in closed form, for
    legs with (2|E_R| + 2K) L > 2, where every argument below has |z| >= 1/3
    and a real part <= 0 (no overflow, no cancellation worth the name).

    With c1 = i omega - K/2, c3 = i omega - 3K/2 and z = c L:
    int e^{c t} = L phi1(z); int (L - t) e^{c t} = L^2 phi2(z);
    int t e^{c t} = L^2 (phi1(z) - phi2(z));
    int e^{i omega t} e^{-K (L - t)/2} = e^{i omega L} L phi1((-i omega - K/2) L);
    int t e^{c1 t} (e^{c3 t} - 1)/(c3 t) = L (phi1((c1 + c3) L) - phi1(c1 L)) / c3.
    """
    c1: ComplexArray = 1j * omega - 0.5 * k
    c3: ComplexArray = 1j * omega - 1.5 * k
    z1 = c1 * length
    i_mean = length * _phi1(z1)
    i_tail = np.exp(1j * omega * length) * length * _phi1((-1j * omega - 0.5 * k) * length)
    i_same_abs = length**2 * _phi2(z1)
    i_stein = length**2 * (_phi1(z1) - _phi2(z1))
    i_f = length * _phi1((1j * omega - 1.5 * k) * length)
    z13: ComplexArray = (c1 + c3) * length
    i_same_sq = length * (_phi1(z13) - _phi1(z1)) / c3
    i_noise = length * _phi1((2j * omega - 2.0 * k) * length)
    return (i_mean, i_tail, i_same_abs, i_stein, i_f, i_same_sq, i_noise)


def pose_moments(
    path: EncoderPath, params: ErrorParameters, turns: TurnErrors | None = None
) -> PoseMoments:
    """Mean vector and 3x3 covariance of (x, y, Delta) for one trial of ``path``.

    Args:
        path: the encoder path.
        params: the error parameters (SI).
        turns: the turns' errors (None: exact turns, the paper's model).

    Returns:
        A :class:`PoseMoments` in SI (m, rad).
    """
    legs = path.legs
    k = params.k_theta
    gain = 1.0 + params.e_t
    length = legs.length_m
    start = legs.start_arc_m
    omega = params.e_r * legs.sign
    # A(a_j + t) = alpha_j e^{i omega_j t} on leg j, t in [0, L_j]
    phase = legs.heading_rad + params.e_r * legs.start_signed_m
    # the spins' heading variance before each leg (the jumps of V), rad^2
    jump = np.zeros(length.size)
    turn_mean, turn_var = 0.0, 0.0
    if turns is not None and not turns.exact:
        table = path.turns
        scales = turns.scales
        phase = phase + scales @ table.before_rad
        jump = turns.k_spin * table.spin_before_rad
        turn_mean = float(scales @ table.total_rad)
        turn_var = turns.k_spin * table.spin_total_rad
    alpha = gain * legs.sign * np.exp(1j * phase)
    # V(s) at each leg's start: K a_j + J_j
    v_start = k * start + jump

    # legs whose integrands turn by a bounded phase: one Gauss-Legendre panel;
    # the others by closed forms in phi1, phi2 (cost independent of the length)
    rate = 2.0 * abs(params.e_r) + 2.0 * k
    long_leg = rate * length > _PANEL_RATE_LENGTH
    x, w = _gauss_legendre()
    t = length[:, None] * x[None, :]
    wt = length[:, None] * w[None, :]
    leg_l = length[:, None]
    om = omega[:, None]

    rot = np.exp(1j * om * t)
    decay = np.exp(-0.5 * k * t)
    e1 = rot * decay  # e^{(i omega - K/2) t}
    c3 = 1j * om - 1.5 * k

    def per_leg(values: ComplexArray) -> ComplexArray:
        sums: ComplexArray = (wt * values).sum(axis=1)
        return sums

    i_mean = per_leg(e1)
    i_tail = per_leg(rot * np.exp(-0.5 * k * (leg_l - t)))
    i_same_abs = per_leg((leg_l - t) * e1)
    i_stein = per_leg(t * e1)
    i_f = per_leg(rot * decay**3)
    i_same_sq = per_leg(e1 * t * _expm1_over(c3 * t))
    i_noise = per_leg(rot * rot * decay**4)
    if np.any(long_leg):
        exact = _long_leg_integrals(length[long_leg], omega[long_leg], k)
        for target, value in zip(
            (i_mean, i_tail, i_same_abs, i_stein, i_f, i_same_sq, i_noise), exact, strict=True
        ):
            target[long_leg] = value

    mean_legs = alpha * np.exp(-0.5 * v_start) * i_mean  # m_j
    mean_z = complex(mean_legs.sum())

    # E|Z|^2: same legs, then pairs i < j through S_j = sum_{i<j} B_i e^{-K(a_j - e_i)/2}
    same_abs = 2.0 * float((np.abs(alpha) ** 2 * i_same_abs.real).sum())
    tail = (alpha * i_tail).tolist()  # B_i
    head = np.conj(alpha * i_mean).tolist()  # conj C_j
    shrink = np.exp(-0.5 * k * length).tolist()
    # the heading variance jumps at spins; without any, e^0 = 1 exactly, and
    # np.diff and np.exp cost a tenth of the call
    jumps = np.exp(-0.5 * np.diff(jump, prepend=0.0)).tolist() if turn_var else [1.0] * length.size
    running, cross = 0.0j, 0.0j
    for b, c_conj, g, h in zip(tail, head, shrink, jumps, strict=True):
        running *= h
        cross += running * c_conj
        running = running * g + b
    abs_sq = params.k_rho * path.distance_m + same_abs + 2.0 * cross.real

    # E[Z^2]: kernel e^{-3Ks/2} e^{-Ks'/2} for s < s'
    sq_alpha = alpha * alpha
    f_legs = alpha * np.exp(-1.5 * v_start) * i_f
    before = np.concatenate(([0.0j], np.cumsum(f_legs)[:-1]))
    same_sq = sq_alpha * np.exp(-2.0 * v_start) * i_same_sq
    noise = params.k_rho / gain**2 * sq_alpha * np.exp(-2.0 * v_start) * i_noise
    sq = complex(2.0 * (same_sq.sum() + (before * mean_legs).sum()) + noise.sum())

    cov_delta_z = complex(
        (1j * alpha * np.exp(-0.5 * v_start) * (v_start * i_mean + k * i_stein)).sum()
    )

    c_abs = abs_sq - abs(mean_z) ** 2  # Var x + Var y
    c_sq = sq - mean_z * mean_z  # Var x - Var y + 2i Cov(x, y)
    var_delta = k * path.distance_m + turn_var
    cov = np.array(
        [
            [(c_abs + c_sq.real) / 2.0, c_sq.imag / 2.0, cov_delta_z.real],
            [c_sq.imag / 2.0, (c_abs - c_sq.real) / 2.0, cov_delta_z.imag],
            [cov_delta_z.real, cov_delta_z.imag, var_delta],
        ]
    )
    mean_delta = (
        path.net_turn_rad - path.winding_rad + params.e_r * path.signed_distance_m + turn_mean
    )
    mean = np.array([mean_z.real, mean_z.imag, mean_delta])
    return PoseMoments(mean=mean, cov=cov)


def observable_means(path: EncoderPath, params: ErrorParameters) -> ObservableMeans:
    """Expected phi1..phi5, <x>, <y> of ``path`` from the path integrals eqs.
    (22), (24), (29), (30), (32) with the decay e^{-K_theta s/2} (SI).

    phi5 is <x^2 + y^2>, a raw second moment: it measures spread only for a
    closed path."""
    moments = pose_moments(path, params)
    x, y, delta = (float(v) for v in moments.mean)
    return ObservableMeans(
        phi1=delta,
        phi2=float(moments.cov[2, 2]),
        phi3=x,
        phi4=y,
        phi5=moments.mean_square_distance,
        x=x,
        y=y,
    )


@dataclass(frozen=True)
class PathSet:
    """Many paths' legs and turns as padded arrays (T paths x M legs), for
    :func:`batch_moments`. Padding legs have length 0 and sign 0 (they add
    nothing).

    Attributes:
        heading_rad, sign, length_m, start_arc_m, start_signed_m: (T, M) as
            in :class:`~odohil.science.paths.LegTable`.
        before_rad: (T, 4, M) per turn class, the signed angle turned before each leg.
        spin_before_rad: (T, M) |angle| spun before each leg, rad.
        total_rad: (T, 4) per turn class, the path's signed total, rad.
        spin_total_rad: (T,) |angle| spun over the path, rad.
        distance_m, signed_distance_m: (T,) per path, m.
        heading_offset_rad: (T,) net encoder turn minus winding, rad.
        paths: the T paths.
        leg_length_m, leg_sign: (U,) the distinct legs (length m, travel
            sign) of all the paths, padding excluded: a leg's one-leg
            integrals depend on nothing else (repeated paths share them).
        leg_index: (T, M) each leg's index among the distinct legs, U for padding.
        buckets: the paths grouped by leg count, (indices into the T paths,
            their own PathSet padded to the group's longest path), when the
            groups' padding is smaller than the whole set's; () for one group.
    """

    heading_rad: FloatArray
    sign: FloatArray
    length_m: FloatArray
    start_arc_m: FloatArray
    start_signed_m: FloatArray
    before_rad: FloatArray
    spin_before_rad: FloatArray
    total_rad: FloatArray
    spin_total_rad: FloatArray
    distance_m: FloatArray
    signed_distance_m: FloatArray
    heading_offset_rad: FloatArray
    paths: tuple[EncoderPath, ...]
    leg_length_m: FloatArray
    leg_sign: FloatArray
    leg_index: IntArray
    buckets: tuple[tuple[IntArray, PathSet], ...] = ()

    @classmethod
    def of(cls, paths: tuple[EncoderPath, ...]) -> PathSet:
        """The padded tables of ``paths``, grouped by leg count (:func:`_leg_buckets`)."""
        whole = cls._padded(paths)
        groups = _leg_buckets([p.legs.length_m.size for p in paths])
        if len(groups) < 2:
            return whole
        buckets = []
        for group in groups:
            members = tuple(paths[i] for i in group)
            top = max(p.legs.length_m.size for p in members)
            # a multiple of 8 legs: numpy's pairwise sums over the legs then
            # add each leg in the same place as in any other multiple of 8 up
            # to 128 (the same sums, bit for bit, as the whole set's if its
            # longest path has such a count)
            width = -(-top // _SUM_BLOCK) * _SUM_BLOCK
            buckets.append((np.array(group, dtype=np.intp), cls._padded(members, width)))
        return replace(whole, buckets=tuple(buckets))

    @classmethod
    def _padded(cls, paths: tuple[EncoderPath, ...], width: int = 0) -> PathSet:
        """The padded tables of ``paths``, one group, ``width`` legs wide (at
        least the longest path's)."""
        t, m = len(paths), max(width, *(p.legs.length_m.size for p in paths))
        tables = {
            name: np.zeros((t, m))
            for name in ("heading_rad", "sign", "length_m", "start_arc_m", "start_signed_m")
        }
        before = np.zeros((t, 4, m))
        spin_before = np.zeros((t, m))
        for i, path in enumerate(paths):
            n = path.legs.length_m.size
            for name, table in tables.items():
                table[i, :n] = getattr(path.legs, name)
            before[i, :, :n] = path.turns.before_rad
            spin_before[i, :n] = path.turns.spin_before_rad
        length, sign = tables["length_m"], tables["sign"]
        valid = length > 0
        distinct, inverse = np.unique(
            np.stack([length[valid], sign[valid]], axis=1), axis=0, return_inverse=True
        )
        index = np.full((t, m), distinct.shape[0], dtype=np.intp)
        index[valid] = inverse.reshape(-1)
        return cls(
            before_rad=before,
            spin_before_rad=spin_before,
            total_rad=np.array([p.turns.total_rad for p in paths]),
            spin_total_rad=np.array([p.turns.spin_total_rad for p in paths]),
            distance_m=np.array([p.distance_m for p in paths]),
            signed_distance_m=np.array([p.signed_distance_m for p in paths]),
            heading_offset_rad=np.array([p.net_turn_rad - p.winding_rad for p in paths]),
            paths=paths,
            leg_length_m=np.ascontiguousarray(distinct[:, 0]),
            leg_sign=np.ascontiguousarray(distinct[:, 1]),
            leg_index=index,
            heading_rad=tables["heading_rad"],
            sign=sign,
            length_m=length,
            start_arc_m=tables["start_arc_m"],
            start_signed_m=tables["start_signed_m"],
        )


_BUCKET_PADDING = 1.25
"""A path joins the group of the longest path not yet grouped when that one
has at most this many times its legs (at most a fifth of a group is padding)."""


_SUM_BLOCK = 8
"""numpy's pairwise summation adds blocks of 8 numbers (8 accumulators)."""


def _leg_buckets(counts: Sequence[int]) -> list[list[int]]:
    """Indices of the paths with ``counts`` legs, grouped (longest first): the
    moments of a path do not depend on the padding, and a one-leg straight
    run padded to a circle's 64 legs costs 64 legs."""
    order = sorted(range(len(counts)), key=lambda i: -counts[i])
    groups: list[list[int]] = []
    top = 0
    for i in order:
        if not groups or counts[i] * _BUCKET_PADDING < top:
            groups.append([])
            top = counts[i]
        groups[-1].append(i)
    return [sorted(group) for group in groups]


BATCH_COLUMNS = ("E_R", "E_T", "K_theta", "K_rho", *TURN_CLASSES, "K_spin")
"""The columns of :func:`batch_moments`' parameter rows (SI)."""
_MAX_HALF_VARIANCE = 600.0
"""Above this V/2 the batch's running sums could overflow: those rows are
done path by path by :func:`pose_moments` (its recurrence never overflows)."""


_PANEL_NODES = ((0.1, 4), (0.6, 6), (_PANEL_RATE_LENGTH, _NODES))
"""Gauss-Legendre nodes by (2|E_R| + 2K) L: the panel error is about
(load)^(2n) / (2n)!, below 1e-12 relative in each class."""


@lru_cache(maxsize=8)
def _gauss_legendre_n(nodes: int) -> tuple[FloatArray, FloatArray]:
    x, w = np.polynomial.legendre.leggauss(nodes)
    return (x + 1.0) / 2.0, w / 2.0


def _panel_integrals(
    length: FloatArray, omega: FloatArray, k: FloatArray, nodes: int
) -> ComplexArray:
    """The seven one-leg integrals of :func:`pose_moments` by one
    Gauss-Legendre panel of ``nodes`` nodes, legs as flat arrays: (7, legs)."""
    x, w = _gauss_legendre_n(nodes)
    leg = length[:, None]
    t = leg * x
    wt = leg * w
    om = omega[:, None]
    kt = k[:, None] * t
    e1 = np.exp(1j * om * t - 0.5 * kt)
    shrink = np.exp(-kt)  # >= e^-1 on a panel leg (K L <= 1)
    c3t = (1j * om - 1.5 * k[:, None]) * t
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(c3t == 0, 1.0, np.expm1(c3t) / c3t)
    out: ComplexArray = np.empty((7, length.size), dtype=np.complex128)
    for row, values in enumerate(
        (e1, e1 / shrink, (leg - t) * e1, t * e1, e1 * shrink, e1 * t * ratio, e1 * e1 * shrink)
    ):
        np.add.reduce(wt * values, axis=-1, out=out[row])
    out[1] *= np.exp(-0.5 * k * length)
    return out


def _distinct_pairs(pairs: FloatArray) -> tuple[FloatArray, list[int] | None]:
    """The distinct rows of ``pairs`` (Q, 2), in order of first appearance, and
    the index of each row's among them (None when every row is distinct)."""
    first: dict[tuple[float, float], int] = {}
    inverse = [first.setdefault((a, b), len(first)) for a, b in pairs.tolist()]
    if len(first) == len(inverse):
        return pairs, None
    return np.array(list(first), dtype=np.float64).reshape(-1, 2), inverse


def _distinct_rows(rows: FloatArray) -> tuple[FloatArray, list[int] | None]:
    """The distinct rows of ``rows`` (Q, n), in order of first appearance, and
    the index of each row's among them (None when every row is distinct)."""
    first: dict[tuple[float, ...], int] = {}
    inverse = [first.setdefault(tuple(row), len(first)) for row in rows.tolist()]
    if len(first) == len(inverse):
        return rows, None
    return np.array(list(first), dtype=np.float64).reshape(-1, rows.shape[1]), inverse


def _all_leg_integrals(paths: PathSet, q: FloatArray) -> ComplexArray:
    """The seven one-leg integrals of every leg at every row of ``q``, (7, Q, T, M).
    They depend on a row only through E_R and K_theta, so each distinct
    pair is done once (finite-difference rows mostly move other parameters),
    and on a leg only through its length and sign, so each distinct leg
    (:attr:`PathSet.leg_length_m`) is done once; padding legs get 0."""
    pairs, inverse = _distinct_pairs(q[:, [0, 2]])
    e_r = pairs[:, 0, None]
    k = pairs[:, 1, None]
    length = paths.leg_length_m[None]
    omega = e_r * paths.leg_sign[None]
    shape = omega.shape
    kk = np.empty(shape)
    kk[...] = k
    ll = np.empty(shape)
    ll[...] = length
    # one more leg, never chosen, for the padding's index
    integrals = np.zeros((7, shape[0], shape[1] + 1), dtype=np.complex128)
    load = (2.0 * np.abs(e_r) + 2.0 * k) * length
    low = 0.0
    for high, nodes in _PANEL_NODES:
        chosen = (load > low) & (load <= high) if low else load <= high
        low = high
        if not np.any(chosen):
            continue
        integrals[:, :, :-1][:, chosen] = _panel_integrals(
            ll[chosen], omega[chosen], kk[chosen], nodes
        )
    long_leg = load > _PANEL_RATE_LENGTH
    if np.any(long_leg):
        exact = _long_leg_integrals(ll[long_leg], omega[long_leg], kk[long_leg])
        for target, value in zip(integrals[:, :, :-1], exact, strict=True):
            target[long_leg] = value
    rows = np.arange(shape[0]) if inverse is None else np.array(inverse)
    gathered: ComplexArray = integrals[:, rows[:, None, None], paths.leg_index[None]]
    return gathered


def _exclusive_cumsum(values: ComplexArray) -> ComplexArray:
    """sum_{i<j} values_i along the last axis (no subtraction: no cancellation)."""
    out = np.zeros_like(values)
    np.cumsum(values[..., :-1], axis=-1, out=out[..., 1:])
    return out


def batch_moments(paths: PathSet, values: FloatArray) -> tuple[FloatArray, FloatArray]:
    """:func:`pose_moments` of every path at every parameter row, vectorised.

    Args:
        paths: the paths (T of them).
        values: (Q, 9) rows of :data:`BATCH_COLUMNS` (SI; E_T > -1, rates >= 0).

    Returns:
        means (Q, T, 3) and covariances (Q, T, 3, 3), as :func:`pose_moments`
        gives them (tests/science/test_turn_moments.py checks that they agree).
    """
    q = np.asarray(values, dtype=np.float64).reshape(-1, 9)
    if not paths.buckets:
        return _bucket_moments(paths, q)
    means = np.empty((q.shape[0], len(paths.paths), 3))
    covs = np.empty((q.shape[0], len(paths.paths), 3, 3))
    for indices, bucket in paths.buckets:
        means[:, indices], covs[:, indices] = _bucket_moments(bucket, q)
    return means, covs


def _bucket_moments(paths: PathSet, q: FloatArray) -> tuple[FloatArray, FloatArray]:
    """:func:`batch_moments` of one group of paths (``paths.buckets`` empty), q (Q, 9)."""
    gain, k, k_rho = (q[:, i, None, None] for i in range(1, 4))
    gain = 1.0 + gain
    scales = q[:, 4:8]
    k_spin = q[:, 8, None, None]
    length, start, sign = paths.length_m[None], paths.start_arc_m[None], paths.sign[None]
    # e^{i phase} depends on a row only through E_R and the e_turn: each
    # distinct one once (finite-difference rows mostly move other parameters)
    turning, again = _distinct_rows(q[:, [0, 4, 5, 6, 7]])
    phase = (
        paths.heading_rad[None]
        + turning[:, 0, None, None] * paths.start_signed_m[None]
        + np.einsum("qc,tcm->qtm", turning[:, 1:], paths.before_rad)
    )
    rotation = np.exp(1j * phase)
    jump = k_spin * paths.spin_before_rad[None]
    alpha = gain * sign * (rotation if again is None else rotation[again])
    v_start = k * start + jump
    v_end = v_start + k * length
    i_mean, i_tail, i_same_abs, i_stein, i_f, i_same_sq, i_noise = _all_leg_integrals(paths, q)

    half = np.exp(-0.5 * v_start)
    mean_legs = alpha * half * i_mean
    mean_z = mean_legs.sum(axis=-1)
    same_abs = 2.0 * (np.abs(alpha) ** 2 * i_same_abs.real).sum(axis=-1)
    # pairs i < j: conj C_j e^{-V(a_j)/2} sum_{i<j} B_i e^{V(e_i)/2}
    safe = np.minimum(v_end, 2.0 * _MAX_HALF_VARIANCE)
    grow = alpha * i_tail * np.exp(0.5 * safe)
    running = _exclusive_cumsum(grow)
    cross = (running * np.conj(alpha * i_mean) * half).sum(axis=-1)
    abs_sq = k_rho[..., 0] * paths.distance_m[None] + same_abs + 2.0 * cross.real
    f_legs = alpha * np.exp(-1.5 * v_start) * i_f
    before = _exclusive_cumsum(f_legs)
    two = np.exp(-2.0 * v_start)
    same_sq = alpha * alpha * two * i_same_sq
    noise = k_rho / gain**2 * alpha * alpha * two * i_noise
    sq = 2.0 * (same_sq.sum(axis=-1) + (before * mean_legs).sum(axis=-1)) + noise.sum(axis=-1)
    cov_dz = (1j * alpha * half * (v_start * i_mean + k * i_stein)).sum(axis=-1)
    c_abs = abs_sq - np.abs(mean_z) ** 2
    c_sq = sq - mean_z * mean_z
    var_delta = q[:, 2, None] * paths.distance_m[None] + q[:, 8, None] * paths.spin_total_rad[None]
    mean_delta = (
        paths.heading_offset_rad[None]
        + q[:, 0, None] * paths.signed_distance_m[None]
        + scales @ paths.total_rad.T
    )
    means = np.stack([mean_z.real, mean_z.imag, mean_delta], axis=-1)
    covs = np.empty((*means.shape[:2], 3, 3))
    covs[..., 0, 0] = (c_abs + c_sq.real) / 2.0
    covs[..., 1, 1] = (c_abs - c_sq.real) / 2.0
    covs[..., 0, 1] = covs[..., 1, 0] = c_sq.imag / 2.0
    covs[..., 0, 2] = covs[..., 2, 0] = cov_dz.real
    covs[..., 1, 2] = covs[..., 2, 1] = cov_dz.imag
    covs[..., 2, 2] = var_delta
    # rows whose running sums would overflow: path by path
    overflow = np.nonzero((v_end > 2.0 * _MAX_HALF_VARIANCE).any(axis=-1))
    for row, path_index in zip(*overflow, strict=True):
        r = q[row]
        moments = pose_moments(
            paths.paths[path_index],
            ErrorParameters(float(r[0]), float(r[1]), float(r[2]), float(r[3])),
            TurnErrors.of(r[4:8], float(r[8])),
        )
        means[row, path_index], covs[row, path_index] = moments.mean, moments.cov
    return means, covs


def turn_errors_from(names: Sequence[str], values: Sequence[float]) -> TurnErrors:
    """The turn errors named among ``names`` at SI ``values``: ``K_spin``
    (rad^2/rad) and ``e_turn`` with the parts of the turn classes it covers
    (``e_turn``, ``e_turn_spin``, ``e_turn_cw``, ``e_turn_arc_ccw``, ...: the
    names odohil/science/estimators/paths.py fits); zero where none is named."""
    scales = np.zeros(4)
    k_spin = 0.0
    for name, value in zip(names, values, strict=True):
        if name == "K_spin":
            k_spin = float(value)
            continue
        if not name.startswith("e_turn"):
            continue
        parts = name.split("_")[2:]
        rows = [
            r
            for r, label in enumerate(TURN_CLASSES)
            if all(part in label.split() for part in parts)
        ]
        scales[rows] = float(value)
    return TurnErrors.of(scales, k_spin)
