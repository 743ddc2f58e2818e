"""Where a node's model comes from: its parameters, or a URDF (robot_description); the model
itself is read by ``core.io.arm_source.read_arm``, as every tool reads it.

``model.source`` (read-only):

- ``parameters`` (default): the model's parameters (``joint_names``, ``<joint>.*``; see
  ``declare_model_source``), as in config/irb140.yaml.
- ``robot_description``: the chain from ``model.base_link`` to ``model.tip_link`` of a URDF
  (see ``core.urdf``), taken from the string parameter ``robot_description`` when it is set,
  else from the file ``model.urdf_file`` when that is set, else from the topic
  ``robot_description`` (std_msgs/String, reliable, transient local: as
  robot_state_publisher publishes it). From the topic, the node waits (publishing
  nothing) until a valid model arrives; each later URDF is read off the executor (a text
  over the size limit refused before that), checked whole with the current parameters,
  and then swapped in at once, or refused (logged) keeping the model in use: the model
  before answers every message meanwhile.
  The per-joint parameters are not declared in this mode: the URDF gives the joints, their
  names, inertials, limits and friction; ``gravity`` (here in the URDF's root frame, turned
  into base_link's), ``friction.smoothing_velocity``, ``payload.*`` (on the tip link) and
  the node's own parameters work as with parameters. The loader's warnings (inertials
  taken as given) are logged as warnings, its notes (invalid inertials off the chain) as info.
"""

from __future__ import annotations

from typing import Any

from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

from irb140_dynamics.core import Joint, RigidBody, RobotModel
from irb140_dynamics.core.errors import one_line
from irb140_dynamics.core.io.arm_source import SOURCES, read_arm
from irb140_dynamics.core.io.params_file import read_parameter_file
from irb140_dynamics.core.io.text_files import size_limit
from irb140_dynamics.core.io.urdf import MAX_URDF_CHARS, LoadedUrdf, UrdfError, load_urdf, read_urdf
from irb140_dynamics.core.model.robot_model import check_joint_names
from irb140_dynamics.package_files import default_config_path
from irb140_dynamics.ros.parameters.live import LiveParameters, Recipe
from irb140_dynamics.ros.parameters.overrides import Overrides
from irb140_dynamics.ros.parameters.spec import Spec
from irb140_dynamics.ros.parameters.specs import MODEL_NAME, check_choice, joint_names_spec, model_specs
from irb140_dynamics.ros.runtime.builder import Builder, Failed
from irb140_dynamics.ros.runtime.command_line import params_files_given

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


def declare_model_source(node: Node, recipe: Recipe) -> LiveParameters:
    """Declare ``model.source``, the model's parameters of that source and the node's own
    (``recipe``); the parameters, their first configuration built. With the
    robot_description topic ``current`` stays None until a model arrives, and the per-joint
    parameters are declared as models come."""
    overrides = Overrides(node)
    source = overrides.declare(SOURCE)
    check_choice("model.source", source, SOURCES)
    if source == "robot_description":
        return RobotDescription(node, overrides, recipe).parameters
    path = default_config_path()
    if not path.is_file():
        raise ValueError(f"default model: no {path}; is the package installed? (or give --params-file)")
    defaults = read_parameter_file(path)
    given = params_files_given()
    if given:
        node.get_logger().info(f"model: params file {', '.join(given)} (over the built-in IRB-140 model, {path})")
    else:
        node.get_logger().info(f"model: the built-in IRB-140 model ({path})")
    names = check_joint_names(
        overrides.declare(joint_names_spec(defaults["joint_names"]))
    )  # they become parameter prefixes: check them first
    robot_name = overrides.declare(MODEL_NAME)
    specs = [*model_specs(names, defaults), *recipe.specs, *recipe.per_joint(names)]

    def check(values: dict) -> Any:  # the model as read_arm reads it, then the node's own rules
        return recipe.check({**values, **read_arm(values, defaults).model.to_params()})

    parameters = LiveParameters(node, overrides, specs, check, recipe)
    parameters.robot_name = robot_name
    return parameters


class RobotDescription:
    """The model of a node from a URDF: parameter, file or topic (see the module)."""

    def __init__(self, node: Node, overrides: Overrides, recipe: Recipe):
        self._node, self._recipe = node, recipe
        text, path, base, tip = (overrides.declare(spec) for spec in DESCRIPTION_PARAMETERS)
        self._chain_ends = (base or None, tip or None)
        self.urdf: LoadedUrdf | None = None  # the URDF's chain of the model in use
        self.refused, self.last_refusal = 0, ""  # URDFs refused on the topic, and why the last one was
        origin = "robot_description parameter" if text else f"model.urdf_file {path}"
        if text or path:
            self.urdf = self._load(text or _read(path), origin)
        own = recipe.per_joint(self.urdf.model.joint_names) if self.urdf is not None else []
        self.parameters = LiveParameters(
            node, overrides, [*model_specs([], {}), *recipe.specs, *own], self._build, recipe
        )
        if self.urdf is not None:
            self._announce(origin)
            return
        self._reader = Builder(node, self._read_topic, self._use, f"{node.get_name()} robot_description")
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
            stand_in_defaults = {spec.name: spec.default for spec in self._recipe.per_joint(STAND_IN.joint_names)}
            self._recipe.check({**STAND_IN.to_params(), **stand_in_defaults, **values})
            return None
        return self._build_with(self.urdf, values)

    def _build_with(self, urdf: LoadedUrdf, values: dict) -> Any:
        """The URDF chain's model as ``read_arm`` reads it (``gravity`` given in the URDF's root
        frame, taken in base_link's), then the node's own rules."""
        return self._recipe.check({**values, **read_arm(values, urdf=urdf).model.to_params()})

    def _on_description(self, msg: String) -> None:
        """A new URDF: read off the executor (``_read_topic``), then ``_use``d; a text over
        the size limit is refused at once, unread."""
        limit = size_limit(MAX_URDF_CHARS)
        if len(msg.data) > limit:
            too_long = UrdfError("document", f"{len(msg.data)} characters, more than the limit of {limit} (max_chars)")
            self._refuse(ValueError(f"robot_description topic: {too_long}"))
            return
        self._reader.submit(0, msg.data)

    def _read_topic(self, text: str, previous) -> LoadedUrdf:
        """In the reader's worker thread: the URDF's chain (the slow part: parsing)."""
        return self._load(text, "robot_description topic")

    def _use(self, generation: int, urdf: LoadedUrdf | Failed) -> None:
        """On the executor thread: the URDF read, checked whole with the current parameters,
        then swapped in (finished off the executor when slow), or refused keeping the model
        in use."""
        try:
            if isinstance(urdf, Failed):
                raise urdf.error
            self.parameters.declare(self._recipe.per_joint(urdf.model.joint_names))
            draft = self._build_with(urdf, self.parameters.values())
        except Exception as error:  # noqa: BLE001 (nothing of ours may leave a callback)
            self._refuse(error)
            return
        self.urdf = urdf
        self.parameters.submit(draft)  # finished (compiled, analysed) off the executor when slow
        self._announce("robot_description topic")

    def _refuse(self, error: BaseException) -> None:
        self.refused += 1
        kind = "" if isinstance(error, ValueError) else f"{type(error).__name__}: "
        self.last_refusal = f"{kind}{one_line(error)}"
        keeping = "still waiting" if self.urdf is None else f"keeping the model of {self.urdf.model.n} joints"
        self._node.get_logger().error(f"refused a robot_description ({keeping}): {self.last_refusal}")


def _read(path: str) -> str:
    """The file's text, bounded (``read_urdf``: a regular file, of at most MAX_URDF_CHARS)."""
    try:
        return read_urdf(path)
    except UrdfError as error:
        raise ValueError(f"model.urdf_file: {error.reason}") from None
