"""A node's parameters: where its arm comes from, the arm's own and the node's, each declared
with its descriptor and the value given at startup (``overrides``).

``model.source`` (read-only): ``parameters`` (default), the model's parameters
(``joint_names``, ``<joint>.*``) over the built-in IRB-140 model (config/irb140.yaml); or
``robot_description``, the chain from ``model.base_link`` to ``model.tip_link`` of a URDF:
the parameter ``robot_description``, else the file ``model.urdf_file``, else each text on
the topic ``robot_description`` (``DESCRIPTION_QOS``, as robot_state_publisher publishes
it; the node's own per-joint parameters are declared as each URDF comes). Either way the
model is read as every tool reads it (``core.io.arm_source.read_arm``). The node checks each
change whole in its own on-set callback (``check_change``) and builds what it runs on.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from irb140_dynamics.core import Joint, RigidBody, RobotModel
from irb140_dynamics.core.errors import check_choice, one_line
from irb140_dynamics.core.io.arm_source import SOURCES, held_chain, model_summary, read_arm, read_urdf_file
from irb140_dynamics.core.io.params_file import read_parameter_file
from irb140_dynamics.core.io.urdf import LoadedUrdf
from irb140_dynamics.core.io.urdf.writer import BASE, FLANGE
from irb140_dynamics.core.model.robot_model import check_joint_names
from irb140_dynamics.package_files import default_config_path
from irb140_dynamics.ros.parameters.overrides import Overrides
from irb140_dynamics.ros.parameters.services import ParameterServices
from irb140_dynamics.ros.parameters.spec import Spec, as_type
from irb140_dynamics.ros.parameters.specs import (
    DESCRIPTION_PARAMETERS,
    MODEL_NAME,
    PAYLOAD_LINK,
    RELIABILITIES,
    SOURCE,
    drive_specs,
    joint_names_spec,
    model_specs,
)
from irb140_dynamics.ros.runtime.command_line import params_files_given

DESCRIPTION_QOS = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
STAND_IN = RobotModel((Joint("stand_in", link=RigidBody(1.0)),))  # checks the parameters before a URDF comes


class ArmParameters:
    """The parameters of ``node``: the arm's and ``specs`` (the node's own; ``per_joint``: its
    own of each joint). ``urdf``: the URDF chain in use (None: a model of parameters, or none
    yet from the topic); ``from_topic``: the URDF comes on the topic; ``robot_name``: the
    hardware_id of /diagnostics."""

    def __init__(
        self, node: Node, specs: Sequence[Spec], per_joint: Callable[[Sequence[str]], list[Spec]] | None = None
    ):
        self._node, self._per_joint = node, per_joint or (lambda joint_names: [])
        self._overrides = overrides = Overrides(node)
        self.declaring = False  # declarations are no changes: check_change lets them through
        self.urdf: LoadedUrdf | None = None
        self.from_topic = False
        self.refused, self.last_refusal = 0, ""  # URDFs refused on the topic, and why the last one was
        self.robot_name = ""
        source = overrides.declare(SOURCE)
        check_choice("model.source", source, SOURCES)
        if source == "robot_description":
            text, path, base, tip, held = (overrides.declare(spec) for spec in DESCRIPTION_PARAMETERS)
            self._chain_ends = (base or None, tip or None, held)  # held: model.held_positions
            origin = "robot_description parameter" if text else f"model.urdf_file {path}"
            if text or path:
                self.urdf = self.read(text or read_urdf_file(path, "model.urdf_file").text, origin)
            self.from_topic = self.urdf is None
            joint_names = None if self.urdf is None else self.urdf.model.joint_names
            arm = model_specs([], {})
        else:
            path = default_config_path()
            if not path.is_file():
                raise ValueError(f"default model: no {path}; is the package installed? (or give --params-file)")
            defaults, given = read_parameter_file(path), params_files_given()
            over = f"params file {', '.join(given)} (over the built-in IRB-140 model, {path})"
            node.get_logger().info(f"model: {over if given else f'the built-in IRB-140 model ({path})'}")
            joint_names = check_joint_names(overrides.declare(joint_names_spec(defaults["joint_names"])))
            self.robot_name = overrides.declare(MODEL_NAME)
            arm = model_specs(joint_names, defaults)
        # payload.link, model.held_positions on an arm of parameters: refused unless empty (read_arm)
        self.declare([*arm, PAYLOAD_LINK, *specs, *([] if joint_names is None else self._joint_specs(joint_names))])
        overrides.warn_unknown(joint_names)
        if self.urdf is not None:
            self._announce(origin)
        elif self.from_topic:
            node.get_logger().info(
                "waiting for the model: a URDF on robot_description (std_msgs/String, transient local); "
                "publishing nothing until then"
            )
        node.add_pre_set_parameters_callback(self._as_declared_types)
        ParameterServices(node)

    def declare(self, specs: Sequence[Spec]) -> None:
        """Declare the parameters not declared yet, with the values given at startup."""
        self.declaring = True
        try:
            for spec in specs:
                if not self._node.has_parameter(spec.name):
                    self._overrides.declare(spec)
        finally:
            self.declaring = False

    def _joint_specs(self, joint_names: Sequence[str]) -> list[Spec]:
        """The node's own per-joint parameters; on a URDF arm, also the drive values given at
        startup (``<joint>.torque_limit``, friction, ...), which its model takes as every tool's does."""
        given = self._overrides.given
        drives = [spec for name in joint_names for spec in drive_specs(name) if spec.name in given]
        return [*self._per_joint(joint_names), *drives]

    def values(self, changes: Sequence[Parameter] = ()) -> dict[str, Any]:
        """Every parameter value by name, ``changes`` applied on top."""
        values = {name: p.value for name, p in self._node.get_parameters_by_prefix("").items()}
        return values | {p.name: p.value for p in changes}

    def model_values(self, values: dict[str, Any], urdf: LoadedUrdf | None = None) -> dict[str, Any] | None:
        """``values`` with the model's own parameters those of the arm they give (a URDF's
        chain, ``urdf`` or else the one in use, under the values it takes); None while no
        URDF has come."""
        urdf = urdf or self.urdf
        if urdf is None and self.from_topic:
            return None
        return {**values, **read_arm(values, urdf=urdf).model.to_params()}

    def read(self, text: str, origin: str = "robot_description topic") -> LoadedUrdf:
        """The URDF's chain (thread-safe: parsing only), or ValueError naming ``origin``."""
        try:
            return held_chain(text, *self._chain_ends)
        except ValueError as error:
            raise ValueError(f"{origin}: {error}") from None

    def read_topic(self, text: str, previous=None) -> LoadedUrdf | Exception:
        """A URDF of the topic read (a Rebuild's build, in its worker thread), or the error
        that refuses it (on the executor thread, in ``take_urdf``)."""
        try:
            return self.read(text)
        except Exception as error:  # noqa: BLE001
            return error

    def take_urdf(self, urdf: LoadedUrdf | Exception, check: Callable[[dict], Any]) -> Any:
        """On the executor thread, a URDF of the topic read: the node's per-joint parameters
        of its joints declared, then everything checked (``draft``); the draft, the URDF in
        use from now on. Or None: refused (counted, logged), the model in use staying."""
        try:
            if isinstance(urdf, Exception):
                raise urdf
            self.declare(self._joint_specs(urdf.model.joint_names))
            draft = self.draft(check, self.values(), urdf)
        except Exception as error:  # noqa: BLE001 (nothing of ours may leave a callback)
            self.refused += 1
            kind = "" if isinstance(error, ValueError) else f"{type(error).__name__}: "
            self.last_refusal = f"{kind}{one_line(error)}"
            keeping = "still waiting" if self.urdf is None else f"keeping the model of {self.urdf.model.n} joints"
            self._node.get_logger().error(f"refused a robot_description ({keeping}): {self.last_refusal}")
            return None
        self.urdf = urdf
        self._announce("robot_description topic")
        return draft

    def draft(self, check: Callable[[dict], Any], values: dict[str, Any], urdf: LoadedUrdf | None = None) -> Any:
        """``check`` (a node's: its settings, not built yet, or ValueError naming the
        parameter) of the model's values; None while no URDF has come, the node's own values
        checked meanwhile on a one-joint stand-in arm. The shared qos.reliability is checked here."""
        if "qos.reliability" in values:
            check_choice("qos.reliability", values["qos.reliability"], RELIABILITIES)
        model_values = self.model_values(values, urdf)
        if model_values is not None:
            return check(model_values)
        defaults = {spec.name: spec.default for spec in self._per_joint(STAND_IN.joint_names)}
        check({**STAND_IN.to_params(), **defaults, **values})
        return None

    def check_change(self, parameters: Sequence[Parameter], check: Callable[[dict], Any]):
        """(rclpy's answer, the draft) for a change: ``draft`` of every value with the change
        applied; a ValueError refuses it, naming the parameter. Declarations pass (draft None)."""
        if self.declaring:
            return SetParametersResult(successful=True), None
        try:
            return SetParametersResult(successful=True), self.draft(check, self.values(parameters))
        except ValueError as error:
            return SetParametersResult(successful=False, reason=one_line(error)), None
        except Exception as error:  # noqa: BLE001  (a defect of ours must not end the node)
            why = f"{type(error).__name__}: {error}"
            self._node.get_logger().error(f"validating {[p.name for p in parameters]}: {why}")
            return SetParametersResult(successful=False, reason=f"internal error: {why}"), None

    def _as_declared_types(self, parameters: list[Parameter]) -> list[Parameter]:
        """`ros2 param set ... payload.mass 3` means 3.0 for a double parameter (``spec.as_type``)."""
        node = self._node
        return [
            as_type(p, Parameter.Type(node.describe_parameter(p.name).type))
            if p.name and node.has_parameter(p.name)
            else p
            for p in parameters
        ]

    @property
    def chain_links(self) -> tuple[str, str]:
        """(base link, tip link): the frames of markers and wrenches."""
        return (self.urdf.base_link, self.urdf.tip_link) if self.urdf is not None else (BASE, FLANGE)

    def _announce(self, origin: str) -> None:
        urdf, logger = self.urdf, self._node.get_logger()
        self.robot_name = urdf.robot_name or "robot"
        logger.info(f"model from the {origin}: {model_summary(urdf)}")
        for warning in urdf.warnings:
            logger.warning(warning)
        for note in urdf.notes:
            logger.info(f"note: {note}")


def declare_fixed(node: Node, specs: Sequence[Spec]) -> list[Any]:
    """Declare the parameters of a node without an arm (read-only, read at startup) with the
    values given, and serve the parameter services; their values, in order."""
    overrides = Overrides(node)
    values = [overrides.declare(spec) for spec in specs]
    overrides.warn_unknown(None)
    ParameterServices(node)
    return values
