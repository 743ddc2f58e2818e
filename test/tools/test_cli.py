"""The tools' common runner (tools.cli.run): how a tool ends on what stops it."""

import signal

from irb140_dynamics.tools.cli import ToolError, run


def test_a_closed_standard_output_ends_the_tool_quietly_as_sigpipe_would(capsys):
    """`tool ... | head`: once the reader has gone, a write raises BrokenPipeError; the tool
    ends with no line (not 'error: Broken pipe') and 141, as a program SIGPIPE ends."""

    def body(interrupts):
        raise BrokenPipeError(32, "Broken pipe")

    assert run("sometool", body) == 128 + signal.SIGPIPE
    out, err = capsys.readouterr()
    assert out == "" and err == ""


def test_other_errors_are_one_line_and_status_1(capsys):
    def body(interrupts):
        raise ToolError("the file is bad")

    assert run("sometool", body) == 1
    assert capsys.readouterr().err.strip() == "sometool: error: the file is bad"
