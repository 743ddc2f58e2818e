"""The compile room: a kernel's C compiled into a native form the core's calls use.

The core traces a model's kernels and emits their C (``core.codegen``) but starts no
process; this room runs the C compiler (``library``: the compiler as a process, the cache
of built libraries) and puts the checked native form on each kernel, in a background
thread or at once (``compiler``). It installs its ``COMPILER`` in ``native_hook`` when
imported, which the package does the first time the core asks (see
``irb140_dynamics.native_hook``): ``core.prepare`` and a kernel's warm-up then reach it.

May import: ``core`` (and ``native_hook``); nothing above the core.
"""

from irb140_dynamics import native_hook
from irb140_dynamics.native.compiler import COMPILER, enabled, unavailable
from irb140_dynamics.native.library import c_compiler, cache_dir

__all__ = ["COMPILER", "c_compiler", "cache_dir", "enabled", "unavailable"]

native_hook.install(COMPILER)
