"""URDFs the loader refuses, each with one line naming the element; and what it accepts."""

import pytest

from irb140_dynamics.core import ModelError, RobotModel
from irb140_dynamics.core.io.urdf import UrdfError, load_urdf

LIMIT = '<limit lower="-1" upper="1" effort="10" velocity="1"/>'
ARM = f"""<robot name="arm">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>{LIMIT}</joint>
  <link name="l1"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1"/></inertial></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>{LIMIT}</joint>
  <link name="l2"><inertial><origin xyz="0.1 0 0"/><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1"/></inertial></link>
</robot>"""
J2 = '<joint name="j2" type="revolute">'
L2 = ARM[ARM.index('<link name="l2">') : ARM.index("</robot>")]


def edited(*replacements) -> str:
    text = ARM
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new, 1)
    return text


def extra(xml: str) -> str:
    return edited(("</robot>", xml + "</robot>"))


REFUSED = {
    "xml_does_not_parse": (ARM[:-3], {}, "URDF XML: does not parse: "),
    "not_a_robot": (ARM.replace("robot", "model"), {}, "the root element is <model>"),
    "empty": ("  ", {}, "URDF document: empty"),
    "mimic_of_a_joint_off_the_model": (
        edited((LIMIT + '</joint>\n  <link name="l2"', LIMIT + '<mimic joint="j1"/></joint>\n  <link name="l2"')),
        {"base_link": "l1"},
        "URDF joint \"j2\" <mimic>: follows 'j1', which is not a moving joint of the model",
    ),
    "mimic_of_a_mimic": (
        extra(
            f'<joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>{LIMIT}<mimic joint="j2"/></joint>'
            '<link name="l3"/>'
        ).replace(LIMIT + '</joint>\n  <link name="l2"', LIMIT + '<mimic joint="j3"/></joint>\n  <link name="l2"'),
        {"tip_link": "l3"},
        "follows 'j3', itself a mimic joint (a mimic of a mimic is not supported)",
    ),
    "mimic_of_a_missing_joint": (
        edited((LIMIT + '</joint>\n  <link name="l2"', LIMIT + '<mimic joint="nowhere"/></joint>\n  <link name="l2"')),
        {},
        "URDF joint \"j2\" <mimic>: follows 'nowhere', which is not a moving joint of the model",
    ),
    "floating_in_a_tree": (
        extra('<joint name="f" type="floating"><parent link="l1"/><child link="cam"/></joint><link name="cam"/>'),
        {"base_link": "base"},  # no tip_link: the whole tree
        "URDF joint \"f\": a floating joint below 'base'",
    ),
    "floating_in_chain": (edited((J2, J2.replace("revolute", "floating"))), {}, 'URDF joint "j2": a floating joint'),
    "planar_in_chain": (edited((J2, J2.replace("revolute", "planar"))), {}, 'URDF joint "j2": a planar joint'),
    "unknown_type": (edited((J2, J2.replace("revolute", "ball"))), {}, "URDF joint \"j2\": type 'ball'"),
    "negative_mass": (edited(('<mass value="1"/>', '<mass value="-1"/>')), {}, 'URDF link "l1" <inertial> <mass>'),
    "mass_missing": (edited(('<mass value="1"/>', "")), {}, 'URDF link "l1" <inertial> <mass>: missing value'),
    "unknown_base_link": (
        ARM,
        {"base_link": "world"},
        "URDF base_link: no link 'world' in the URDF (links: base, l1, l2)",
    ),
    "unknown_tip_link": (ARM, {"tip_link": "tool0"}, "URDF tip_link: no link 'tool0'"),
    "tip_not_below_base": (
        ARM,
        {"base_link": "l2", "tip_link": "l1"},
        "URDF tip_link: 'l1' is not below base_link 'l2'",
    ),
    "loop_through_every_link": (
        extra('<joint name="back" type="fixed"><parent link="l2"/><child link="base"/></joint>'),
        {},
        "URDF tree: a loop: every link is the child of a joint",
    ),
    "loop_beside_the_tree": (
        extra(
            '<link name="a"/><link name="b"/>'
            '<joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>'
            '<joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint>'
        ),
        {},
        "URDF tree: a loop through links a, b",
    ),
    "two_parents": (
        extra('<joint name="again" type="fixed"><parent link="base"/><child link="l2"/></joint>'),
        {},
        'URDF link "l2": has two parents: joints "j2" and "again"',
    ),
    "two_roots": (extra('<link name="stray"/>'), {}, "URDF tree: 2 root links (links no joint leads to): base, stray"),
    "link_defined_twice": (extra('<link name="l1"/>'), {}, 'URDF link "l1": defined twice'),
    "joint_to_unknown_link": (
        edited(('<child link="l2"/>', '<child link="l3"/>')),
        {},
        "URDF joint \"j2\" <child>: no link 'l3'",
    ),
    "revolute_without_limit": (
        edited((LIMIT + '</joint>\n  <link name="l2"', '</joint>\n  <link name="l2"')),
        {},
        'URDF joint "j2": a revolute joint needs <limit',
    ),
    "lower_above_upper": (
        edited((LIMIT, '<limit lower="1" upper="-1" effort="10" velocity="1"/>')),
        {},
        'URDF joint "j1" <limit>: lower 1.0 > upper -1.0',
    ),
    "negative_effort": (
        edited((LIMIT, '<limit lower="-1" upper="1" effort="-10" velocity="1"/>')),
        {},
        'URDF joint "j1" <limit>: effort must be >= 0',
    ),
    "effort_beyond_the_cap": (  # as the torque_limit parameter: no 1e300 to overflow the proofs
        edited((LIMIT, '<limit lower="-1" upper="1" effort="1e300" velocity="1"/>')),
        {},
        'URDF joint "j1" <limit>: effort must be <= 1e+07 (sanity cap), got 1e+300',
    ),
    "negative_damping": (
        edited((LIMIT, LIMIT + '<dynamics damping="-0.5"/>')),
        {},
        'URDF joint "j1" <dynamics>: damping must be >= 0',
    ),
    "bad_number": (
        edited(('<origin xyz="0 0 0.1"/>', '<origin xyz="0 0"/>')),
        {},
        'URDF joint "j1" <origin>: xyz="0 0": expected 3 finite numbers',
    ),
    "not_finite": (
        edited(('<origin xyz="0 0 0.1"/>', '<origin xyz="0 nan 0.1"/>')),
        {},
        'URDF joint "j1" <origin>: xyz="0 nan 0.1"',
    ),
    "zero_axis": (
        edited(('<axis xyz="0 0 1"/>', '<axis xyz="0 0 0"/>')),
        {},
        'URDF joint "j1" <axis>: xyz=[0.0, 0.0, 0.0] is not a direction',
    ),
    "no_moving_joint": (
        ARM,
        {"tip_link": "base"},
        "URDF chain: no revolute, continuous or prismatic joint from 'base' to 'base'",
    ),
}


@pytest.mark.parametrize("text, ends, message", list(REFUSED.values()), ids=list(REFUSED))
def test_refused_with_one_line_naming_the_element(text, ends, message):
    with pytest.raises(UrdfError) as refused:
        load_urdf(text, **ends)
    assert message in str(refused.value)
    assert "\n" not in str(refused.value)
    assert isinstance(refused.value, ModelError) and isinstance(refused.value, ValueError)


def test_the_base_arm_loads():
    assert load_urdf(ARM).model.joint_names == ("j1", "j2")


@pytest.mark.parametrize(
    "text",
    [
        pytest.param(
            edited(
                (
                    '<link name="l1"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1"/>'
                    "</inertial></link>",
                    '<link name="l1"/>',
                )
            ),
            id="massless_link_carrying_a_massive_one",
        ),
        pytest.param(
            extra(
                '<joint name="finger" type="prismatic"><parent link="l2"/><child link="f"/>'
                f'<axis xyz="0 1 0"/>{LIMIT}<mimic joint="j2"/></joint>'
                '<link name="f"><inertial><mass value="0.1"/><inertia ixx="0.001" iyy="0.001" izz="0.001"/>'
                "</inertial></link>"
            ),
            id="mimic_prismatic_finger_off_the_chain",
        ),
        pytest.param(
            extra(
                '<transmission name="t"><joint name="j1"><hardwareInterface>x</hardwareInterface></joint>'
                "</transmission>"
            ),
            id="transmission_joint",
        ),
        pytest.param(
            extra(
                '<joint name="float" type="floating"><parent link="base"/><child link="marker"/></joint>'
                '<link name="marker"/>'
            ),
            id="floating_joint_off_the_chain_at_the_base",
        ),
    ],
)
def test_accepted(text):
    loaded = load_urdf(text, tip_link="l2")
    assert loaded.model.joint_names == ("j1", "j2")


WARNED = {
    "inertia_not_positive_semidefinite": (
        edited(
            (
                'ixx="0.1" iyy="0.1" izz="0.1"/></inertial></link>\n  <joint',
                'ixx="-0.001" iyy="0.1" izz="0.1"/></inertial></link>\n  <joint',
            )
        ),
        'URDF link "l1" <inertial> <inertia>: not positive semi-definite',
    ),
    "inertia_breaks_triangle_inequality": (
        edited(
            (
                'ixx="0.1" iyy="0.1" izz="0.1"/></inertial></link>\n</robot>',
                'ixx="0.1" iyy="0.1" izz="0.3"/></inertial></link>\n</robot>',
            )
        ),
        'URDF link "l2" <inertial> <inertia>: principal moments',
    ),
    "no_inertial_and_nothing_carried_has_mass": (edited((L2, '<link name="l2"/>')), 'URDF joint "j2": moves no mass'),
}


@pytest.mark.parametrize("text, message", list(WARNED.values()), ids=list(WARNED))
def test_accepted_with_one_warning_naming_the_link(text, message):
    """Finite but not physical inertials on the chain (vendor files have them; Pinocchio
    computes with them), and a joint that moves nothing: taken as given, one warning."""
    loaded = load_urdf(text)
    assert loaded.model.joint_names == ("j1", "j2")
    assert len(loaded.warnings) == 1 and loaded.warnings[0].startswith(message)
    assert "\n" not in loaded.warnings[0] and len(loaded.warnings[0]) < 300
    again = RobotModel.from_params(loaded.model.to_params())  # the nodes' path: the parameter form
    assert again == loaded.model


def test_invalid_inertials_off_the_chain_are_notes():
    text = extra(
        '<joint name="cam" type="fixed"><parent link="base"/><child link="camera"/></joint>'
        '<link name="camera"><inertial><mass value="nan"/><inertia ixx="1" iyy="1" izz="5"/></inertial></link>'
        '<joint name="w" type="fixed"><parent link="base"/><child link="wheel"/></joint>'
        '<link name="wheel"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="5"/></inertial></link>'
    )
    loaded = load_urdf(text, tip_link="l2")
    assert loaded.warnings == ()
    assert [note.split(" <")[0] for note in loaded.notes] == ['URDF link "camera"', 'URDF link "wheel"']
    assert all(note.endswith("(off the chain: ignored)") for note in loaded.notes)


def test_prismatic_joints_and_any_names_load():
    text = edited((J2, J2.replace("revolute", "prismatic"))).replace('"j1"', '"arm-left.1"')
    model = load_urdf(text).model
    assert model.joint_names == ("arm-left.1", "j2")
    assert [j.kind for j in model.joints] == ["revolute", "prismatic"]
