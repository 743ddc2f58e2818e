"""A node's configuration kept in step with its parameters: checked whole, built off the executor.

The node states how its parameters become the configuration it runs on in a ``Recipe``;
``LiveParameters`` declares them (each with its descriptor, see ``spec``), builds the first
configuration (a failure stops startup), then, as rclpy's examples do, reacts to changes
in its ``on_set_parameters`` callback: the whole configuration is checked before a change
is accepted (off the executor, see ``checked_sets``; a refused change keeps the old one,
its reason naming the parameter), then finished off the executor and swapped in at once.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter

from irb140_dynamics.core.errors import one_line
from irb140_dynamics.ros.parameters.checked_sets import CheckedSets
from irb140_dynamics.ros.parameters.overrides import Overrides
from irb140_dynamics.ros.parameters.services import ParameterServices, undeclared
from irb140_dynamics.ros.parameters.spec import Spec, as_type
from irb140_dynamics.ros.runtime.builder import Builder, Failed


def no_joint_parameters(joint_names) -> list[Spec]:
    return []


@dataclass(frozen=True)
class Recipe:
    """How a node's parameters become the configuration it runs on.

    ``check(values)`` validates all the parameter values at once (what no descriptor can
    say: the model as a whole, rules across parameters) and returns a draft, or raises
    ValueError naming the parameter. It runs before a change is accepted: in a worker
    thread for a change through the parameter services (``checked_sets``), within the call
    for one set in the process (``node.set_parameters``); it must be thread-safe.
    ``finish(draft, previous)`` does the slow part (compiling kernels, the workspace
    analysis; None: the draft is the configuration) off the executor; ``previous`` is the
    last configuration finished (None at first). ``quick(draft, previous)``: True when
    finish will be quick (nothing to compile): then it runs at once, and the change is in
    force when the call returns. ``per_joint(joint_names)``: the node's parameters of each
    joint. ``startup_wait`` (s): the first finish runs in the worker too and the node comes
    up after at most that long, its configuration following when ready; None: the node
    comes up with it.
    """

    specs: Sequence[Spec]
    check: Callable[[dict], Any]
    per_joint: Callable[[list[str]], list[Spec]] = no_joint_parameters
    finish: Callable[[Any, Any], Any] | None = None
    quick: Callable[[Any, Any], bool] | None = None
    startup_wait: float | None = None


class LiveParameters:
    """The node's validated configuration (``current``), kept in step with its parameters.

    ``current`` is None until the first configuration is finished (or while a URDF is
    awaited: a draft None finishes as None). ``pending_since`` (time.monotonic()) tells that
    an accepted change is not yet in force; ``failure`` the error of a finish that failed
    (the configuration before stays). Listeners (``on_change``) are called on the executor
    thread with each new configuration.
    """

    def __init__(
        self, node: Node, overrides: Overrides, specs: list[Spec], check: Callable[[dict], Any], recipe: Recipe
    ):
        """Declare ``specs`` with the values ``overrides`` holds; ``check``: the recipe's,
        or one wrapping it (a URDF's model); the rest from ``recipe``."""
        self._node, self._overrides, self._check_values = node, overrides, check
        self._quick = recipe.quick if recipe.finish is not None else (lambda draft, previous: True)
        finish = recipe.finish or (lambda draft, previous: draft)
        self._declaring = False
        self.declare(specs)
        joint_names = node.get_parameter("joint_names").value if node.has_parameter("joint_names") else None
        overrides.warn_unknown(joint_names)
        self.current = None
        self.robot_name = ""  # the hardware_id of /diagnostics: model.name, or the URDF's <robot name>
        self.failure: str | None = None
        self.pending_since: float | None = time.monotonic()
        self._listeners: list[Callable[[Any], None]] = []
        self._accepted, self._applied = 1, 0  # generations: the newest accepted change, the one in force
        self._checked = None  # (the changes, draft) accepted by _check, not yet applied
        self._builder = Builder(node, _or_none(finish), self._deliver, f"{node.get_name()} parameters")
        self._starting = True  # a failure is raised, not logged
        draft = check(self.values())
        if recipe.startup_wait is None:
            self._builder.build_here(1, draft)
        else:
            self._builder.submit(1, draft)
            self._builder.wait(recipe.startup_wait, node.context.ok)
        self._starting = False
        if self.failure is not None:
            raise ValueError(self.failure)
        node.add_pre_set_parameters_callback(self._as_declared_types)
        node.add_on_set_parameters_callback(self._check)
        node.add_post_set_parameters_callback(self._apply)
        self._taken = None  # (snapshot, Future): a check done off the executor (CheckedSets), for _check
        checked_sets = CheckedSets(node, self._snapshot, lambda snapshot: check(snapshot[1]), self._take)
        ParameterServices(node, checked_sets.submit)

    def values(self, changes=()) -> dict[str, Any]:
        """All parameter values by name, with ``changes`` (Parameters) applied on top."""
        values = {name: parameter.value for name, parameter in self._node.get_parameters_by_prefix("").items()}
        return values | {p.name: p.value for p in changes}

    def on_change(self, listener: Callable[[Any], None]) -> None:
        self._listeners.append(listener)

    def declare(self, specs: Sequence[Spec]) -> None:
        """Declare parameters (a new model's per-joint ones) with the values given at
        startup; those declared already stay. Declaring is not a change: nothing is checked."""
        self._declaring = True
        try:
            for spec in specs:
                if not self._node.has_parameter(spec.name):
                    self._overrides.declare(spec)
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

    def _as_declared_types(self, parameters: list[Parameter]) -> list[Parameter]:
        """`ros2 param set ... payload.mass 3` means 3.0 for a double parameter (``spec.as_type``)."""
        return [
            as_type(p, Parameter.Type(self._node.describe_parameter(p.name).type))
            if p.name and self._node.has_parameter(p.name)
            else p
            for p in parameters
        ]

    def _check(self, parameters: list[Parameter]) -> SetParametersResult:
        """Validate the whole new configuration; refuse the change if that fails."""
        self._checked = None
        if self._declaring:
            return SetParametersResult(successful=True)
        refusal = undeclared(self._node, [p.name for p in parameters])  # rclpy's own check lets '' through
        if refusal is not None:
            return refusal
        values = self.values(parameters)
        try:
            if self._taken is not None and self._taken[0] == (self._accepted, values):  # checked off the executor
                draft = self._taken[1].result()
            else:
                draft = self._check_values(values)
            self._checked = (_changes(parameters), draft)
        except ValueError as error:
            return SetParametersResult(successful=False, reason=one_line(error))
        except Exception as error:  # noqa: BLE001  (a defect of ours must not end the node)
            self._node.get_logger().error(f"validating {[p.name for p in parameters]}: {type(error).__name__}: {error}")
            return SetParametersResult(successful=False, reason=f"internal error: {type(error).__name__}: {error}")
        return SetParametersResult(successful=True)

    def _snapshot(self, changes: list[Parameter]) -> tuple[int, dict]:
        """What a check of ``changes`` starts from: the generation in force (a URDF swapped in
        meanwhile changes it) and the values."""
        return self._accepted, self.values(self._as_declared_types(changes))

    def _take(self, snapshot: tuple[int, dict] | None, future=None) -> None:
        """The check of ``snapshot`` done off the executor (a Future), for the change set next;
        None after it."""
        self._taken = None if snapshot is None else (snapshot, future)

    def _apply(self, parameters: list[Parameter]) -> None:
        """Build the configuration checked by _check for exactly these changes: at once if
        that is quick, else off the executor. (rclpy calls it for declarations too: those
        were not checked, and change nothing.)"""
        checked, self._checked = self._checked, None
        if checked is None or checked[0] != _changes(parameters):  # not the change just checked
            return
        self._accept(checked[1])

    def _accept(self, draft) -> None:
        self._accepted += 1
        if self.pending_since is None:
            self.pending_since = time.monotonic()
        try:
            quick = draft is None or self._quick(draft, self._builder.previous)
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


def declare_fixed(node: Node, specs: Sequence[Spec]) -> list[Any]:
    """Declare a node's parameters that are only read at startup (read-only ones) with the
    values given, and serve the parameter services; their values, in order."""
    overrides = Overrides(node)
    values = [overrides.declare(spec) for spec in specs]
    overrides.warn_unknown(None)
    ParameterServices(node)
    return values


def _changes(parameters: list[Parameter]) -> list[tuple[str, Any]]:
    return [(p.name, p.value) for p in parameters]


def _error_text(error: BaseException) -> str:
    """A ValueError's text (it names the parameter); for anything else, its type too."""
    return one_line(error) if isinstance(error, ValueError) else f"{type(error).__name__}: {one_line(error)}"


def _or_none(finish: Callable[[Any, Any], Any]) -> Callable[[Any, Any], Any]:
    """finish, for a draft None (nothing to run on yet) None."""
    return lambda draft, previous: None if draft is None else finish(draft, previous)
