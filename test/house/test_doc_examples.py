"""The C++ loop docs/equations.md shows is the file its walkthrough compiles and runs."""

import re

from ..support.paths import ROOT


def test_the_shown_controller_loop_is_the_compiled_one():
    doc = (ROOT / "docs" / "equations.md").read_text()
    shown = re.search(r"```cpp\n(// A computed-torque feed-forward.*?)```", doc, re.S)
    assert shown is not None
    assert shown.group(1) == (ROOT / "docs" / "examples" / "controller_loop.cpp").read_text()
