"""A handmade tree for the tests (no Pinocchio needed to read it): a torso turning, two
2-joint arms on it (one on a fixed bracket), a gripper whose fingers are mimic joints (one
before its joint in the file, one prismatic with an offset), and friction on a mimic joint;
``_link`` and ``_joint`` write such URDF elements."""

LIMIT = '<limit lower="-2" upper="2" effort="10" velocity="1"/>'
INERTIA = '<inertial><origin xyz="{x} 0.02 0.01"/><mass value="{m}"/><inertia ixx="0.02" iyy="0.03" izz="0.025" ixy="0.001" ixz="0" iyz="0"/></inertial>'


def _link(name: str, m: float = 1.0, x: float = 0.1) -> str:
    return f'<link name="{name}">{INERTIA.format(m=m, x=x)}</link>'


def _joint(name, parent, child, kind="revolute", xyz="0 0 0.2", axis="0 1 0", extra="") -> str:
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="0.1 0 0.3"/><axis xyz="{axis}"/>{LIMIT}{extra}</joint>'
    )


TWO_ARMS = f"""<robot name="two_arms">
  <link name="base"/>{_link("torso", 5.0)}
  {_joint("torso", "base", "torso", axis="0 0 1")}
  <link name="bracket"/>
  <joint name="bracket" type="fixed"><parent link="torso"/><child link="bracket"/><origin xyz="0 0.3 0.5" rpy="1.2 0 0"/></joint>
  {_joint("l1", "bracket", "la1", xyz="0 0.1 0")}{_link("la1", 2.0)}
  {_joint("l2", "la1", "la2", axis="1 0 0")}{_link("la2", 1.5)}
  {_joint("r1", "torso", "ra1", xyz="0 -0.3 0.5", axis="1 0 0")}{_link("ra1", 2.0)}
  {
    _joint(
        "finger_b",
        "ra1",
        "fb",
        kind="prismatic",
        axis="0 0 1",
        extra='<mimic joint="r2" multiplier="-0.5" offset="0.01"/><dynamics damping="0.3"/>',
    )
}{_link("fb", 0.2)}
  {_joint("r2", "ra1", "ra2")}{_link("ra2", 1.5)}
  {_joint("finger_a", "ra2", "fa", extra='<mimic joint="r2" multiplier="2.0" offset="0.2"/>')}{_link("fa", 0.3)}
</robot>"""
