"""Virtual force sensors at several links: the wrenches that jointly explain the external
joint torques (id_node's ``external_wrench.links``, on a tree or a chain).

Wrenches F_k (force [N]; torque [N m] about link k's origin, both in link k's axes) on the
links L_1..L_m load the joints with tau_ext = sum_k J_k^T F_k, J_k the 6 x n Jacobian of
link k's frame (rows v; w) turned into its own axes: the columns of the joints it hangs
from, zero for the others (``kinematics.placed_pose_and_jacobian``). Stacked, J = [J_1;
...; J_m] (6m x n), F is the least-squares solution of J^T F = tau_ext, damped near a
singularity as the flange's (``damped_solution``; the rule: ``wrench``'s module): exact
when the links' joints tell their wrenches apart (J^T of full column rank 6m, e.g. two arms
of six joints or more each, one link on each), the least-norm one otherwise. External
torques from anywhere else (a push on the torso, on a link not listed) are read as the
listed links' wrenches that explain them best: list every link that may be touched.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.kinematics import placed_pose_and_jacobian
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.model.states import state

SINGULAR_THRESHOLD = 0.05  # sigma_min of J below this: damped, and flagged as near a singularity
MAX_DAMPING = 0.05  # lambda at sigma_min = 0
MAX_LINKS = 16  # links of external_wrench.links


@dataclass(frozen=True)
class LinkWrench:
    """The estimated wrench on one link, in its axes, the torque about its origin; finite."""

    link: str
    force: np.ndarray  # (3,) N
    torque: np.ndarray  # (3,) N m


def damped_solution(Jt: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, float, float]:
    """(F, sigma_min, lambda): the least-squares solution of Jt F = tau through Jt's singular
    value decomposition, damped below SINGULAR_THRESHOLD (see ``wrench``'s module)."""
    U, s, Vt = np.linalg.svd(Jt, full_matrices=False)  # Jt = U diag(s) Vt, s descending
    sigma_min = float(s[-1])
    damping = 0.0
    if sigma_min < SINGULAR_THRESHOLD:
        damping = MAX_DAMPING * math.sqrt(1.0 - (sigma_min / SINGULAR_THRESHOLD) ** 2)
    inverse = np.divide(s, s * s + damping * damping, out=np.zeros_like(s), where=s > 0.0)
    return Vt.T @ (inverse * (U.T @ tau)), sigma_min, damping


def turned(R: np.ndarray, J: np.ndarray) -> np.ndarray:
    """J's rows (v; w) turned by R: both halves."""
    return np.vstack([R @ J[:3], R @ J[3:]])


def wrench_places(links: Sequence[str], carried: Mapping | None) -> tuple[tuple[str, str, object], ...]:
    """(link, the joint moving it, its placement in that joint's link frame) of each link,
    from ``carried`` (``LoadedUrdf.carried``; None: no URDF); ValueError naming
    external_wrench.links for a link the model does not move, a repeated one, or too many."""
    links = list(links or ())
    if not links:
        return ()
    if carried is None:
        raise ValueError("external_wrench.links: names URDF links; the model is no URDF's (model.source)")
    if len(links) > MAX_LINKS:
        raise ValueError(f"external_wrench.links: at most {MAX_LINKS} links; got {len(links)}")
    repeated = next((link for k, link in enumerate(links) if link in links[:k]), None)
    if repeated is not None:
        raise ValueError(f"external_wrench.links: {str(repeated)[:80]!r} is named twice; name each link once")
    for link in links:
        if link not in carried:
            raise ValueError(f"external_wrench.links: {str(link)[:80]!r} is not moved by the model's joints")
    return tuple((link, *carried[link]) for link in links)


def link_wrenches(model: RobotModel, q, tau_ext, places) -> tuple[tuple[LinkWrench, ...], float, float]:
    """(the wrench on each link of ``places`` (``wrench_places``), J's smallest singular
    value, the damping used): the joint least-squares solution of the module. ValueError if
    q or tau_ext are not n finite numbers or the solution is not finite."""
    tau_ext = state(tau_ext, model.n, "tau_ext")
    blocks = []
    for _, joint, placement in places:
        pose, J = placed_pose_and_jacobian(model, q, joint, placement)
        blocks.append(turned(pose[:3, :3].T, J))
    F, sigma_min, damping = damped_solution(np.vstack(blocks).T, np.asarray(tau_ext))
    if not np.isfinite(F).all():
        raise ValueError(f"link wrenches not finite for tau_ext {list(tau_ext)}")
    wrenches = tuple(
        LinkWrench(link, F[6 * k : 6 * k + 3], F[6 * k + 3 : 6 * k + 6]) for k, (link, *_) in enumerate(places)
    )
    return wrenches, sigma_min, damping
