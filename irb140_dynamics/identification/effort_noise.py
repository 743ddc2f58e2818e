"""The recorded efforts' noise a payload excitation is designed for (``--effort-noise``):
N m on every joint, or a fraction of each joint's torque limit."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.model.robot_model import RobotModel


@dataclass(frozen=True)
class EffortNoise:
    """The recorded efforts' noise, one standard deviation per sample: ``value`` N m on
    every joint, or (``relative``) that fraction of each joint's torque limit, of its peak
    torque along the motion (the arm's own, without the payload) where the model gives none."""

    value: float
    relative: bool = True

    def __post_init__(self):
        if not (math.isfinite(self.value) and self.value > 0.0) or (self.relative and self.value >= 1.0):
            raise ValueError(f"effort noise: must be > 0{' and below 100 %' if self.relative else ''}, got {self}")

    @classmethod
    def parse(cls, text: str) -> EffortNoise:
        """'1%' (of each joint's torque limit) or '0.05' (N m); ValueError in one line."""
        body = text.strip()
        relative = body.endswith("%")
        try:
            value = float(body[:-1] if relative else body)
        except ValueError:
            raise ValueError(f"effort noise: expected N m (0.05) or a percentage (1%), got {text!r}") from None
        return cls(value / 100.0 if relative else value, relative)

    def sigma(self, model: RobotModel, peak: np.ndarray) -> np.ndarray:
        """(n,) N m: each joint's noise; ``peak`` (n,) its peak torque along the motion."""
        if not self.relative:
            return np.full(model.n, self.value)
        limits = np.array(model.torque_limits, dtype=float)
        scale = np.where(limits > 0.0, limits, peak)
        return self.value * np.maximum(scale, 1e-6 * max(float(scale.max()), 1e-9))

    def __str__(self) -> str:
        if self.relative:
            return f"{100.0 * self.value:g} % of each joint's torque limit (peak torque where it has none)"
        return f"{self.value:g} N m"


DEFAULT_EFFORT_NOISE = EffortNoise(0.01)
