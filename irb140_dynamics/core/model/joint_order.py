"""Joints matched by name: where each of a model's joints sits in a list of joint names.

Used for every stream of joint values (JointState messages, recordings), whatever carries
them: a name list may hold the model's joints in any order and other joints besides. A
message refused is a BadMessage, e.g. one the model gives no finite torques for
(``finite_torques``).
"""

from __future__ import annotations

import math

import numpy as np


class BadMessage(ValueError):
    """A message that must not yield torques; ``kind`` is a short tag for counting."""

    def __init__(self, kind: str, detail: str):
        super().__init__(f"{kind}: {detail}")
        self.kind = kind


class NotForThisModel(BadMessage):
    """A message about none of the model's joints (a gripper's, another arm's): ignored."""


class JointOrder:
    """Where each of the model's joints sits in a message's name list.

    Cached per name list: streams from a few publishers (arm, gripper) each keep theirs.
    """

    _CACHE_SIZE = 16

    def __init__(self, joint_names):
        self.joint_names = tuple(joint_names)
        self._cache: dict[tuple, list[int]] = {}

    def indices(self, names) -> list[int]:
        names = tuple(names)
        index = self._cache.get(names)
        if index is None:
            index = self._match(names)
            if len(self._cache) >= self._CACHE_SIZE:
                self._cache.clear()
            self._cache[names] = index
        return index

    def for_values(self, names, count: int) -> tuple[list[int], int]:
        """(indices, length every value field must have) for a message naming ``names`` with
        ``count`` positions: one without names is taken positionally if ``count`` is n."""
        if not names and count == len(self.joint_names):
            return list(range(count)), count
        return self.indices(names), len(names)

    def _match(self, names: tuple) -> list[int]:
        if not names:
            raise BadMessage("unnamed", "no joint names and the lengths do not match the model")
        if len(set(names)) != len(names):
            raise BadMessage("duplicate_names", f"duplicate joint names in {list(names)}")
        where = {name: i for i, name in enumerate(names)}
        missing = [name for name in self.joint_names if name not in where]
        if len(missing) == len(self.joint_names):
            raise NotForThisModel("other_joints", f"none of the model's joints in {list(names)}")
        if missing:
            raise BadMessage("missing_joints", f"no {', '.join(missing)} in {list(names)}")
        return [where[name] for name in self.joint_names]


def core_result(function, model, *state):
    """``function(model, *state)``; the core's refusal (ValueError: a state too large for
    the model, the torques not finite) as BadMessage non_finite_torques."""
    try:
        return function(model, *state)
    except ValueError as error:
        raise BadMessage("non_finite_torques", str(error)) from None


def finite_torques(function, model, *state):
    """``function(model, *state)`` (rnea, gravity) when all its torques are finite, else
    BadMessage non_finite_torques (an absurd but finite state can overflow the model's sums)."""
    tau = core_result(function, model, *state)
    values = tau.tolist() if type(tau) is np.ndarray else tau  # a sum of floats: a fraction of NumPy's
    if not (math.isfinite(sum(values)) or all(map(math.isfinite, values))):
        raise BadMessage("non_finite_torques", f"the model gives {[float(x) for x in tau]}")
    return tau
