"""Localisation error: what each robot believes its pose is, while pymunk moves its true body.

Off by default (``model = "perfect"``: the estimate is the true pose and nothing here runs). With a model on,
a robot senses, maps, plans and shares in its *estimated* frame (:mod:`swarm.sim.loop`): its lidar measures
ranges from where it is and writes them from where it believes it is (:meth:`swarm.world.sensing.Lidar.
write_from`), a map it merges from another robot lands where that robot believed it was, and its navigator
drives the true body with commands computed on the estimate.

Two models (issue 50):

- ``"odometry"``: dead reckoning with no correction, as on a wheeled robot whose odometry is integrated
  alone. Each tick the true motion (distance ``ds`` along the heading, turn ``dth``) is measured with a
  systematic error drawn once per robot, ``ds (1 + s) + e``, ``dth (1 + t) + h ds + f``: ``s`` (scale
  error, std ``drift_per_m``: 0.02 is the classic "2 % of the distance travelled"), ``t`` (turn scale
  error, std ``turn_drift_per_rad``), ``h`` (heading drift per metre travelled, std ``heading_drift_per_m``
  rad/m: unequal wheel radii bend a straight drive into an arc, and the heading error then grows the
  position error), and random noise ``e`` ~ N(0, noise_per_m^2 |ds|), ``f`` ~ N(0, noise_per_rad^2 |dth|)
  (a random walk: its std grows with the square root of the distance or angle). The estimate integrates
  the measured motion from the true start pose (the robot knows where it starts).
- ``"bounded"``: a localiser of a given accuracy, as a SLAM system with loop closure gives: the estimate is
  the true pose plus an error whose x, y and heading components each have stationary standard deviation
  ``sigma_m`` (m) or ``sigma_rad`` (rad), made of a temporally correlated part (an Ornstein-Uhlenbeck
  process with time constant ``correlation_s``) and a spatially correlated part (a smooth random field over
  the map, bilinear between random offsets on a grid of spacing ``correlation_m``, drawn once per robot),
  ``spatial_share`` of the variance in the second.

Random numbers: robot i draws from ``SeedSequence(seed, spawn_key=(LOCALIZATION_STREAM, i))``, a stream of
its own, so no other stream of a run changes when localisation is switched on, and a robot's error does not
depend on how many robots there are.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from swarm.base.params import OMIT_DEFAULT, check_choice, check_float

LOCALIZATION_MODELS: tuple[str, ...] = ("perfect", "odometry", "bounded")
LOCALIZATION_STREAM = 6
"""Robot i's localisation errors draw from ``SeedSequence(seed, spawn_key=(LOCALIZATION_STREAM, i))``."""


@dataclass(frozen=True)
class LocalizationSpec:
    """The run spec's ``[localization]`` section (module docstring). Left out of a spec while ``perfect``."""

    model: str = field(default="perfect", metadata={OMIT_DEFAULT: True})
    drift_per_m: float = 0.02
    turn_drift_per_rad: float = 0.02
    heading_drift_per_m: float = 0.005
    noise_per_m: float = 0.01
    noise_per_rad: float = 0.01
    sigma_m: float = 0.1
    sigma_rad: float = 0.02
    correlation_s: float = 10.0
    correlation_m: float = 5.0
    spatial_share: float = 0.5

    def __post_init__(self) -> None:
        check_choice("localization.model", self.model, LOCALIZATION_MODELS)
        for name in ("drift_per_m", "turn_drift_per_rad", "noise_per_m", "noise_per_rad"):
            check_float(f"localization.{name}", getattr(self, name), 0.0, 1.0)
        check_float("localization.heading_drift_per_m", self.heading_drift_per_m, 0.0, 1.0)
        check_float("localization.sigma_m", self.sigma_m, 0.0, 100.0)
        check_float("localization.sigma_rad", self.sigma_rad, 0.0, math.pi)
        check_float("localization.correlation_s", self.correlation_s, 0.0, 1e6, lo_open=True)
        check_float("localization.correlation_m", self.correlation_m, 0.0, 1e6, lo_open=True)
        check_float("localization.spatial_share", self.spatial_share, 0.0, 1.0)

    @property
    def on(self) -> bool:
        return self.model != "perfect"


class Localizer:
    """Every robot's pose estimate, updated once per tick from the true poses (``float64[R, 3]``)."""

    def __init__(self, spec: LocalizationSpec, seed: int, true_poses: np.ndarray, tick_s: float,
                 map_size_m: tuple[float, float]) -> None:
        self.spec = spec
        n = true_poses.shape[0]
        self.rngs = [np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(LOCALIZATION_STREAM, i)))
                     for i in range(n)]
        self.tick_s = tick_s
        self._last_true = np.array(true_poses, dtype=np.float64)
        self.estimates = np.array(true_poses, dtype=np.float64)
        if spec.model == "odometry":
            bias = np.array([rng.standard_normal(3) for rng in self.rngs]).reshape(n, 3)
            self._scale = bias[:, 0] * spec.drift_per_m
            self._turn = bias[:, 1] * spec.turn_drift_per_rad
            self._heading = bias[:, 2] * spec.heading_drift_per_m
        elif spec.model == "bounded":
            temporal = math.sqrt(1.0 - spec.spatial_share)
            spatial = math.sqrt(spec.spatial_share)
            sig = np.array([spec.sigma_m, spec.sigma_m, spec.sigma_rad])
            self._sig_t = sig * temporal
            w, h = map_size_m
            gx = int(math.ceil(w / spec.correlation_m)) + 2
            gy = int(math.ceil(h / spec.correlation_m)) + 2
            self._field = np.array([rng.standard_normal((gy, gx, 3)) for rng in self.rngs]).reshape(n, gy, gx, 3)
            self._field *= sig * spatial
            self._ou = np.array([rng.standard_normal(3) for rng in self.rngs]).reshape(n, 3) * self._sig_t
            self._decay = math.exp(-tick_s / spec.correlation_s)
            self.estimates = true_poses + self._error(true_poses)
            self.estimates[:, 2] = _wrap(self.estimates[:, 2])

    def update(self, true_poses: np.ndarray, active: np.ndarray | None = None) -> np.ndarray:
        """The estimates after the robots moved to ``true_poses`` (robots not ``active`` keep theirs)."""
        spec = self.spec
        if spec.model == "odometry":
            self._odometry(true_poses, active)
        elif spec.model == "bounded":
            d = self._decay
            kick = math.sqrt(1.0 - d * d)
            for i, rng in enumerate(self.rngs):
                if active is None or active[i]:
                    self._ou[i] = self._ou[i] * d + rng.standard_normal(3) * self._sig_t * kick
            est = true_poses + self._error(true_poses)
            est[:, 2] = _wrap(est[:, 2])
            if active is not None:
                est[~active] = self.estimates[~active]
            self.estimates = est
        self._last_true = np.array(true_poses, dtype=np.float64)
        return self.estimates

    def _odometry(self, true_poses: np.ndarray, active: np.ndarray | None) -> None:
        from .motion import wrap_angle   # here: the run spec imports this module, and motion loads numba

        spec = self.spec
        last = self._last_true
        for i, rng in enumerate(self.rngs):
            if active is not None and not active[i]:
                continue
            dx, dy = true_poses[i, 0] - last[i, 0], true_poses[i, 1] - last[i, 1]
            dth = wrap_angle(true_poses[i, 2] - last[i, 2])
            mid = last[i, 2] + 0.5 * dth
            ds = dx * math.cos(mid) + dy * math.sin(mid)          # signed distance along the heading
            noise = rng.standard_normal(2)
            ds_m = ds * (1.0 + self._scale[i]) + noise[0] * spec.noise_per_m * math.sqrt(abs(ds))
            dth_m = (dth * (1.0 + self._turn[i]) + self._heading[i] * ds
                     + noise[1] * spec.noise_per_rad * math.sqrt(abs(dth)))
            est = self.estimates[i]
            heading = est[2] + 0.5 * dth_m
            est[0] += ds_m * math.cos(heading)
            est[1] += ds_m * math.sin(heading)
            est[2] = wrap_angle(est[2] + dth_m)

    def _error(self, true_poses: np.ndarray) -> np.ndarray:
        """The bounded model's error at the true poses: the temporal part plus the spatial field there."""
        cm = self.spec.correlation_m
        gx = np.clip(true_poses[:, 0] / cm, 0.0, self._field.shape[2] - 1.000001)
        gy = np.clip(true_poses[:, 1] / cm, 0.0, self._field.shape[1] - 1.000001)
        ix, iy = gx.astype(np.int64), gy.astype(np.int64)
        fx, fy = (gx - ix)[:, None], (gy - iy)[:, None]
        r = np.arange(true_poses.shape[0])
        f = self._field
        spatial = ((1 - fx) * (1 - fy) * f[r, iy, ix] + fx * (1 - fy) * f[r, iy, ix + 1]
                   + (1 - fx) * fy * f[r, iy + 1, ix] + fx * fy * f[r, iy + 1, ix + 1])
        return self._ou + spatial

    def errors(self, true_poses: np.ndarray) -> np.ndarray:
        """Per robot: the position error (m) and the absolute heading error (rad) of the estimate."""
        d = self.estimates - true_poses
        return np.column_stack([np.hypot(d[:, 0], d[:, 1]), np.abs(_wrap(d[:, 2]))])


def _wrap(a: np.ndarray) -> np.ndarray:
    """:func:`swarm.world.motion.wrap_angle` on an array."""
    return np.pi - (np.pi - a) % (2.0 * np.pi)


__all__ = ["LOCALIZATION_MODELS", "LOCALIZATION_STREAM", "LocalizationSpec", "Localizer"]
