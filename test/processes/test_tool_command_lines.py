"""The tools as processes, smoke tests of what test/tools/test_programs.py checks in-process
for every tool: ``python -m irb140_dynamics.tools.<name>`` and a console script's function
(irb140_dynamics.programs) answer --help with the usage, exit 0, no traceback."""

import sys

from ..support.node_process import run_to_exit


def test_python_m_answers_help():
    code, output = run_to_exit([sys.executable, "-m", "irb140_dynamics.tools.identify", "--help"])
    assert code == 0 and output.startswith("usage: identify") and "Traceback" not in output, output


def test_a_console_script_answers_help():
    script = "from irb140_dynamics.programs import record; record()"
    code, output = run_to_exit([sys.executable, "-c", script, "-h"])
    assert code == 0 and output.startswith("usage: record") and "Traceback" not in output, output
