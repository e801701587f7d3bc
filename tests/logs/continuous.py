"""A continuous recording for the windowing tests (issue 30, part 2): a
differential drive driving a long random path of curves, straight stretches
and turns in place without ever resting, sample by sample under the model's
errors (Martinelli's discrete model, as odohil/science/simulator.py: each
sample's encoder distance ds turns the true heading by E_R ds plus a normal of
variance K_theta |ds| and drives (1 + E_T) ds plus a normal of variance
K_rho |ds|, along the heading after its own rotation; in-place turns exact),
seen by a capture system with white pose noise pose_sigma, written as an
odohil log CSV (no rests, no trial column)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from odohil.science.parameters import ErrorParameters
from odohil.science.paths import FloatArray
from odohil.session.trials.logs.csv_log import write_csv_log
from odohil.session.trials.logs.recording import Recording

TRUE = ErrorParameters(e_r=-0.02, e_t=-0.015, k_theta=4e-5, k_rho=4e-5)
"""The simulated robot's errors (SI; heading drift and spread a few times the
Nomad 150's, so that 60 m of windows pin them within a test's time)."""
POSE_SIGMA = (0.0005, 0.0005, 0.001)
"""The capture's accuracy (x m, y m, theta rad), as the description states it."""

DESCRIPTION = f"""# a robot known from its continuous log
[robot]
protocol = "recorded"
counts_per_rev = 1000
wheel_diameter_m = 0.08
wheel_base_m = 0.2
turns_exact = true

[screws]
A = [0.10, 0.0]
B = [-0.05, 0.087]
C = [-0.05, -0.087]

[measurement]
sigma_m = 0.001
pose_sigma = [{POSE_SIGMA[0]}, {POSE_SIGMA[1]}, {POSE_SIGMA[2]}]
"""


@dataclass(frozen=True)
class Drive:
    """The encoder's steps (ds m, dtheta rad) of each sample interval."""

    ds: FloatArray
    dtheta: FloatArray


def random_drive(distance_m: float, seed: int, rate_hz: float = 10.0) -> Drive:
    """Curves, straight stretches, backward stretches and turns in place, one
    after another without a rest, until ``distance_m`` is driven."""
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate_hz
    ds_parts, dtheta_parts, driven = [], [], 0.0
    while driven < distance_m:
        kind = rng.choice(["curve", "straight", "back", "spin"], p=[0.5, 0.25, 0.1, 0.15])
        n = int(rng.integers(10, 40))
        v = {"curve": 0.3, "straight": 0.3, "back": -0.2, "spin": 0.0}[kind]
        w = {
            "curve": rng.uniform(-0.8, 0.8),
            "straight": 0.0,
            "back": rng.uniform(-0.2, 0.2),
            "spin": rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 1.5),
        }[kind]
        ds_parts.append(np.full(n, v * dt))
        dtheta_parts.append(np.full(n, w * dt))
        driven += abs(v) * dt * n
    return Drive(np.concatenate(ds_parts), np.concatenate(dtheta_parts))


def _integrate(ds: FloatArray, heading: FloatArray, end_heading: FloatArray) -> FloatArray:
    """Poses from each step's length ``ds`` along ``heading``, the heading
    after each step ``end_heading``."""
    x = np.concatenate([[0.0], np.cumsum(ds * np.cos(heading))])
    y = np.concatenate([[0.0], np.cumsum(ds * np.sin(heading))])
    return np.stack([x, y, np.concatenate([[0.0], end_heading])], axis=1)


def continuous_log(
    path: Path,
    distance_m: float = 60.0,
    seed: int = 1,
    params: ErrorParameters = TRUE,
    truth_gap_s: tuple[float, float] | None = None,
) -> Recording:
    """Write the continuous log of :func:`random_drive` to ``path`` (and
    return it); ``truth_gap_s`` blanks the ground truth over (from, to) s."""
    drive = random_drive(distance_m, seed)
    rng = np.random.default_rng(seed + 1000)
    encoder = np.cumsum(drive.dtheta)  # the encoder heading after each step
    along = encoder - 0.5 * drive.dtheta  # a step's chord: the heading half-way
    odometry = _integrate(drive.ds, along, encoder)
    size = np.abs(drive.ds)
    error = np.cumsum(  # the heading error after each step's own rotation
        params.e_r * drive.ds + rng.normal(0.0, 1.0, len(size)) * np.sqrt(params.k_theta * size)
    )
    rho = (1 + params.e_t) * drive.ds + rng.normal(0.0, 1.0, len(size)) * np.sqrt(
        params.k_rho * size
    )
    true = _integrate(rho, along + error, encoder + error)
    truth = true + rng.normal(0.0, 1.0, true.shape) * np.array(POSE_SIGMA)
    c, s = math.cos(0.7), math.sin(0.7)  # a world frame of its own
    world = np.stack(
        [1.5 + c * truth[:, 0] - s * truth[:, 1], -2.0 + s * truth[:, 0] + c * truth[:, 1],
         np.angle(np.exp(1j * (truth[:, 2] + 0.7)))],
        axis=1,
    )  # fmt: skip
    t = 100.0 + 0.1 * np.arange(len(world))
    if truth_gap_s is not None:
        world[(t >= truth_gap_s[0]) & (t <= truth_gap_s[1])] = np.nan
    recording = Recording(
        source=str(path),
        t_s=t,
        odometry=odometry,
        truth=world,
        where=np.arange(2, len(t) + 2, dtype=np.int64),
    )
    write_csv_log(path, recording)
    return recording


def write_description(folder: Path, pose_sigma: bool = True) -> Path:
    """The robot description of the log (without ``pose_sigma`` on request)."""
    path = folder / "robot.toml"
    text = DESCRIPTION if pose_sigma else DESCRIPTION.replace("pose_sigma", "# pose_sigma")
    path.write_text(text)
    return path
