"""id_node's wrist force/torque sensor (core.ft_sensor): ft_wrench in, ft_contact_wrench out, ~/estimate_ft_load."""

from __future__ import annotations

from geometry_msgs.msg import WrenchStamped
from rclpy.parameter import Parameter
from std_srvs.srv import Trigger

from irb140_dynamics.core.ft_sensor.stream import FtSensorStream, sensor_refusal
from irb140_dynamics.core.io.stamps import seconds
from irb140_dynamics.core.model.joint_order import BadMessage
from irb140_dynamics.core.payload.mass_com_estimation import EstimationError
from irb140_dynamics.ros.messages.wrench import fill_wrench
from irb140_dynamics.ros.parameters.specs import joint_states_qos
from irb140_dynamics.ros.runtime.guard import guarded


class FtSensor:
    def __init__(self, node, depth: int):
        self.node, self.tally, self.stream, self._msg = node, node.tally, FtSensorStream(), WrenchStamped()
        node.create_subscription(WrenchStamped, "ft_wrench", self._on_reading, joint_states_qos(node))
        self._pub = node.create_publisher(WrenchStamped, "ft_contact_wrench", depth)
        node.create_service(Trigger, "~/estimate_ft_load", self._on_estimate)

    def use(self, settings, started: bool) -> None:
        """The sensor on the settings' model; a link not on it: off, said (ValueError at startup)."""
        urdf = self.node.parameters.urdf
        carried, lag = None if urdf is None else urdf.carried, settings.cutoff_frequency
        refused = self.stream.use(settings.model, settings.ft_link, settings.ft_frame, carried, lag, strict=not started)
        if refused:
            self.node.get_logger().error(refused)

    def refusal(self, settings) -> str | None:
        """Why a parameter change would turn the sensor on now off (the change is refused), or None."""
        urdf = self.node.parameters.urdf
        if self.stream.model is None:
            return None
        return sensor_refusal(settings.model, settings.ft_link, None if urdf is None else urdf.carried)

    @guarded("ft_wrench")
    def _on_reading(self, msg: WrenchStamped) -> None:
        if self.stream.model is None:
            return self.tally.add("ft_wrench", "sensor_off")
        f, m, stamp = msg.wrench.force, msg.wrench.torque, msg.header.stamp
        t = seconds(stamp.sec, stamp.nanosec) or self.node._now()  # unstamped: its arrival
        try:
            w = self.stream.contact(t, [f.x, f.y, f.z, m.x, m.y, m.z], msg.header.frame_id)
        except BadMessage as error:
            return self.tally.drop("ft_wrench", error)
        frame_id = self.stream.link if self.stream.frame == "sensor" else self.node.parameters.chain_links[0]
        self._pub.publish(fill_wrench(self._msg, stamp, frame_id, w[:3], w[3:]))

    @guarded("estimate_ft_load", fallback=lambda request, response, error: Trigger.Response(message=f"error: {error}"))
    def _on_estimate(self, request, response):
        try:
            estimate = self.stream.estimate()
        except EstimationError as error:
            return Trigger.Response(success=False, message=f"cannot estimate: {error}")
        if not self.node.get_parameter("ft_sensor.apply_load").value or estimate.com is None:
            return Trigger.Response(success=True, message=f"{estimate.summary()}\napplied: the bias")
        load = [Parameter("payload.mass", value=estimate.mass), Parameter("payload.com", value=list(estimate.com))]
        applied = self.node.set_parameters_atomically(load)
        outcome = "the bias, payload.mass, payload.com" if applied.successful else f"the bias ({applied.reason})"
        return Trigger.Response(success=applied.successful, message=f"{estimate.summary()}\napplied: {outcome}")
