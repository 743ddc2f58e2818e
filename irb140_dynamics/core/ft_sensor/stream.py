"""A wrist force/torque sensor against a stream of joint states: what a node runs.

Joint states (t [s], q, qd) are kept for a short while (HISTORY of them), each with qdd
from the velocities (core.monitoring.filters: a finite difference through a first-order
low-pass). A reading (t, 6 numbers as ``contact``'s) is matched to the joint state nearest
in time (at most MAX_GAP away) and gives the contact wrench; a reading stamped in a frame
other than the sensor's link (its header.frame_id; "" and a leading "/" accepted) is
refused, as its numbers are in other axes or about another point. Readings at rest (every joint
slower than REST_VELOCITY for REST_TIME, as payload_check_node's defaults) are averaged,
one sample per pose, for ``estimate``: the bias is used at once; the samples are forgotten
after an estimate (the next one uses the poses since).
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from irb140_dynamics.core.errors import check_choice
from irb140_dynamics.core.ft_sensor.contact import FRAMES, NO_BIAS, contact_wrench, sensor_mount
from irb140_dynamics.core.ft_sensor.load_estimation import FtLoadEstimate, estimate_ft_load
from irb140_dynamics.core.io.urdf.writer import exported_carried
from irb140_dynamics.core.model.joint_order import BadMessage
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.monitoring.filters import VelocityDifferentiator
from irb140_dynamics.core.payload.mass_com_estimation import EstimationError
from irb140_dynamics.core.payload.rest_samples import RestDetector

HISTORY = 200  # joint states kept to match readings with
MAX_GAP = 0.1  # s: a reading farther than this from every joint state kept is dropped
REST_VELOCITY, REST_TIME = 0.02, 0.5  # rad/s, s
MAX_FORCE, MAX_TORQUE = 1e5, 1e4  # N, N m: a reading beyond is refused as absurd


class FtSensorStream:
    """The contact wrenches of a sensor's readings, and the rests kept for its load's estimate."""

    def __init__(self):
        self.model: RobotModel | None = None  # None: off
        self.link, self.mount, self.frame, self.bias = "", np.eye(4), "sensor", NO_BIAS.copy()
        self.rests = RestDetector(REST_VELOCITY, REST_TIME)
        self._states: deque = deque(maxlen=HISTORY)
        self._differentiator: VelocityDifferentiator | None = None

    def use(self, model: RobotModel, link: str, frame: str, carried, cutoff: float, strict: bool = True) -> str | None:
        """The settings in force: the sensor on ``link`` ("" = off) of ``model``, among the
        links its joints move (``LoadedUrdf.carried``; None: ``exported_carried``, the model's
        of parameters; see ``contact.sensor_mount``), the contact wrench in ``frame``'s axes, qdd through a
        low-pass of ``cutoff`` [Hz]. A link or frame refused: ValueError, nothing changed
        (``strict``), or the sensor off and the refusal returned. A model of other joints
        forgets the joint states and rests seen."""
        try:
            check_choice("ft_contact_wrench.frame", frame, FRAMES)
            mount = sensor_mount(model, link, exported_carried(model) if carried is None else carried) if link else None
        except ValueError as error:
            if strict:
                raise
            self.use(model, "", "sensor", carried, cutoff)
            return f"{error}; the force/torque sensor is off"
        if not link or self.model is None or model.joint_names != self.model.joint_names:
            self._states.clear()
            self.rests.clear()
        differentiator = self._differentiator
        if not link:
            differentiator = None
        elif differentiator is None or differentiator.n != model.n or differentiator.time_constant != _lag(cutoff):
            differentiator = VelocityDifferentiator(model.n, cutoff)
        self._differentiator = differentiator
        self.model, self.link, self.mount, self.frame = model if link else None, link, mount, frame
        return None

    def note(self, t: float, q, qd) -> None:
        """A joint state at t [s] (finite q, qd of the model's joints); nothing while off."""
        if self.model is None:
            return
        qdd = np.array(self._differentiator.update(t, qd.tolist()))
        if not np.isfinite(qdd).all():
            self._differentiator.reset()
            return
        self._states.append((t, q, qd, qdd))

    def contact(self, t: float, reading, frame_id: str = "") -> np.ndarray:
        """The contact wrench of a reading at t [s] (see ``contact``) given in ``frame_id``
        ("": the sensor's link), in ``frame``'s axes; the reading kept if the arm rests.
        BadMessage: a reading in another link's frame, not finite or absurd, no joint state
        near it, a joint state too fast for a finite contact wrench."""
        if frame_id and frame_id.removeprefix("/") != self.link:
            raise BadMessage("wrong_frame", f"reading in frame {frame_id!r}, the sensor is on {self.link!r}")
        reading = np.asarray(reading, dtype=float)
        if reading.shape != (6,) or not np.isfinite(reading).all():
            raise BadMessage("not_finite", f"reading not 6 finite numbers: {reading.tolist()}")
        force, torque = math.hypot(*reading[:3]), math.hypot(*reading[3:])
        if force > MAX_FORCE or torque > MAX_TORQUE:
            raise BadMessage("absurd_wrench", f"|force| {force:.3g} N, |torque| {torque:.3g} N m")
        if not self._states:
            raise BadMessage("no_joint_state", "no joint state yet")
        gap, (_, q, qd, qdd) = self._nearest(t)
        if gap > MAX_GAP:
            raise BadMessage("no_joint_state", f"the nearest joint state is {gap:.3g} s from the reading")
        with np.errstate(all="ignore"):
            contact = contact_wrench(self.model, q, qd, qdd, reading, self.mount, self.bias, self.frame)
        if not np.isfinite(contact).all():  # a joint state too fast for the model's numbers
            raise BadMessage("not_finite_contact", f"no finite contact wrench at qd = {qd.tolist()} rad/s")
        self.rests.update(t, q, qd, reading)
        return contact

    def _nearest(self, t: float) -> tuple[float, tuple]:
        """(|gap| [s], the joint state nearest t): searched from the newest back, until the
        states are older than the best gap (they come in time order; ties: the newest)."""
        best = None
        for joint_state in reversed(self._states):
            gap = abs(joint_state[0] - t)
            if best is None or gap < best[0]:
                best = (gap, joint_state)
            elif joint_state[0] < t - best[0]:
                break
        return best

    def estimate(self) -> FtLoadEstimate:
        """The bias and the tool's load from the rests since the start or the last estimate,
        the bias used at once; EstimationError (nothing changed) when they cannot tell."""
        if self.model is None:
            raise EstimationError("the force/torque sensor is off: no model yet, or ft_sensor.link empty or refused")
        self.rests.flush()
        estimate = estimate_ft_load(self.model, self.rests.samples, self.mount)
        self.bias = estimate.bias
        self.rests.clear()
        return estimate


def sensor_refusal(model: RobotModel, link: str, carried) -> str | None:
    """Why the sensor cannot be on ``link`` of ``model`` (one line; ``use``'s arguments), or None."""
    try:
        if link:
            sensor_mount(model, link, exported_carried(model) if carried is None else carried)
    except ValueError as error:
        return str(error)
    return None


def _lag(cutoff: float) -> float:
    """The time constant [s] of a first-order low-pass of ``cutoff`` [Hz] (as VelocityDifferentiator's)."""
    return 1.0 / (2.0 * math.pi * cutoff)
