"""A virtual force sensor at the flange: the wrench that explains the external joint torques.

A wrench F = (f [N], m [N m] about the flange origin) acting on the flange loads the joints
with tau_ext = J(q)^T F, J the flange's 6 x n geometric Jacobian (rows v; w) in the axes
the wrench is given in: the base frame's (``base``) or the flange's own (``tip``, J's rows
turned by R^T, R the flange's orientation in the base frame). Given the observer's
external torques, F is the least-squares solution of J^T F = tau_ext through J's singular
value decomposition: exact for 6 joints, the best fit for more, and for fewer (where many
wrenches give the same torques) the one of least norm.

Near a singularity (J's smallest singular value sigma_min below SINGULAR_THRESHOLD) the
plain solution would amplify noise without bound along the lost direction; there the
solution is damped (Nakamura and Hanafusa 1986; Chiaverini 1997): each singular value s
is inverted as s / (s^2 + lambda^2) with lambda^2 = (1 - (sigma_min /
SINGULAR_THRESHOLD)^2) MAX_DAMPING^2, zero at the threshold (continuous) and MAX_DAMPING^2
at sigma_min = 0. Elsewhere lambda = 0: the plain least-squares solution, unbiased. The
singular values mix metres (a turning joint's v) and ones (its w); the threshold, 0.05,
is what a wrist of centimetres or an elbow of a few degrees from stretched gives on an
arm of the IRB-140's size.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.kinematics import flange_pose_and_jacobian
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.model.states import state
from irb140_dynamics.core.monitoring.link_wrenches import (
    MAX_DAMPING as MAX_DAMPING,  # the damping's rule is stated here (the module) and shared
)
from irb140_dynamics.core.monitoring.link_wrenches import (
    SINGULAR_THRESHOLD,
    LinkWrench,
    damped_solution,
    link_wrenches,
    turned,
    wrench_places,
)

FRAMES = ("tip", "base")


@dataclass(frozen=True)
class FlangeWrench:
    """The estimated wrench on the flange, in the axes of ``frame``, finite."""

    force: np.ndarray  # (3,) N
    torque: np.ndarray  # (3,) N m, about the flange origin
    frame: str  # "tip" or "base"
    smallest_singular_value: float  # of J (at most 6 of them)
    damping: float  # lambda used (0: the plain least-squares solution)

    @property
    def near_singularity(self) -> bool:
        return self.smallest_singular_value < SINGULAR_THRESHOLD

    @property
    def vector(self) -> np.ndarray:
        """(force, torque), 6 numbers."""
        return np.concatenate([self.force, self.torque])


def flange_jacobian_in(model: RobotModel, q, frame: str = "base") -> np.ndarray:
    """The flange's 6 x n Jacobian with its rows (v; w) in the base's axes or the flange's
    (``tip``): v the flange origin's velocity, w the flange's angular velocity."""
    _check_frame(frame)
    pose, J = flange_pose_and_jacobian(model, q)
    return J if frame == "base" else turned(pose[:3, :3].T, J)


TREE_REFUSAL = (
    "no external wrench on a tree or with mimic joints without external_wrench.links: the external "
    "torques of every branch would be read as one flange's wrench; external_torques only"
)


def wrench_refusal(model: RobotModel) -> str | None:
    """Why ``model`` has no flange wrench (a tree, mimic joints, the flange off the last link), or None."""
    return None if model.is_chain else TREE_REFUSAL


def flange_wrench(model: RobotModel, q, tau_ext, frame: str = "tip") -> FlangeWrench:
    """The wrench F on the flange with J(q)^T F = tau_ext [N m] (see the module), in the axes
    of ``frame``. ValueError if q or tau_ext are not n finite numbers, for another frame, or
    on a model that is no chain (``wrench_refusal``)."""
    _check_frame(frame)
    if not model.is_chain:
        raise ValueError(TREE_REFUSAL)
    tau_ext = state(tau_ext, model.n, "tau_ext")
    pose, J = flange_pose_and_jacobian(model, q)
    return wrench_of(pose, J, tau_ext, frame)


def wrench_of(pose: np.ndarray, J: np.ndarray, tau_ext, frame: str = "tip") -> FlangeWrench:
    """``flange_wrench`` from the flange pose and base-axes Jacobian already computed for q
    (``kinematics.flange_pose_and_jacobian``). ValueError if tau_ext is not n finite numbers,
    or for another frame."""
    _check_frame(frame)
    tau_ext = state(tau_ext, J.shape[1], "tau_ext")
    if frame == "tip":
        J = turned(pose[:3, :3].T, J)
    F, sigma_min, damping = damped_solution(J.T, tau_ext)
    if not np.isfinite(F).all():
        raise ValueError(f"flange wrench not finite for tau_ext {tau_ext.tolist()}")
    return FlangeWrench(F[:3], F[3:], frame, sigma_min, damping)


def in_base_axes(pose: np.ndarray, wrench) -> np.ndarray:
    """A wrench (force; torque about the flange origin) given in the flange's axes, in the
    base's: both turned by the flange's orientation R (the point stays the flange origin)."""
    R, w = pose[:3, :3], np.asarray(wrench, dtype=float)
    return np.concatenate([R @ w[:3], R @ w[3:]])


def _check_frame(frame: str) -> None:
    if frame not in FRAMES:
        raise ValueError(f"frame: must be 'tip' or 'base', got {frame!r}")


class WrenchStream:
    """The flange wrenches (or, with ``use``, the wrenches on named links) of a stream of
    observed samples (q, external torques), and how near a singularity they came since the
    last report."""

    def __init__(self):
        self.places: tuple = ()  # (link, joint, placement) of external_wrench.links (link_wrenches)
        self.forget()

    def forget(self) -> None:
        """A new model: the last sample belongs to the old one."""
        self._sample, self._smallest = None, None  # (model, q, r); the smallest sigma_min since the last report

    def use(self, links, carried, strict: bool) -> str | None:
        """Estimate the wrenches on ``links`` (URDF links; ``carried``: ``LoadedUrdf.carried``,
        None: no URDF) from now on; empty: the flange's. A link the model does not move:
        ValueError if ``strict`` (at startup), else the links off and the reason returned."""
        try:
            self.places = wrench_places(links, carried)
        except ValueError as error:
            self.places = ()
            if strict:
                raise
            return f"{error}; no link wrenches"
        return None

    @property
    def refusal(self) -> str | None:
        """Why no wrench is estimated for the last sample's model, or None."""
        return None if self._sample is None or self.places else wrench_refusal(self._sample[0])

    def note(self, model: RobotModel, q, tau_ext) -> None:
        """An observed sample, reported on even when no wrench is asked of it."""
        self._sample = (model, q, tau_ext)

    def estimate(self, frame: str) -> FlangeWrench:
        """The wrench of the last sample noted, in the axes of ``frame`` (ValueError if not finite)."""
        wrench = flange_wrench(*self._sample, frame)
        self._note_sigma(wrench.smallest_singular_value)
        return wrench

    def estimate_links(self) -> tuple[LinkWrench, ...]:
        """The wrenches on the links of ``use`` at the last sample noted, each in its link's
        axes (``link_wrenches``; ValueError if not finite)."""
        wrenches, sigma, _ = link_wrenches(*self._sample, self.places)
        self._note_sigma(sigma)
        return wrenches

    def _note_sigma(self, sigma: float) -> None:
        self._smallest = sigma if self._smallest is None else min(self._smallest, sigma)

    def report(self) -> tuple[bool, str, dict[str, str]]:
        """(near a singularity now or at a wrench since the last report, the message, the
        smallest singular values of J); starts a new period."""
        if self._sample is None:
            return False, "no efforts received: no wrench estimated", {}
        if self.refusal:
            return False, self.refusal, {}
        try:
            if self.places:
                sigma = link_wrenches(*self._sample, self.places)[1]
            else:
                sigma = flange_wrench(*self._sample, "tip").smallest_singular_value
        except ValueError as error:
            return True, f"no wrench at the last joint state ({error})", {}
        smallest = sigma if self._smallest is None else min(self._smallest, sigma)
        self._smallest = None
        values = {
            "smallest singular value of J, now": f"{sigma:.4f}",
            "smallest singular value of J since last report": f"{smallest:.4f}",
        }
        if smallest >= SINGULAR_THRESHOLD:
            return False, f"smallest singular value of J {smallest:.4f}", values
        where = "now" if sigma < SINGULAR_THRESHOLD else "since the last report"
        message = (
            f"near a singularity {where}: smallest singular value of J {smallest:.4f} < {SINGULAR_THRESHOLD:g}; "
            "the wrench estimate is damped and poor along the direction the arm cannot push"
        )
        return True, message, values
