"""Where a node's model comes from: its parameters, or a URDF (robot_description).

``model.source`` (read-only):

- ``parameters`` (default): the model's parameters (``joint_names``, ``<joint>.*``; see
  ``params.declare_model``), as in config/irb140.yaml.
- ``robot_description``: the chain from ``model.base_link`` to ``model.tip_link`` of a URDF
  (see ``core.urdf``), taken from the string parameter ``robot_description`` when it is set,
  else from the file ``model.urdf_file`` when that is set, else from the topic
  ``robot_description`` (std_msgs/String, reliable, transient local: as
  robot_state_publisher publishes it). From the topic, the node waits (publishing
  nothing) until a valid model arrives; each later URDF is checked whole, with the current
  parameters, and then swapped in at once, or refused (logged) keeping the model in use.
  The per-joint parameters are not declared in this mode: the URDF gives the joints, their
  names, inertials, limits and friction; ``gravity`` (here in the URDF's root frame, turned
  into base_link's), ``friction.smoothing_velocity``, ``payload.*`` (on the tip link) and
  the node's own parameters work as with parameters. The loader's warnings (inertials
  taken as given) are logged as warnings, its notes (invalid inertials off the chain) as info.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from typing import Any

from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

from irb140_dynamics.core import Joint, RigidBody, RobotModel
from irb140_dynamics.core.errors import one_line
from irb140_dynamics.core.io.urdf import LoadedUrdf, UrdfError, load_urdf, read_urdf
from irb140_dynamics.ros.parameters.live import LiveParameters
from irb140_dynamics.ros.parameters.spec import declare
from irb140_dynamics.ros.parameters.specs import Spec, check_choice, declare_model, model_specs

PerJoint = Callable[[list[str]], list[Spec]]  # a node's parameters for each joint of a model
SOURCES = ("parameters", "robot_description")
DESCRIPTION_QOS = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
STAND_IN = RobotModel((Joint("stand_in", link=RigidBody(1.0)),))  # checks the parameters before a URDF comes
SOURCE = Spec(
    "model.source",
    "parameters",
    "where the model comes from: 'parameters' (joint_names and <joint>.*) or 'robot_description' (URDF)",
    read_only=True,
)
DESCRIPTION_PARAMETERS = [
    Spec(
        "robot_description",
        "",
        "the URDF text (model.source robot_description); empty: model.urdf_file, else the robot_description topic",
        read_only=True,
    ),
    Spec(
        "model.urdf_file",
        "",
        "a URDF file, when robot_description is empty; empty: the robot_description topic",
        read_only=True,
    ),
    Spec("model.base_link", "", "the URDF link the chain starts from (fixed); empty: the root link", read_only=True),
    Spec(
        "model.tip_link",
        "",
        "the URDF link where the chain ends, the payload's frame; empty: the only leaf",
        read_only=True,
    ),
]


def declare_model_source(
    node: Node,
    extra: list[Spec],
    check: Callable[[dict], Any],
    per_joint: PerJoint | None = None,
    finish: Callable[[Any, Any], Any] | None = None,
    startup_wait: float | None = None,
    quick: Callable[[Any, Any], bool] | None = None,
) -> LiveParameters:
    """Declare ``model.source`` and the model's parameters of that source, and a node's own
    (``extra``, and ``per_joint`` specs made for the model's joint names); ``check``,
    ``finish``, ``startup_wait`` and ``quick`` as for LiveParameters. With the
    robot_description topic the returned parameters' ``current`` is None until a model
    arrives, and the per-joint specs are declared as models come."""
    source = declare(node, SOURCE)
    check_choice("model.source", source, SOURCES)
    if source == "parameters":
        return declare_model(node, extra, check, per_joint, finish, startup_wait, quick)
    later = dict(finish=finish, startup_wait=startup_wait, quick=quick)
    return RobotDescription(node, extra, check, per_joint or (lambda names: []), later).parameters


class RobotDescription:
    """The model of a node from a URDF: parameter, file or topic (see the module)."""

    def __init__(
        self,
        node: Node,
        extra: list[Spec],
        check: Callable[[dict], Any],
        per_joint: PerJoint,
        later: dict | None = None,
    ):
        """``later``: LiveParameters' finish, startup_wait and quick."""
        self._node, self._build_node, self._per_joint = node, check, per_joint
        text, path, base, tip = (declare(node, spec) for spec in DESCRIPTION_PARAMETERS)
        self._chain_ends = (base or None, tip or None)
        self.urdf: LoadedUrdf | None = None  # the URDF's chain of the model in use
        self.refused, self.last_refusal = 0, ""  # URDFs refused on the topic, and why the last one was
        origin = "robot_description parameter" if text else f"model.urdf_file {path}"
        if text or path:
            self.urdf = self._load(text or _read(path), origin)
        own = per_joint(self.urdf.model.joint_names) if self.urdf is not None else []
        self.parameters = LiveParameters(node, [*model_specs([], {}), *extra, *own], self._build, **(later or {}))
        if self.urdf is not None:
            self._announce(origin)
            return
        subscription = node.create_subscription(String, "robot_description", self._on_description, DESCRIPTION_QOS)
        node.get_logger().info(
            f"waiting for the model: a URDF on {subscription.topic_name} (std_msgs/String, transient local); "
            "publishing nothing until then"
        )

    def _load(self, text: str, origin: str) -> LoadedUrdf:
        """The URDF's chain, or ValueError naming where the text came from and what is wrong."""
        try:
            return load_urdf(text, *self._chain_ends)
        except ValueError as error:
            raise ValueError(f"{origin}: {error}") from None

    def _announce(self, origin: str) -> None:
        self.parameters.robot_name = self.urdf.robot_name or "robot"
        self.parameters.chain_links = (self.urdf.base_link, self.urdf.tip_link)  # frames of markers and wrenches
        names, held = list(self.urdf.model.joint_names), self.urdf.held_joints
        held = f"; held at zero: {', '.join(held)}" if held else ""
        logger = self._node.get_logger()
        logger.info(
            f"model from the {origin}: {self.urdf.base_link} -> {self.urdf.tip_link}, {len(names)} joints {names}{held}"
        )
        for warning in self.urdf.warnings:
            logger.warning(warning)
        for note in self.urdf.notes:
            logger.info(f"note: {note}")

    def _build(self, values: dict) -> Any:
        """The node's checked configuration (its draft) from the URDF's model and the
        parameter values. Until a URDF has come: None, the parameters checked on a stand-in
        one-joint arm."""
        if self.urdf is None:
            stand_in_defaults = {spec.name: spec.default for spec in self._per_joint(STAND_IN.joint_names)}
            self._build_node({**STAND_IN.to_params(), **stand_in_defaults, **values})
            return None
        return self._build_with(self.urdf, values)

    def _build_with(self, urdf: LoadedUrdf, values: dict) -> Any:
        """``gravity`` is given in the URDF's root frame: the model takes it in base_link's."""
        values = dict(values)
        with contextlib.suppress(KeyError, TypeError, ValueError):  # absent or not 3 numbers: the check names it
            values["gravity"] = urdf.in_base(values["gravity"])
        return self._build_node({**urdf.model.to_params(), **values})

    def _on_description(self, msg: String) -> None:
        """A new URDF: checked whole, then swapped in, or refused keeping the model in use."""
        logger = self._node.get_logger()
        keeping = "still waiting" if self.urdf is None else f"keeping the model of {self.urdf.model.n} joints"
        try:
            urdf = self._load(msg.data, "robot_description topic")
            self.parameters.declare(self._per_joint(urdf.model.joint_names))
            draft = self._build_with(urdf, self.parameters.values())
        except Exception as error:  # noqa: BLE001 (nothing of ours may leave a callback)
            self.refused += 1
            kind = "" if isinstance(error, ValueError) else f"{type(error).__name__}: "
            self.last_refusal = f"{kind}{one_line(error)}"
            logger.error(f"refused a robot_description ({keeping}): {self.last_refusal}")
            return
        self.urdf = urdf
        self.parameters.submit(draft)  # finished (compiled, analysed) off the executor when slow
        self._announce("robot_description topic")


def _read(path: str) -> str:
    """The file's text, bounded (``read_urdf``: a regular file, of at most MAX_URDF_CHARS)."""
    try:
        return read_urdf(path)
    except UrdfError as error:
        raise ValueError(f"model.urdf_file: {error.reason}") from None
