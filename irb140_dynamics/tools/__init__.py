"""Command-line tools (``ros2 run irb140_dynamics <tool>``): thin wrappers of ``identification``
and ``core``: parse, call, print. May import every floor below (``ros`` only where ROS I/O is
the point: ``record``); never ``nodes``.

Their linear algebra is on small matrices (a few hundred columns at most), where OpenBLAS's
threads cost more than they give: they spin while they wait, and on a busy machine
identify's base parameters and fit took 5 to 20 times the CPU time of one thread. So a
tool that is the program (NumPy not loaded yet) runs OpenBLAS on one thread, unless
OPENBLAS_NUM_THREADS or OMP_NUM_THREADS says otherwise.
"""

import os
import sys

if "numpy" not in sys.modules and not {"OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"} & set(os.environ):
    os.environ["OPENBLAS_NUM_THREADS"] = "1"

# A tool started as the program (python -m irb140_dynamics.tools.<name>, a console script, ros2
# run) takes SIGINT and SIGTERM from here on, before its own module is even compiled: they are
# noted in EARLY_SIGNALS (nothing raised), and its main() acts on them (record: a stop request;
# the others: interrupted, exit 130). Imported by a test or a library, nothing is installed.
TOOL_SCRIPTS = {"identify", "record", "excitation", "export_urdf"}
EARLY_SIGNALS: list[int] = []


def _started_as_a_tool() -> bool:
    """Is one of TOOL_SCRIPTS the program: its console script, or ``python -m`` of its module?
    (Other tools of the package handle Ctrl-C their own way: for them nothing is installed.)"""
    program = os.path.basename(sys.argv[0]) if sys.argv else ""
    if program == "-m":  # runpy is importing the package on its way to the module
        original = list(getattr(sys, "orig_argv", []))
        module = original[original.index("-m") + 1] if "-m" in original[:-1] else ""
        return module in {f"{__name__}.{name}" for name in TOOL_SCRIPTS}
    return program in TOOL_SCRIPTS or program in {f"irb140-{name.replace('_', '-')}" for name in TOOL_SCRIPTS}


AS_PROGRAM = _started_as_a_tool()  # then signals are ignored once main() is done (interpreter exit)
if AS_PROGRAM:
    import signal

    for _signal in (signal.SIGINT, signal.SIGTERM):
        signal.signal(_signal, lambda signum, _frame: EARLY_SIGNALS.append(signum))
