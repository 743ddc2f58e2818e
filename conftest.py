# Makes the source tree importable for the tests (pytest puts this folder on sys.path).

# OpenBLAS on one thread, as the tools run it (irb140_dynamics/entry.py): its threads
# spin while they wait, and on a shared 2-core machine the identification tests took ten
# times longer with them. Set before anything imports NumPy; an explicit setting wins.
import os
import random
import tempfile

if not {"OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"} & set(os.environ):
    os.environ["OPENBLAS_NUM_THREADS"] = "1"

# The run's first DDS domain, drawn here, where pytest-xdist's controller draws it too (it
# reads no test/ conftest): its workers inherit it and take one domain each from it
# (test/conftest.py), so no two workers of a run share one.
os.environ.setdefault("IRB140_TEST_DOMAIN", str(random.SystemRandom().randint(1, 93)))

# The run's cache of native kernels, made here too and inherited by the workers: one folder
# for the whole run (the cache takes concurrent processes: a library is written whole by an
# atomic rename), so a kernel that both workers need is compiled once. Removed at the end.
if "IRB140_TEST_CACHE" not in os.environ:
    _RUN_CACHE = tempfile.TemporaryDirectory(prefix="irb140_kernels_")
    os.environ["IRB140_TEST_CACHE"] = _RUN_CACHE.name
