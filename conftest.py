# Makes the source tree importable for the tests (pytest puts this folder on sys.path).

# OpenBLAS on one thread, as the tools run it (irb140_dynamics/entry.py): its threads
# spin while they wait, and on a shared 2-core machine the identification tests took ten
# times longer with them. Set before anything imports NumPy; an explicit setting wins.
import os

if not {"OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"} & set(os.environ):
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
