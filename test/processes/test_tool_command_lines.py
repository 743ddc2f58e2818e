"""Every tool is reachable in one line without the ros2 CLI and answers --help / -h with
its usage (exit 0, no traceback): console scripts `irb140-<name>` beside the plain names
`ros2 run` uses, and `python -m irb140_dynamics.tools.<name>`."""

import re
import sys

import pytest

from ..support.node_process import run_to_exit
from ..support.paths import ROOT

TOOLS = {"identify": "identify", "record": "record", "excitation": "excitation", "export_urdf": "export-urdf"}


def entry_points() -> dict[str, str]:
    text = (ROOT / "setup.py").read_text()
    return dict(re.findall(r'"([\w-]+) = ([\w.]+:main)"', text))


def test_every_tool_has_both_console_scripts_and_runs_as_a_module():
    scripts = entry_points()
    for module, name in TOOLS.items():
        target = f"irb140_dynamics.tools.{module}:main"
        assert scripts.get(module) == target and scripts.get(f"irb140-{name}") == target, scripts
        source = (ROOT / "irb140_dynamics" / "tools" / f"{module}.py").read_text()
        assert 'if __name__ == "__main__":\n    sys.exit(main())' in source


@pytest.mark.parametrize("module", sorted(TOOLS))
@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_help_prints_usage_and_exits_0(module, flag):
    code, output = run_to_exit([sys.executable, "-m", f"irb140_dynamics.tools.{module}", flag])
    assert code == 0 and output.startswith(f"usage: {module}") and "Traceback" not in output, output
