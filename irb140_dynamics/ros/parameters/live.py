"""A node's configuration kept in step with its parameters: checked whole, built off the executor.

See ``LiveParameters``. Declaring a parameter (``declare``) turns rclpy's refusals of a
given value into one line naming the parameter.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from rcl_interfaces.msg import SetParametersResult
from rclpy.exceptions import (
    ParameterNotDeclaredException,
)
from rclpy.node import Node
from rclpy.parameter import Parameter

from irb140_dynamics.core.errors import one_line
from irb140_dynamics.ros.parameters.overrides import warn_unknown_overrides
from irb140_dynamics.ros.parameters.services import guard_parameter_services
from irb140_dynamics.ros.parameters.spec import declare
from irb140_dynamics.ros.runtime.builder import Builder, Failed


class LiveParameters:
    """The node's validated configuration, kept in step with its parameters.

    ``check(values)`` validates all the parameter values at once and returns a draft of
    the configuration, or raises ValueError naming the parameter; it runs within the
    parameter call (that is what "validated whole" means), so it must be quick.
    ``finish(draft, previous)`` does the slow part (compiling kernels, the workspace
    analysis) and returns the configuration to run on; ``previous`` is the last one
    finished (None at first), for what can be reused.

    At startup both run before the node is ready; with ``startup_wait`` (s), finish runs
    in the worker and the node comes up after at most that long, its configuration
    following when ready (``current`` is None until then). A change is answered once check
    has passed; finish then runs in a worker thread (see Builder) and the result replaces
    ``current`` on the executor thread, listeners called there: until then messages are
    served by the configuration before. ``pending_since`` (time.monotonic()) tells that
    an accepted change is not yet in force; ``failure`` the error of a finish that failed
    (the configuration before stays).
    """

    def __init__(
        self,
        node: Node,
        specs: list,
        check: Callable[[dict], Any],
        finish: Callable[[Any, Any], Any] | None = None,
        declared=(),
        startup_wait: float | None = None,
        quick: Callable[[Any, Any], bool] | None = None,
    ):
        """``finish`` None: ``check`` builds the whole configuration (then always quick);
        ``declared``: names of parameters the caller has declared already; ``quick(draft,
        previous)``: True when finish will be quick (nothing to compile): then it runs at
        once, and the change is in force when the call returns. A draft None (an input from
        elsewhere, a URDF, yet to come) finishes as None: nothing to run on yet."""
        self._node, self._check_values = node, check
        self._quick = (lambda draft, previous: True) if finish is None else quick
        finish = finish or (lambda draft, previous: draft)
        for spec in specs:
            declare(node, spec)
        self._values = {
            name: node.get_parameter_or(name).value for name in [spec.name for spec in specs] + list(declared)
        }  # kept in step by _apply
        warn_unknown_overrides(node)
        self.current = None
        self.robot_name = ""  # the hardware_id of /diagnostics: model.name, or the URDF's <robot name>
        self.failure: str | None = None
        self.pending_since: float | None = time.monotonic()
        self._declaring = self._starting = False
        self._listeners: list[Callable[[Any], None]] = []
        self._accepted, self._applied = 1, 0  # generations: the newest accepted change, the one in force
        self._checked = None  # (the changes, draft) accepted by _check, not yet applied
        finish = _or_none(finish)
        self._builder = Builder(node, finish, self._deliver, f"{node.get_name()} parameters")
        draft = check(self.values())
        if startup_wait is None:
            self._deliver(1, finish(draft, None))
            self._builder.previous = self.current
        else:
            self._starting = True  # a failure is raised, not logged
            self._builder.submit(1, draft)
            delivered = self._builder.wait(startup_wait, node.context.ok)
            self._starting = False
            if delivered and self.failure is not None:
                raise ValueError(self.failure)
        node.add_pre_set_parameters_callback(self._coerce_integers)
        node.add_on_set_parameters_callback(self._check)
        node.add_post_set_parameters_callback(self._apply)
        node._check_undeclared_parameters = self._refuse_undeclared  # rclpy's lets '' through, names none
        guard_parameter_services(node)

    def values(self, changes=()) -> dict[str, Any]:
        """All parameter values by name, with ``changes`` (Parameters) applied on top."""
        values = dict(self._values)
        values.update({p.name: p.value for p in changes})
        return values

    def on_change(self, listener: Callable[[Any], None]) -> None:
        self._listeners.append(listener)

    def declare(self, specs: list) -> None:
        """Declare more parameters (a new model's per-joint ones); those declared already stay.
        Declaring is not a change: the checks are not run for it."""
        self._declaring = True
        try:
            for spec in specs:
                if not self._node.has_parameter(spec.name):
                    self._values[spec.name] = declare(self._node, spec)
        finally:
            self._declaring = False

    def submit(self, draft) -> None:
        """Apply a draft checked elsewhere (from the current values and an input from outside
        the parameters, such as a new robot_description), as an accepted change."""
        self._accept(draft)

    def status(self) -> str | None:
        """None when the parameters are in force; else in words why not (yet)."""
        if self.failure is not None:
            return f"parameters accepted but not applied: {self.failure}"
        if self.pending_since is not None:
            return f"new parameters being applied (for {time.monotonic() - self.pending_since:.1f} s)"
        return None

    def _coerce_integers(self, parameters: list[Parameter]) -> list[Parameter]:
        """Let `ros2 param set ... payload.mass 3` mean 3.0 for a double parameter."""
        try:
            return self._coerced(parameters)
        except Exception:  # noqa: BLE001  (leave them as they are: the checks that follow refuse what is wrong)
            return parameters

    def _coerced(self, parameters: list[Parameter]) -> list[Parameter]:
        coerced = []
        for p in parameters:
            wanted = self._type_of(p.name)
            if wanted == Parameter.Type.DOUBLE and p.type_ == Parameter.Type.INTEGER:
                p = Parameter(p.name, Parameter.Type.DOUBLE, float(p.value))
            elif wanted == Parameter.Type.DOUBLE_ARRAY and p.type_ == Parameter.Type.INTEGER_ARRAY:
                p = Parameter(p.name, Parameter.Type.DOUBLE_ARRAY, [float(x) for x in p.value])
            coerced.append(p)
        return coerced

    def _type_of(self, name: str):
        if not name or not self._node.has_parameter(name):
            return None
        return Parameter.Type(self._node.describe_parameter(name).type)

    def _refuse_undeclared(self, parameters: list[Parameter]) -> None:
        names = [p.name for p in parameters if not p.name or not self._node.has_parameter(p.name)]
        if names:
            raise ParameterNotDeclaredException(names)

    def _check(self, parameters: list[Parameter]) -> SetParametersResult:
        """Validate the whole new configuration; refuse the change if that fails."""
        self._checked = None
        if self._declaring:
            return SetParametersResult(successful=True)
        try:
            self._refuse_undeclared([p for p in parameters if not p.name])  # others: rclpy's check, above
            self._checked = (_changes(parameters), self._check_values(self.values(parameters)))
        except (ValueError, ParameterNotDeclaredException) as error:
            return SetParametersResult(successful=False, reason=one_line(error))
        except Exception as error:  # noqa: BLE001  (a defect of ours must not end the node)
            self._node.get_logger().error(f"validating {[p.name for p in parameters]}: {type(error).__name__}: {error}")
            return SetParametersResult(successful=False, reason=f"internal error: {type(error).__name__}: {error}")
        return SetParametersResult(successful=True)

    def _apply(self, parameters: list[Parameter]) -> None:
        """Build the configuration checked by _check for exactly these changes: at once if
        that is quick, else off the executor."""
        for p in parameters:
            if p.name in self._values:
                self._values[p.name] = p.value
        checked, self._checked = self._checked, None
        if checked is None or checked[0] != _changes(parameters):  # not the change just checked
            return
        self._accept(checked[1])

    def _accept(self, draft) -> None:
        self._accepted += 1
        if self.pending_since is None:
            self.pending_since = time.monotonic()
        try:
            quick = draft is None or (self._quick is not None and self._quick(draft, self._builder.previous))
        except Exception:  # noqa: BLE001  (then the worker finds out)
            quick = False
        if quick:
            self._builder.build_here(self._accepted, draft)
        else:
            self._builder.submit(self._accepted, draft)

    def _deliver(self, generation: int, result) -> None:
        """On the executor thread: swap in a finished configuration, or note its failure."""
        if generation <= self._applied:  # a newer one is in force already
            return
        if generation == self._accepted:
            self.pending_since = None
        if isinstance(result, Failed):
            self.failure = _error_text(result.error)
            if not self._starting:
                self._node.get_logger().error(f"new parameters not applied, the previous stay in force: {self.failure}")
            return
        self._applied, self.current, self.failure = generation, result, None
        if result is None:  # nothing to run on yet (waiting for a URDF)
            return
        for listener in self._listeners:
            try:
                listener(result)
            except Exception as error:  # noqa: BLE001  (a defect of ours must not end the node)
                self._node.get_logger().error(f"applying new parameters: {type(error).__name__}: {error}")


def _changes(parameters: list[Parameter]) -> list[tuple[str, Any]]:
    return [(p.name, p.value) for p in parameters]


def _error_text(error: BaseException) -> str:
    """A ValueError's text (it names the parameter); for anything else, its type too."""
    return one_line(error) if isinstance(error, ValueError) else f"{type(error).__name__}: {one_line(error)}"


def _or_none(finish: Callable[[Any, Any], Any]) -> Callable[[Any, Any], Any]:
    """finish, for a draft None (nothing to run on yet) None."""
    return lambda draft, previous: None if draft is None else finish(draft, previous)
