"""The catalog of the nodes' parameter names (core.io.parameter_names) is what the nodes
declare: the warning (nodes) and refusal (tools) of unknown parameters knows every sibling's
parameter."""

from irb140_dynamics.core.io.parameter_names import NODE_PARAMETER_NAMES, PER_JOINT_SUFFIXES, sibling_parameter_names
from irb140_dynamics.nodes.demo_node import node as demo_node
from irb140_dynamics.nodes.id_node import settings as id_node
from irb140_dynamics.nodes.payload_check_node import node as payload_check_node
from irb140_dynamics.nodes.sim_node import settings as sim_node
from irb140_dynamics.nodes.trajectory_check_node import node as trajectory_check_node

NODE_MODULES = (id_node, payload_check_node, sim_node, demo_node, trajectory_check_node)


def declared_names() -> tuple[set[str], set[str]]:
    names, suffixes = set(), set()
    for module in NODE_MODULES:
        names |= {spec.name for spec in getattr(module, "NODE_PARAMETERS", [])}
        names |= set(getattr(module, "PARAMETER_NAMES", ()))
        per_joint = getattr(module, "PER_JOINT_PARAMETERS", None)
        if per_joint is not None:
            suffixes |= {spec.name[1:] for spec in per_joint(["_"])}
    return names, suffixes


def test_the_catalog_lists_every_parameter_the_nodes_declare():
    names, suffixes = declared_names()
    assert set(NODE_PARAMETER_NAMES) == names
    assert set(PER_JOINT_SUFFIXES) == suffixes


def test_per_joint_names_for_given_joints():
    known = sibling_parameter_names(["shoulder"])
    assert {f"shoulder{suffix}" for suffix in PER_JOINT_SUFFIXES} <= known
