"""WrenchStamped <-> arrays: any six floats and any frame either read as a finite wrench within
the bounds in the frame it names, or refused (BadMessage) with a kind; filled messages read back."""

import math

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import WrenchStamped
from hypothesis import given, settings
from hypothesis import strategies as st

from irb140_dynamics.core.model.joint_order import BadMessage
from irb140_dynamics.ros.messages.wrench import MAX_FORCE, MAX_TORQUE, chain_links, fill_wrench, read_wrench

LINKS = ("base_link", "flange")
numbers = st.floats(allow_nan=True, allow_infinity=True, width=64)


@settings(max_examples=300, deadline=None)
@given(st.lists(numbers, min_size=6, max_size=6), st.sampled_from(["flange", "base_link", "", "tool0", "x" * 300]))
def test_any_wrench_is_read_finite_and_bounded_or_refused(values, frame_id):
    msg = fill_wrench(WrenchStamped(), Time(sec=1, nanosec=2), frame_id, values[:3], values[3:])
    try:
        wrench, frame = read_wrench(msg, LINKS)
    except BadMessage as error:
        assert error.kind in ("unknown_frame", "not_finite", "absurd_wrench") and len(str(error)) < 300
        return
    assert frame == {"flange": "tip", "base_link": "base"}[frame_id]
    assert np.isfinite(wrench).all() and wrench.tolist() == [float(x) for x in values]
    assert math.hypot(*wrench[:3]) <= MAX_FORCE and math.hypot(*wrench[3:]) <= MAX_TORQUE


def test_the_links_of_a_model_of_parameters_are_export_urdf_s():
    class Parameters:
        pass

    assert chain_links(Parameters()) == ("base_link", "flange")
    urdf = Parameters()
    urdf.chain_links = ("world", "tool0")
    assert chain_links(urdf) == ("world", "tool0")
