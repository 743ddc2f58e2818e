"""The model's parameters as ``--help`` lists them (every node that reads a model shows these)."""

from __future__ import annotations

from dataclasses import replace

from irb140_dynamics.core.io.params_file import read_parameter_file
from irb140_dynamics.package_files import default_config_path
from irb140_dynamics.ros.parameters.spec import Spec
from irb140_dynamics.ros.parameters.specs import (
    DESCRIPTION_PARAMETERS,
    MODEL_NAME,
    SOURCE,
    joint_names_spec,
    model_specs,
)

JOINT = "NAME"  # stands for each joint of joint_names in the per-joint parameters


def model_sections() -> list[tuple[str, list[Spec]]]:
    """(title, Specs) of the model's parameters: source, whole arm, per joint, URDF source;
    the defaults are the built-in model's (config/irb140.yaml)."""
    try:
        defaults = read_parameter_file(default_config_path())
    except (OSError, ValueError):  # help without the file: the types, no defaults
        defaults = {}
    specs = model_specs([JOINT], {})
    per_joint = [spec for spec in specs if spec.name.startswith(f"{JOINT}.")]
    whole = [replace(spec, default=defaults.get(spec.name, spec.default)) for spec in specs if spec not in per_joint]
    names = list(defaults.get("joint_names", [])) or [JOINT]
    return [
        (
            "The model (defaults: the built-in IRB-140 model, config/irb140.yaml)",
            [SOURCE, MODEL_NAME, joint_names_spec(names), *whole],
        ),
        (f"Per joint, {JOINT} = each of joint_names (the built-in model gives every one for its joints)", per_joint),
        ("The model from a URDF (model.source: robot_description)", list(DESCRIPTION_PARAMETERS)),
    ]


def per_joint_section(specs: list[Spec], what: str) -> tuple[str, list[Spec]]:
    return (f"{what}, per joint ({JOINT} = each of joint_names)", specs)
