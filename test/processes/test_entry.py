"""The entry every executable starts through (irb140_dynamics.entry), as a program: signals
that come while it starts, exit statuses, one-line errors, OpenBLAS's threads. Each case a
small program of its own run as ``python -m`` (the form where CPython's exit status can be
changed by an interrupted import), the signal sent by the program to itself at a chosen
moment: no timing involved."""

import os
import subprocess
import sys
import textwrap

import pytest

from ..support.paths import ROOT


def run_program(tmp_path, body: str, env: dict | None = None) -> tuple[int, str]:
    """(exit status, output) of ``body`` run as ``python -m program`` from ``tmp_path``."""
    (tmp_path / "program.py").write_text(textwrap.dedent(body))
    environment = {**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{tmp_path}", **(env or {})}
    for name, value in list(environment.items()):
        if value is None:
            del environment[name]
    done = subprocess.run(
        [sys.executable, "-m", "program"],
        cwd=tmp_path,
        env=environment,
        capture_output=True,
        text=True,
        timeout=120,
    )
    return done.returncode, done.stdout + done.stderr


@pytest.mark.parametrize("signal_name, status", [("SIGINT", 130), ("SIGTERM", 143)])
def test_a_tool_signalled_while_starting_says_interrupted_once(tmp_path, signal_name, status):
    code, output = run_program(
        tmp_path,
        f"""
        import os, signal
        from irb140_dynamics.entry import TOOL, finish, start
        start("sometool", TOOL)
        os.kill(os.getpid(), signal.{signal_name})  # while its modules load
        os.kill(os.getpid(), signal.SIGINT)  # and again
        from irb140_dynamics.tools.cli import run

        def main():
            return run("sometool", lambda interrupts: print("worked") or 0)

        finish(main)
        """,
    )
    assert code == status, output
    assert output == "sometool: interrupted\n", output


def test_the_first_signal_decides_when_one_comes_while_the_tool_installs_its_handlers(tmp_path):
    """SIGTERM while the tool installs its handlers (SIGINT's ours already, SIGTERM's still
    the entry's, which notes it), then Ctrl-C: the status is SIGTERM's, which came first."""
    code, output = run_program(
        tmp_path,
        """
        import os, signal
        from irb140_dynamics.entry import TOOL, finish, start
        start("sometool", TOOL)
        from irb140_dynamics.tools import cli

        def install(self, original=cli.Interrupts.install):
            self._previous[signal.SIGINT] = signal.signal(signal.SIGINT, self._on_signal)
            os.kill(os.getpid(), signal.SIGTERM)  # noted by the entry
            os.kill(os.getpid(), signal.SIGINT)  # raised by ours, here
            original(self)

        cli.Interrupts.install = install

        def main():
            return cli.run("sometool", lambda interrupts: print("worked") or 0)

        finish(main)
        """,
    )
    assert (code, output) == (143, "sometool: interrupted\n")


def test_a_node_signalled_while_starting_stops_quietly_without_running(tmp_path):
    code, output = run_program(
        tmp_path,
        """
        import os, signal
        from irb140_dynamics.entry import NODE, finish, start
        start("somenode", NODE)
        os.kill(os.getpid(), signal.SIGINT)
        finish(lambda: print("main ran") or 1)
        """,
    )
    assert code == 0 and output == "", output


def test_a_node_gets_keyboard_interrupt_back_in_main(tmp_path):
    code, output = run_program(
        tmp_path,
        """
        import os, signal, time
        from irb140_dynamics.entry import NODE, finish, start
        start("somenode", NODE)

        def main():
            try:
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(5.0)
            except KeyboardInterrupt:
                print("stopped in main")
                return 0
            return 1

        finish(main)
        """,
    )
    assert code == 0 and output == "stopped in main\n", output


def test_the_recorder_takes_every_signal_noted_while_starting(tmp_path):
    code, output = run_program(
        tmp_path,
        """
        import os, signal
        from irb140_dynamics.entry import RECORDER, finish, start, take_noted_signals
        start("record", RECORDER)
        for s in (signal.SIGHUP, signal.SIGTERM, signal.SIGINT):
            os.kill(os.getpid(), s)
        finish(lambda: print(take_noted_signals(), take_noted_signals()) or 0)
        """,
    )
    assert code == 0 and output == "[1, 15, 2] []\n", output


def test_an_interrupt_through_code_run_from_a_string_keeps_the_status(tmp_path):
    """A KeyboardInterrupt that passed through exec("...") (SciPy's imports do that) and was
    handled: main()'s status, not the interpreter killing itself with SIGINT (-2)."""
    code, output = run_program(
        tmp_path,
        """
        from irb140_dynamics.entry import TOOL, finish, start
        start("sometool", TOOL)

        def main():
            try:
                exec("raise KeyboardInterrupt")
            except KeyboardInterrupt:
                print("handled")
                return 130

        finish(main)
        """,
    )
    assert code == 130 and output == "handled\n", output


@pytest.mark.parametrize("kind", ["NODE", "TOOL"])
def test_signals_are_ignored_once_main_has_returned(tmp_path, kind):
    """A late Ctrl-C or SIGTERM, as the interpreter exits: neither a traceback nor a status
    other than main()'s."""
    code, output = run_program(
        tmp_path,
        f"""
        import atexit, os, signal
        from irb140_dynamics.entry import {kind}, finish, start
        start("some", {kind})

        def late():
            os.kill(os.getpid(), signal.SIGINT)
            os.kill(os.getpid(), signal.SIGTERM)
            print("late signals ignored")

        atexit.register(late)
        finish(lambda: 0)
        """,
    )
    assert code == 0 and output == "late signals ignored\n", output


@pytest.mark.parametrize(
    "failure, line",
    [
        ("import no_such_module_here", "sometool: cannot start: No module named 'no_such_module_here'"),
        (
            "raise RuntimeError('a defect,\\n on two lines')",
            "sometool: internal error: RuntimeError: a defect, on two lines",
        ),
    ],
)
def test_an_uncaught_exception_is_one_line_and_status_1(tmp_path, failure, line):
    body = f"""
        from irb140_dynamics.entry import TOOL, finish, start
        start("sometool", TOOL)
        {failure}
        finish(lambda: 0)
        """
    code, output = run_program(tmp_path, body, {"IRB140_TRACEBACK": None})
    assert code == 1 and output == line + "\n", output
    code, output = run_program(tmp_path, body, {"IRB140_TRACEBACK": "1"})
    assert code == 1 and "Traceback (most recent call last)" in output, output


SHOW_THREADS = """
    import os, sys
    from irb140_dynamics.entry import {kind}, finish, start
    start("some", {kind})
    import numpy
    finish(lambda: print(os.environ.get("OPENBLAS_NUM_THREADS"), os.environ.get("OMP_NUM_THREADS")) or 0)
    """


@pytest.mark.parametrize(
    "kind, given, shown",
    [
        ("TOOL", {}, "1 None"),
        ("RECORDER", {}, "1 None"),
        ("TOOL", {"OPENBLAS_NUM_THREADS": "2"}, "2 None"),
        ("TOOL", {"OMP_NUM_THREADS": "3"}, "None 3"),
        ("NODE", {}, "1 None"),
        ("NODE", {"OPENBLAS_NUM_THREADS": "2"}, "2 None"),
    ],
)
def test_every_executable_runs_openblas_on_one_thread_unless_told_otherwise(tmp_path, kind, given, shown):
    unset = {"OPENBLAS_NUM_THREADS": None, "OMP_NUM_THREADS": None}
    code, output = run_program(tmp_path, SHOW_THREADS.format(kind=kind), {**unset, **given})
    assert code == 0 and output == shown + "\n", output
