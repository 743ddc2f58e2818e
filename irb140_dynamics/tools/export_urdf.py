"""export_urdf: the current model as URDF (the IRB-140's with the report's shapes).

    irb140-export-urdf [--out FILE] [--params-file FILE | --urdf FILE [--base LINK] [--tip LINK]]
                       [--hold JOINT=VALUE ...] [-p NAME:=VALUE ...] > arm.urdf
    (or: ros2 run irb140_dynamics export_urdf ..., python -m irb140_dynamics.tools.export_urdf ...)

The model is read as every tool and node reads it (``core.io.arm_source``): the default
config/irb140.yaml, then the params file (``model.source: robot_description`` with
``robot_description`` or ``model.urdf_file`` works too), then -p; or a URDF's chain. The
ROS form ``--ros-args --params-file FILE -p NAME:=VALUE`` is taken as well (parameters
under ``/**`` in a params file apply). No ROS needed. The URDF goes to stdout, or whole or
not at all to --out FILE.

Every joint gets a positive effort and velocity limit (RViz and MoveIt read them), each
from the first of (docs/urdf.md): the model's torque_limit / velocity_limit; for the
velocity, the IRB-140 data sheet's axis speeds; for the effort, the torque the payload
check derives for the rated payload (6 kg: its worst static torque over the joint ranges),
else, for a joint no static payload loads (axes 1 and 6), the largest torque found for the
joint's acceleration limit with the rated payload. Where none applies (a velocity limit
of another arm) the tool refuses in one line. Exit status 0; 1 with one line; 2 for a bad
argument (a parameter name no executable of the package knows, with the nearest known
one); 130 after Ctrl-C, nothing written.
"""

from __future__ import annotations

if __name__ == "__main__":  # python -m: the entry first, before the heavy imports
    from irb140_dynamics.entry import TOOL, start

    start("export_urdf", TOOL)

import math
import sys

from irb140_dynamics.tools.cli import Parser, ToolError, check_model_paths, output_file, refuse_input_as_output, run
from irb140_dynamics.tools.common import add_model_arguments, arm_of, model_inputs

NAME = "export_urdf"
ROS_MARKERS = ("--ros-args", "--")  # the ROS form's markers: its --params-file and -p are ours
# ABB IRB 140 product specification, axis speeds [deg/s], axes 1 to 6 (also config/irb140.yaml)
DATA_SHEET_SPEEDS = (200.0, 200.0, 260.0, 360.0, 360.0, 450.0)
POSES = 2000  # seeded random poses searched for a dynamic effort limit


def parser() -> Parser:
    p = Parser(
        prog=NAME,
        description=__doc__.split("\n\n")[0].split(": ", 1)[1],
        epilog="The ROS form (--ros-args --params-file F -p NAME:=VALUE) chooses the model too.",
    )
    p.add_argument("--out", metavar="FILE", help="write the URDF here (default: stdout)")
    add_model_arguments(p)
    return p


def limits(model) -> tuple[list[float], list[float], list[str]]:
    """Each joint's positive effort [N m] and velocity [rad/s] limit for the URDF, and
    where they come from (see the module's docstring); ToolError when a velocity is unknown."""
    import numpy as np

    from irb140_dynamics.core import irb140
    from irb140_dynamics.core.payload import RATED_PAYLOAD, derive_torque_limits

    is_irb140 = model.joint_names == irb140().joint_names
    velocity, effort, sources = [], [], []
    derived = None
    for k, joint in enumerate(model.joints):
        if joint.velocity_limit > 0:
            velocity.append(joint.velocity_limit)
            source = "velocity: model"
        elif is_irb140:
            velocity.append(math.radians(DATA_SHEET_SPEEDS[k]))
            source = "velocity: IRB 140 data sheet"
        else:
            raise ToolError(
                f"{joint.name}: no velocity_limit in the model and no data sheet for this arm; "
                f"give one (-p {joint.name}.velocity_limit:=RAD_S)"
            )
        if joint.torque_limit > 0:
            effort.append(joint.torque_limit)
            sources.append(source + ", effort: model")
            continue
        if not model.is_chain:  # the rated payload's torques are a chain's (core.payload)
            raise ToolError(
                f"{joint.name}: no torque_limit in the model, and on a tree or with mimic joints none is "
                f"derived; give one (-p {joint.name}.torque_limit:=N_M)"
            )
        derived = derived or derive_torque_limits(model)
        if np.isfinite(derived.values[k]) and derived.values[k] > 0:
            effort.append(float(derived.values[k]))
            sources.append(source + ", effort: derived from the rated payload (static)")
        else:
            effort.append(_dynamic_effort(model.with_payload(RATED_PAYLOAD), k))
            sources.append(source + ", effort: the rated payload at the acceleration limit (dynamic)")
    return effort, velocity, sources


def _dynamic_effort(model, k: int) -> float:
    """The largest |tau_k| found over POSES seeded random poses within the joint ranges,
    at rest, joint k at its acceleration limit (others still): gravity and inertia."""
    import numpy as np

    from irb140_dynamics.core import rnea_batch

    rng = np.random.default_rng(k)
    lower, upper = np.array([j.position_limits for j in model.joints]).T
    q = rng.uniform(lower, upper, size=(POSES, model.n))
    qdd = np.zeros_like(q)
    acceleration = model.joints[k].acceleration_limit or 10.0
    qdd[:, k] = acceleration
    tau = rnea_batch(model, q, np.zeros_like(q), qdd)
    value = float(np.abs(tau[:, k]).max())
    if not value > 0 or not math.isfinite(value):
        raise ToolError(
            f"{model.joints[k].name}: no torque_limit and none can be derived; "
            f"give one (-p {model.joints[k].name}.torque_limit:=N_M)"
        )
    return value


def mimic_limits(model):
    """The model with each mimic joint that has no torque or velocity limit of its own given
    its joint's, as it moves it: velocity |multiplier| times, torque 1/|multiplier| times."""
    if model.mimics is None:
        return model
    from dataclasses import replace

    joints, index = list(model.joints), {joint.name: k for k, joint in enumerate(model.joints)}
    for k, mimic in enumerate(model.mimics):
        if mimic is None or not mimic.multiplier:
            continue
        followed, ratio, joint = model.joints[index[mimic.joint]], abs(mimic.multiplier), joints[k]
        torque = joint.torque_limit or followed.torque_limit / ratio
        joints[k] = replace(
            joint, torque_limit=torque, velocity_limit=joint.velocity_limit or followed.velocity_limit * ratio
        )
    return replace(model, joints=tuple(joints))


def urdf_of(model) -> str:
    """The model's URDF with positive limits; the IRB-140's named irb140 and drawn with its shapes."""
    from dataclasses import replace

    from irb140_dynamics.core import irb140
    from irb140_dynamics.core.io.urdf import export_urdf
    from irb140_dynamics.core.model.irb140 import IRB140_SHAPES

    model = mimic_limits(model)
    effort, velocity, _ = limits(model)
    joints = [replace(j, torque_limit=e, velocity_limit=v) for j, e, v in zip(model.joints, effort, velocity)]
    limited = replace(model, joints=tuple(joints))
    if model.joint_names == irb140().joint_names:
        return export_urdf(limited, "irb140", IRB140_SHAPES)
    return export_urdf(limited, "robot")


def main(args: list[str] | None = None) -> int:
    args = sys.argv if args is None else list(args)
    return run(NAME, lambda interrupts: _export(args, interrupts))


def _export(args: list[str], interrupts) -> int:
    options = parser().parse_args([a for a in args[1:] if a not in ROS_MARKERS])
    check_model_paths(options)
    out = output_file(options.out) if options.out else None
    refuse_input_as_output(model_inputs(options), [(options.out, out)])

    from irb140_dynamics.tools.outputs import Outputs

    text = urdf_of(arm_of(options).model)
    if out is None:
        sys.stdout.write(text)
        sys.stdout.flush()
        return 0
    with Outputs(interrupts) as outputs:
        outputs.text(out, options.out, text)
        outputs.commit()
    print(f"wrote {options.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    from irb140_dynamics.entry import finish

    finish(main)
