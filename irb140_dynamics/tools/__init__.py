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
