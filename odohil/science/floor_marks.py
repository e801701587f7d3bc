"""The pose change of one trial from tape distances between floor marks.

The robot frame at the start is the world frame. Screw j sits at p_j (robot
frame); its start mark is at p_j and its end mark at R(theta) p_j + t for the real
pose change (t = (dx, dy), theta = dtheta). Measured: the same-screw distances
d_j = |end_j - start_j| and up to two cross distances c_ij = |end_j - start_i|.

Method (see docs/measurements.md and docs/paper-notes.md section 3):

1. Same-screw distances alone: a rigid motion of angle theta is a rotation about
   a centre c, so d_j = 2|sin(theta/2)| |p_j - c|. Eliminating c leaves a
   quadratic in u = 1/(2 sin(theta/2))^2: up to two roots, each with both signs
   of theta (a motion and its inverse have identical same-screw distances),
   so up to four closed-form candidates. Near-pure translations (theta ~ 0,
   c far away) are seeded by translations in twelve directions; the odometry
   end pose and the prior mean are seeds too.
2. Every seed is refined by Levenberg-Marquardt on ALL distances; distinct
   local minima become the candidates.
3. Each candidate is scored by its log-likelihood: -chi^2/2 from the
   distances, plus, when a prior N(mean, cov) of the pose change is given,
   log N(candidate; mean, cov + candidate cov). The best is chosen; the
   trial is *clear-cut* only when the best beats every other candidate by a
   likelihood ratio of at least :data:`CLEAR_CUT_LIKELIHOOD_RATIO` and the
   distances pin all three pose components.
4. When even the best candidate leaves chi^2 above the
   (1 - :data:`CONSISTENCY_LEVEL`) quantile of chi^2 with (m - 3) degrees of
   freedom (at least 1), for m distances, no rigid motion explains the
   distances: :class:`InconsistentMeasurementError` names the distance whose
   removal best restores consistency.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import numpy.typing as npt

from odohil.errors import InconsistentMeasurementError, MeasurementError
from odohil.science import distributions
from odohil.science.frames import inverse_pose, rotate_points, rotation
from odohil.science.robot_description import RobotDescription
from odohil.units import angle_near, wrap_angle, wrap_angles

FloatArray = npt.NDArray[np.float64]

CLEAR_CUT_LIKELIHOOD_RATIO = 100.0
"""The best candidate must be this many times as likely as the runner-up."""
CONSISTENCY_LEVEL = 1e-3
"""Chi^2 test level: consistent distances are rejected this rarely."""
_LOG_CLEAR_CUT = math.log(CLEAR_CUT_LIKELIHOOD_RATIO)
_TRANSLATION_SEED_DIRECTIONS = 12
_LM_ITERATIONS = 80
_CONVERGED_DECREMENT = 1e-2
"""A refined seed counts as a local minimum when a Gauss-Newton step could
lower its chi^2 by less than this (a likelihood change under 0.5 %). Small
motions have long, curved chi^2 valleys (the direction of a 1 cm translation
is poorly determined), where Levenberg-Marquardt creeps: a stricter threshold
threw away the true minimum and left only a spurious one."""
_SETTLED_GAIN = 1e-13
"""A seed's Levenberg-Marquardt stops when its step (at damping <= 1) promises
less than this fraction of its chi^2 (plus 1e-13): rounding, not progress."""
_STALLED_STEPS = 6
"""... or when this many steps in a row gained no more than that (at a minimum
the steps are rejected or gain only rounding) ..."""
_STUCK_DAMPING = 1e10
"""... or when its damping passes this (about 20 rejected steps in a row)."""
_EYE = np.eye(3)
_TINY_EYE = 1e-12 * np.eye(3)
"""Added to the damped diagonal: keeps a zero column solvable."""
_POLISH_ROUNDS = 4
"""Further Levenberg-Marquardt rounds for seeds that have not converged yet."""
_SAME_CANDIDATE = 0.05
"""Two minima are one candidate when they differ by less than this many tape
sigmas (positions, and heading times the screws' radius)."""
_MAX_CONDITION = 1e10
NONLINEARITY_LIMIT = 3.0
"""A trial is not clear-cut when a 3-sigma step (of the reported covariance)
from the chosen pose moves the residuals more than this many tape sigmas away
from their linear prediction: the error region is then bent and the
covariance, a linearisation, cannot be trusted."""
_NONLINEARITY_STEP = 3.0


@dataclass(frozen=True)
class MarkDistances:
    """The tape distances of one trial, metres.

    Attributes:
        same_m: d_j, start to end mark of the same screw, in the description's
            screw order.
        cross_m: c_ij, start mark of screw i to end mark of screw j, in the
            description's cross-pair order.
    """

    same_m: tuple[float, ...]
    cross_m: tuple[float, ...] = ()

    @classmethod
    def of(
        cls, description: RobotDescription, distances: Sequence[float] | FloatArray
    ) -> MarkDistances:
        """The distances of one trial in the order :func:`distance_labels`
        names them (same-screw first, then cross), metres, split by the
        description's screws. Their count is checked by the solver."""
        values = tuple(float(v) for v in distances)
        n_same = len(description.screws)
        return cls(values[:n_same], values[n_same:])

    def as_array(self) -> FloatArray:
        """All distances, same-screw first then cross, metres."""
        return np.array(self.same_m + self.cross_m, dtype=np.float64)


class PoseDistribution(Protocol):
    """A Gaussian belief about a pose change (dx m, dy m, dtheta rad)."""

    @property
    def mean(self) -> FloatArray:
        """Mean, shape (3,)."""
        ...

    @property
    def cov(self) -> FloatArray:
        """Covariance, shape (3, 3)."""
        ...


@dataclass(frozen=True, eq=False)
class PosePrior:
    """A prior on the pose change, e.g. the model's predicted moments.

    Attributes:
        mean: (dx m, dy m, dtheta rad), shape (3,).
        cov: covariance in the same units, shape (3, 3).
    """

    mean: FloatArray
    cov: FloatArray


@dataclass(frozen=True, eq=False)
class MarkCandidate:
    """One rigid motion that is a local best fit to the distances.

    Attributes:
        pose: (dx m, dy m, dtheta rad); dtheta in the branch nearest the
            odometry end heading.
        chi2: sum of squared distance residuals over sigma^2, all distances.
        cross_chi2: the part of ``chi2`` from the cross distances (how well
            the candidate agrees with them; 0 when there are none).
        prior_log_likelihood: log N(pose; prior mean, prior cov + pose cov),
            or None without a prior.
        log_likelihood: -chi2 / 2 plus the prior term; the choice maximises it.
    """

    pose: FloatArray
    chi2: float
    cross_chi2: float
    prior_log_likelihood: float | None
    log_likelihood: float


@dataclass(frozen=True, eq=False)
class MarkSolution:
    """The pose change of one trial recovered from floor marks.

    Attributes:
        pose_change: chosen (dx m, dy m, dtheta rad), dtheta in the branch
            nearest the odometry end heading.
        cov: its 3x3 covariance from the distance errors, sigma^2 (J^T J)^-1
            (pseudo-inverse when the distances do not pin the pose).
        candidates: every distinct candidate, best first (the first is chosen).
        chi2: chi^2 of the chosen candidate over all distances.
        dof: degrees of freedom of the consistency test, m - 3 for m distances.
        clear_cut: True when the choice is not in doubt (see module docs).
        reason: plain-language reason when not clear-cut, else empty.
    """

    pose_change: FloatArray
    cov: FloatArray
    candidates: tuple[MarkCandidate, ...]
    chi2: float
    dof: int
    clear_cut: bool
    reason: str


@dataclass(frozen=True)
class _Geometry:
    """Row k of the model: distance |R(theta) source_k + t - target_k|."""

    source: FloatArray
    target: FloatArray
    labels: tuple[str, ...]
    n_same: int
    sigma: float
    scale: float
    source_x: FloatArray
    source_y: FloatArray
    target_x: FloatArray
    target_y: FloatArray


def distance_labels(description: RobotDescription) -> tuple[str, ...]:
    """Human names of the distances, same-screw first then cross."""
    same = tuple(f"d{n + 1} (screw {s.name})" for n, s in enumerate(description.screws))
    cross = tuple(
        f"cross{n + 1} ({i} start to {j} end)" for n, (i, j) in enumerate(description.cross_pairs)
    )
    return same + cross


def marks_from_pose(
    description: RobotDescription, pose_change: Sequence[float] | FloatArray
) -> MarkDistances:
    """The forward model: the distances a pose change (dx m, dy m, dtheta rad)
    leaves between the floor marks, metres, without measurement error."""
    pose = _pose3(pose_change, "pose_change")
    geometry = _geometry(description)
    distances = _model(pose[None, :], geometry)[0]
    return MarkDistances(
        same_m=tuple(float(v) for v in distances[: geometry.n_same]),
        cross_m=tuple(float(v) for v in distances[geometry.n_same :]),
    )


def linearised_marks(
    description: RobotDescription, pose_change: Sequence[float] | FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The distances a pose change leaves (metres, shape (m,)) and their
    Jacobian with respect to (dx m, dy m, dtheta rad), shape (m, 3)."""
    pose = _pose3(pose_change, "pose_change")
    geometry = _geometry(description)
    ones = np.ones(len(geometry.source))
    zero = np.zeros(len(geometry.source))
    residuals, jacobian = _residuals(pose[None, :], geometry, zero, ones)
    return residuals[0] * geometry.sigma, jacobian[0] * geometry.sigma


def mark_jacobian(description: RobotDescription, poses: FloatArray) -> FloatArray:
    """d(distances)/d(pose) of the forward model (:func:`marks_from_pose`),
    same-screw distances first then cross, for poses (n, 3) (m, m, rad):
    shape (n, m_distances, 3)."""
    geometry = _geometry(description)
    unit_weights = np.full(len(geometry.source), geometry.sigma)  # residuals in metres
    zero = np.zeros(len(geometry.source))
    _, jacobian = _residuals(np.asarray(poses, dtype=np.float64), geometry, zero, unit_weights)
    return jacobian


def pose_covariance(
    description: RobotDescription, pose_change: Sequence[float] | FloatArray
) -> FloatArray:
    """sigma^2 (J^T J)^-1 of the description's distances at a pose (dx m, dy m,
    dtheta rad); a pseudo-inverse when they do not pin the pose."""
    cov, _ = _covariance(_pose3(pose_change, "pose_change"), _geometry(description))
    return cov


def solve_marks(
    description: RobotDescription,
    marks: MarkDistances,
    odometry_end_pose: Sequence[float] | FloatArray,
    prior: PoseDistribution | None = None,
) -> MarkSolution:
    """Recover the pose change of one trial from its floor-mark distances.

    Args:
        description: screws, their cross pairs and the tape sigma (metres).
        marks: the measured distances, metres.
        odometry_end_pose: where odometry says the trial ended
            (x m, y m, theta rad); picks the 2 pi branch of dtheta.
        prior: optional Gaussian belief of the pose change (e.g. the model's
            predicted moments); enters the choice as a likelihood.

    Raises:
        MeasurementError: wrong number of distances, NaN, infinite or negative
            values, or a malformed odometry pose or prior.
        InconsistentMeasurementError: no rigid motion explains the distances
            within the measurement error; the message names the suspect.
    """
    geometry = _geometry(description)
    measured = _checked_distances(marks, description)
    odometry = _pose3(odometry_end_pose, "odometry end pose")
    prior_mean, prior_cov = _checked_prior(prior)
    weights = np.ones(measured.size)

    seeds = _seeds(geometry, measured, odometry, prior_mean)
    minima, chi2 = _local_minima(seeds, geometry, measured, weights)
    dof = measured.size - 3
    limit = float(distributions.chi2_isf(CONSISTENCY_LEVEL, max(dof, 1)))
    if chi2.min() > limit:
        raise _inconsistency(geometry, measured, seeds, minima, float(chi2.min()), limit)

    candidates = [
        _candidate(pose, c2, geometry, measured, odometry, prior_mean, prior_cov)
        for pose, c2 in zip(minima, chi2, strict=True)
    ]
    candidates.sort(key=lambda cand: -cand.log_likelihood)
    best = candidates[0]
    cov, pinned = _covariance(best.pose, geometry)
    clear_cut, reason = _verdict(candidates, pinned, cov, prior_mean is not None, geometry)
    return MarkSolution(
        pose_change=best.pose,
        cov=cov,
        candidates=tuple(candidates),
        chi2=best.chi2,
        dof=dof,
        clear_cut=clear_cut,
        reason=reason,
    )


# --- validation -------------------------------------------------------------


def _pose3(value: Sequence[float] | FloatArray, what: str) -> FloatArray:
    try:
        pose = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise MeasurementError(f"{what} must be three numbers (x m, y m, theta rad)") from exc
    if pose.shape != (3,) or not np.all(np.isfinite(pose)):
        raise MeasurementError(
            f"{what} must be three finite numbers (x m, y m, theta rad), got {value!r}"
        )
    return pose


def _checked_distances(marks: MarkDistances, description: RobotDescription) -> FloatArray:
    n_screws, n_cross = len(description.screws), len(description.cross_pairs)
    if len(marks.same_m) != n_screws:
        raise MeasurementError(
            f"expected {n_screws} same-screw distances (one per screw), got {len(marks.same_m)}"
        )
    if len(marks.cross_m) != n_cross:
        raise MeasurementError(
            f"expected {n_cross} cross distances (one per cross pair), got {len(marks.cross_m)}"
        )
    try:
        measured = marks.as_array()
    except (TypeError, ValueError) as exc:
        raise MeasurementError(f"distances must be numbers: {exc}") from exc
    labels = distance_labels(description)
    for label, value in zip(labels, measured, strict=True):
        if not math.isfinite(value):
            raise MeasurementError(f"distance {label} is not a finite number: {value!r}")
        if value < 0:
            raise MeasurementError(f"distance {label} is negative: {value!r} m")
    return measured


def _checked_prior(prior: PoseDistribution | None) -> tuple[FloatArray | None, FloatArray | None]:
    if prior is None:
        return None, None
    mean = _pose3(prior.mean, "prior mean")
    cov = np.asarray(prior.cov, dtype=np.float64)
    if cov.shape != (3, 3) or not np.all(np.isfinite(cov)):
        raise MeasurementError(f"prior cov must be a finite 3x3 matrix, got shape {cov.shape}")
    cov = 0.5 * (cov + cov.T)
    if np.linalg.eigvalsh(cov).min() < -1e-12 * max(1.0, float(np.abs(cov).max())):
        raise MeasurementError("prior cov must be positive semi-definite")
    return mean, cov


# --- model ------------------------------------------------------------------


def _geometry(description: RobotDescription) -> _Geometry:
    points = description.positions()
    cross = description.cross_indices()
    source = np.vstack([points, points[[j for _, j in cross]].reshape(-1, 2)])
    target = np.vstack([points, points[[i for i, _ in cross]].reshape(-1, 2)])
    centred = points - points.mean(axis=0)
    return _Geometry(
        source=source,
        target=target,
        labels=distance_labels(description),
        n_same=len(points),
        sigma=description.sigma_m,
        scale=float(np.sqrt((centred**2).sum(axis=1).mean())),
        source_x=np.ascontiguousarray(source[:, 0]),
        source_y=np.ascontiguousarray(source[:, 1]),
        target_x=np.ascontiguousarray(target[:, 0]),
        target_y=np.ascontiguousarray(target[:, 1]),
    )


def _end_points(poses: FloatArray, geometry: _Geometry) -> tuple[FloatArray, FloatArray]:
    """R(theta) source, per pose: x and y parts, shape (B, m)."""
    return rotate_points(poses[:, 2], geometry.source)


def _model(poses: FloatArray, geometry: _Geometry) -> FloatArray:
    rx, ry = _end_points(poses, geometry)
    vx = rx + poses[:, 0:1] - geometry.target[:, 0]
    vy = ry + poses[:, 1:2] - geometry.target[:, 1]
    distances: FloatArray = np.hypot(vx, vy)
    return distances


def _residuals(
    poses: FloatArray, geometry: _Geometry, measured: FloatArray, weights: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Weighted residuals (B, m) and their Jacobian (B, m, 3), in sigma units;
    ``weights`` is (m,), or (B, m) for a weight per pose."""
    return _scaled_residuals(poses, geometry, measured, weights / geometry.sigma)


def _scaled_residuals(
    poses: FloatArray, geometry: _Geometry, measured: FloatArray, w: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """:func:`_residuals` with the weights already divided by sigma (the
    arithmetic of :func:`_end_points` and :func:`_model`, inlined)."""
    c = np.cos(poses[:, 2:3])
    s = np.sin(poses[:, 2:3])
    px, py = geometry.source_x, geometry.source_y
    rx = c * px - s * py
    ry = s * px + c * py
    vx = rx + poses[:, 0:1] - geometry.target_x
    vy = ry + poses[:, 1:2] - geometry.target_y
    dist = np.hypot(vx, vy)
    positive = dist > 0
    if positive.all():
        ux, uy = vx / dist, vy / dist
    else:
        # Where an end mark lands on its start mark the distance has no
        # gradient; a zero row there is what Gauss-Newton needs.
        safe = np.where(positive, dist, 1.0)
        ux, uy = vx / safe * positive, vy / safe * positive
    residuals = (dist - measured) * w
    jacobian = np.empty((*dist.shape, 3))
    np.multiply(ux, w, out=jacobian[..., 0])
    np.multiply(uy, w, out=jacobian[..., 1])
    np.multiply(ux * -ry + uy * rx, w, out=jacobian[..., 2])
    return residuals, jacobian


def _levenberg_marquardt(
    seeds: FloatArray, geometry: _Geometry, measured: FloatArray, weights: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Refine every seed at once; returns poses, chi^2 and the Gauss-Newton
    decrement (how much one more step could still gain). ``weights`` is (m,),
    or (B, m) for a weight per seed.

    A seed stops early (before _LM_ITERATIONS) once its own step could gain
    less than _SETTLED_GAIN of its chi^2 at small damping, or _STALLED_STEPS
    steps in a row gained no more than that, or its damping has grown past
    _STUCK_DAMPING: more iterations would not move it. The seeds still moving
    are kept in arrays of their own (``at`` holds their rows), so each
    iteration works on them alone; every seed's arithmetic is its own."""
    w = weights / geometry.sigma
    poses = seeds.copy()
    r, jac = _scaled_residuals(poses, geometry, measured, w)
    cost = (r**2).sum(axis=1)
    # The seeds still moving, in arrays of their own: ``at`` holds their rows.
    at = np.arange(len(poses))
    p_a, r_a, j_a, c_a, w_a = poses, r, jac, cost, w
    d_a = np.full(len(poses), 1e-3)
    stalled = np.zeros(len(poses), dtype=np.int64)  # iterations in a row without gain
    for _ in range(_LM_ITERATIONS):
        if at.size == 0:
            break
        normal = np.einsum("bmi,bmj->bij", j_a, j_a)
        gradient = np.einsum("bmi,bm->bi", j_a, r_a)
        diag = normal.diagonal(axis1=1, axis2=2)[:, :, None] * _EYE + _TINY_EYE
        step = np.linalg.solve(normal + d_a[:, None, None] * diag, -gradient[:, :, None])[..., 0]
        trial = p_a + step
        r_new, jac_new = _scaled_residuals(trial, geometry, measured, w_a)
        cost_new = (r_new**2).sum(axis=1)
        better = cost_new < c_a
        tiny = _SETTLED_GAIN * (1.0 + c_a)
        gain = -np.einsum("bi,bi->b", gradient, step)  # what the step promised, chi^2
        still = np.where(better, c_a - cost_new <= tiny, gain <= tiny)
        stalled = np.where(still, stalled + 1, 0)
        column = better[:, None]
        p_a = np.where(column, trial, p_a)
        r_a = np.where(column, r_new, r_a)
        j_a = np.where(column[:, :, None], jac_new, j_a)
        c_a = np.where(better, cost_new, c_a)
        settled = (d_a <= 1.0) & (gain <= tiny)
        d_a = np.minimum(np.maximum(np.where(better, d_a / 3.0, d_a * 3.0), 1e-12), 1e12)
        done = settled | (stalled >= _STALLED_STEPS) | (d_a >= _STUCK_DAMPING)
        if done.any():
            rows = at[done]
            poses[rows], r[rows], jac[rows], cost[rows] = p_a[done], r_a[done], j_a[done], c_a[done]
            keep = ~done
            at, p_a, r_a, j_a, c_a = at[keep], p_a[keep], r_a[keep], j_a[keep], c_a[keep]
            d_a, stalled = d_a[keep], stalled[keep]
            if w_a.ndim == 2:
                w_a = w_a[keep]
    poses[at], r[at], jac[at], cost[at] = p_a, r_a, j_a, c_a
    normal = np.einsum("bmi,bmj->bij", jac, jac)
    gradient = np.einsum("bmi,bm->bi", jac, r)
    newton = np.einsum("bij,bj->bi", np.linalg.pinv(normal), gradient)
    decrement = np.einsum("bi,bi->b", gradient, newton)
    return poses, cost, decrement


def _closed_form_seeds(geometry: _Geometry, measured: FloatArray) -> list[FloatArray]:
    """Rotations about a centre that fit three same-screw distances exactly
    (the triple of screws spanning the largest triangle)."""
    points = geometry.source[: geometry.n_same]
    d = measured[: geometry.n_same]
    best_area, triple = -1.0, (0, 1, 2)
    n = len(points)
    for i in range(n):
        for j in range(i + 1, n):
            for k in range(j + 1, n):
                e1, e2 = points[j] - points[i], points[k] - points[i]
                area = abs(e1[0] * e2[1] - e1[1] * e2[0])
                if area > best_area:
                    best_area, triple = area, (i, j, k)
    p = points[list(triple)]
    dd = d[list(triple)]
    # 2 (p_j - p_1) . c = |p_j|^2 - |p_1|^2 + (d_1^2 - d_j^2) u, so c = a + b u.
    m = 2.0 * (p[1:] - p[0])
    e = (p[1:] ** 2).sum(axis=1) - (p[0] ** 2).sum()
    f = dd[0] ** 2 - dd[1:] ** 2
    a = np.linalg.solve(m, e)
    b = np.linalg.solve(m, f)
    q = p[0] - a
    # |q - b u|^2 = d_1^2 u: a quadratic in u = 1 / (2 sin(theta/2))^2.
    coeffs = [float(b @ b), -(2.0 * float(q @ b) + dd[0] ** 2), float(q @ q)]
    roots = np.roots(coeffs) if abs(coeffs[0]) > 1e-300 else np.roots(coeffs[1:])
    us = [float(r.real) for r in roots if abs(r.imag) <= 1e-9 * max(1.0, abs(r.real))]
    if not us and abs(coeffs[0]) > 0:
        us = [-coeffs[1] / (2.0 * coeffs[0])]  # noise pushed the roots off: take the vertex
    seeds: list[FloatArray] = []
    for u in us:
        if not math.isfinite(u) or u <= 0:
            continue
        half_chord = min(1.0, 0.5 / math.sqrt(u))
        angle = 2.0 * math.asin(half_chord)
        centre = a + b * u
        for theta in (angle, -angle):
            t = (np.eye(2) - rotation(theta)) @ centre
            seeds.append(np.array([t[0], t[1], theta]))
    return seeds


def _seeds(
    geometry: _Geometry,
    measured: FloatArray,
    odometry: FloatArray,
    prior_mean: FloatArray | None,
) -> FloatArray:
    seeds = _closed_form_seeds(geometry, measured)
    length = float(measured[: geometry.n_same].mean())
    for k in range(_TRANSLATION_SEED_DIRECTIONS):
        phi = 2.0 * math.pi * k / _TRANSLATION_SEED_DIRECTIONS
        seeds.append(np.array([length * math.cos(phi), length * math.sin(phi), 0.0]))
    for guess in (odometry, prior_mean):
        if guess is not None:
            seeds += [guess.copy(), inverse_pose(guess)]
    return np.array(seeds, dtype=np.float64)


def _refine(
    seeds: FloatArray, geometry: _Geometry, measured: FloatArray, weights: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Levenberg-Marquardt on every seed, then up to _POLISH_ROUNDS more for
    those not converged yet: poses, chi^2 and decrements. ``weights`` is (m,),
    or (B, m) for a weight per seed."""
    poses, chi2, decrement = _levenberg_marquardt(seeds, geometry, measured, weights)
    for _ in range(_POLISH_ROUNDS):
        slow = decrement >= _CONVERGED_DECREMENT
        if not slow.any():
            break
        poses[slow], chi2[slow], decrement[slow] = _levenberg_marquardt(
            poses[slow], geometry, measured, weights if weights.ndim == 1 else weights[slow]
        )
    return poses, chi2, decrement


def _local_minima(
    seeds: FloatArray, geometry: _Geometry, measured: FloatArray, weights: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Distinct converged minima from the seeds, with their chi^2, best first."""
    poses, chi2, decrement = _refine(seeds, geometry, measured, weights)
    poses[:, 2] = wrap_angles(poses[:, 2])
    converged = decrement < _CONVERGED_DECREMENT
    if not converged.any():
        converged = chi2 == chi2.min()
    order = np.argsort(chi2[converged], kind="stable")
    kept_poses: list[FloatArray] = []
    kept_chi2: list[float] = []
    for pose, c2 in zip(poses[converged][order], chi2[converged][order], strict=True):
        if not any(_same_pose(pose, other, geometry) for other in kept_poses):
            kept_poses.append(pose)
            kept_chi2.append(float(c2))
    return np.array(kept_poses), np.array(kept_chi2)


def _same_pose(a: FloatArray, b: FloatArray, geometry: _Geometry) -> bool:
    dtheta = wrap_angle(float(a[2] - b[2]))
    spread = max(float(np.hypot(*(a[:2] - b[:2]))), abs(dtheta) * geometry.scale)
    return spread < _SAME_CANDIDATE * geometry.sigma


# --- choice -----------------------------------------------------------------


def _candidate(
    pose: FloatArray,
    chi2: float,
    geometry: _Geometry,
    measured: FloatArray,
    odometry: FloatArray,
    prior_mean: FloatArray | None,
    prior_cov: FloatArray | None,
) -> MarkCandidate:
    chosen = np.array([pose[0], pose[1], angle_near(float(pose[2]), float(odometry[2]))])
    r, _ = _residuals(chosen[None, :], geometry, measured, np.ones(measured.size))
    cross_chi2 = float((r[0, geometry.n_same :] ** 2).sum())
    prior_term: float | None = None
    log_likelihood = -0.5 * chi2
    if prior_mean is not None and prior_cov is not None:
        cov, _ = _covariance(chosen, geometry)
        aligned = chosen.copy()
        aligned[2] = angle_near(float(chosen[2]), float(prior_mean[2]))
        prior_term = _gaussian_log_density(aligned - prior_mean, prior_cov + cov)
        log_likelihood += prior_term
    return MarkCandidate(
        pose=chosen,
        chi2=chi2,
        cross_chi2=cross_chi2,
        prior_log_likelihood=prior_term,
        log_likelihood=log_likelihood,
    )


def _gaussian_log_density(delta: FloatArray, cov: FloatArray) -> float:
    # A tiny floor keeps a degenerate prior (zero variance) usable.
    floor = 1e-18 * np.eye(3)
    sign, logdet = np.linalg.slogdet(cov + floor)
    if sign <= 0:
        return -math.inf
    mahalanobis = float(delta @ np.linalg.solve(cov + floor, delta))
    return -0.5 * (mahalanobis + float(logdet) + 3.0 * math.log(2.0 * math.pi))


def _covariance(pose: FloatArray, geometry: _Geometry) -> tuple[FloatArray, bool]:
    """sigma^2 (J^T J)^-1 at the pose (J: all distances by (dx, dy, dtheta)),
    and whether J^T J is well conditioned."""
    weights = np.ones(len(geometry.source))
    _, jac = _residuals(pose[None, :], geometry, np.zeros(len(weights)), weights)
    normal = jac[0].T @ jac[0]  # already divided by sigma^2
    pinned = bool(np.linalg.cond(normal) < _MAX_CONDITION)
    inverse = np.linalg.inv(normal) if pinned else np.linalg.pinv(normal)
    return 0.5 * (inverse + inverse.T), pinned


def _nonlinearity(pose: FloatArray, cov: FloatArray, geometry: _Geometry) -> float:
    """Largest departure, in tape sigmas, of the residuals from their linear
    prediction after a 3-sigma step along each principal axis of ``cov``."""
    weights = np.ones(len(geometry.source))
    zero = np.zeros(len(weights))
    base, jac = _residuals(pose[None, :], geometry, zero, weights)
    values, vectors = np.linalg.eigh(cov)
    steps = (_NONLINEARITY_STEP * np.sqrt(np.clip(values, 0.0, None)) * vectors).T
    steps = np.vstack([steps, -steps])
    moved, _ = _residuals(pose[None, :] + steps, geometry, zero, weights)
    predicted = base + steps @ jac[0].T
    return float(np.sqrt(((moved - predicted) ** 2).sum(axis=1)).max())


def _describe(pose: FloatArray) -> str:
    return f"(dx {pose[0]:+.4f} m, dy {pose[1]:+.4f} m, dtheta {math.degrees(pose[2]):+.3f} deg)"


def _verdict(
    candidates: list[MarkCandidate],
    pinned: bool,
    cov: FloatArray,
    has_prior: bool,
    geometry: _Geometry,
) -> tuple[bool, str]:
    best = candidates[0]
    if not pinned:
        return False, (
            f"the distances do not pin the pose near {_describe(best.pose)}: "
            "some direction of motion leaves them unchanged; add a cross distance"
        )
    bend = _nonlinearity(best.pose, cov, geometry)
    if bend > NONLINEARITY_LIMIT:
        return False, (
            f"the distances fix the pose near {_describe(best.pose)} only loosely: a "
            f"{_NONLINEARITY_STEP:g}-sigma step departs from the linear model by {bend:.2g} "
            "tape sigmas, so the covariance (a linearisation) cannot be trusted; typical "
            "of near-pure translations without enough cross distances, or of turns near "
            "180 degrees"
        )
    if len(candidates) == 1:
        return True, ""
    runner = candidates[1]
    log_ratio = best.log_likelihood - runner.log_likelihood
    if log_ratio >= _LOG_CLEAR_CUT:
        return True, ""
    contenders = [
        c for c in candidates[1:] if best.log_likelihood - c.log_likelihood < _LOG_CLEAR_CUT
    ]
    inverse = inverse_pose(best.pose)
    hint = ""
    if any(_close(c.pose, inverse, cov) for c in contenders):
        hint = (
            " The inverse motion is among them, and same-screw distances cannot tell a "
            "motion from its inverse."
        )
    remedy = "a second cross distance" if has_prior else "a cross distance or the model's prior"
    return False, (
        f"{len(contenders) + 1} motions explain the marks almost equally well (likelihood "
        f"ratio of the best two {math.exp(min(log_ratio, 700.0)):.3g}, below "
        f"{CLEAR_CUT_LIKELIHOOD_RATIO:g}): chosen {_describe(best.pose)} with chi2 "
        f"{best.chi2:.2f}, runner-up {_describe(runner.pose)} with chi2 {runner.chi2:.2f}."
        f"{hint} Check the marks or add {remedy}."
    )


def _close(a: FloatArray, b: FloatArray, cov: FloatArray) -> bool:
    delta = a - b
    delta[2] = wrap_angle(float(delta[2]))
    spread = np.sqrt(np.diag(cov))
    return bool(np.all(np.abs(delta) <= 10.0 * spread + 1e-9))


def _inconsistency(
    geometry: _Geometry,
    measured: FloatArray,
    seeds: FloatArray,
    minima: FloatArray,
    chi2: float,
    limit: float,
) -> InconsistentMeasurementError:
    """The rejection, naming the suspect distance and those whose removal
    would do about as well (in its message and its ``labels``)."""
    starts = np.vstack([seeds, minima])
    # One refinement of every start without each distance in turn (a batch
    # of m groups, each seed with its own weights): the best chi^2 of a group
    # is that of its best converged minimum (of all its seeds if none has
    # converged), as _local_minima finds it.
    m, n_starts = measured.size, len(starts)
    weights = np.repeat(1.0 - np.eye(m), n_starts, axis=0)
    _, chi2_all, decrement_all = _refine(np.tile(starts, (m, 1)), geometry, measured, weights)
    remaining: list[float] = []
    for chi2_k, decrement_k in zip(
        chi2_all.reshape(m, n_starts), decrement_all.reshape(m, n_starts), strict=True
    ):
        converged = decrement_k < _CONVERGED_DECREMENT
        remaining.append(float(chi2_k[converged].min() if converged.any() else chi2_k.min()))
    order = np.argsort(remaining, kind="stable")
    suspect = int(order[0])
    others = [
        geometry.labels[int(k)] for k in order[1:] if remaining[int(k)] <= remaining[suspect] + 1.0
    ]
    also = f"; removing {', '.join(others)} would do about as well" if others else ""
    message = (
        f"no rigid motion explains the floor-mark distances within sigma "
        f"{geometry.sigma:g} m (best chi2 {chi2:.1f}, limit {limit:.1f} at level "
        f"{CONSISTENCY_LEVEL:g}). Suspect distance: {geometry.labels[suspect]} = "
        f"{measured[suspect]:.4f} m (without it chi2 is {remaining[suspect]:.2f}){also}."
    )
    return InconsistentMeasurementError(message, (geometry.labels[suspect], *others))
