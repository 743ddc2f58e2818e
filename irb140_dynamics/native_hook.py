"""Where native code for the core's kernels plugs in, so that the core starts no process.

The core (``core.codegen.kernels``) computes only: it traces a model's kernels and runs
their Python form, or the native form a compiler has put on a kernel (``kernel.native``).
To have kernels made native (``prepare``, or a kernel's PROMOTE_AFTER-th call), it asks
``compiler()`` here for the object that does it, a ``Compiler``, and never imports it: the
compile room (``irb140_dynamics.native``: the C compiler, the cache of built libraries,
the background compiles) installs itself here when imported (``install``), and the
package's ``__init__`` sets ``loader`` to import that room the first time it is asked for.
So every program that imports the core gets native kernels, and no floor imports one above
it. With no compiler installed the kernels stay in Python.

Imports nothing, so that every floor may import it (the core included).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Protocol


class Compiler(Protocol):
    """What makes kernels native: each kernel is a ``core.codegen.kernels.Kernel``, given its
    ``native`` form (and ``native_batch``, for many states) when one is made (and checked
    to give the Python form's bits)."""

    def unavailable(self) -> str | None:
        """Why no kernel can be made native here (e.g. 'IRB140_NATIVE=0', 'no C compiler'),
        or None when kernels can be."""

    def promote(self, kernel) -> None:
        """Make ``kernel`` native in the background (its Python form has been called often)."""

    def make_native(self, kernels: Sequence, timeout: float | None) -> bool:
        """Make ``kernels`` native before any other, waiting at most ``timeout`` seconds
        (None: until done): True if done (or given up) in time, else they go on in the
        background."""

    def bind_built(self, kernels: Sequence) -> bool:
        """Make native at once, without compiling or waiting, those of ``kernels`` whose
        code is built already (another model of the same arm): True if all are native now."""


_installed: Compiler | None = None
loader: Callable[[], object] | None = None  # imports the room that installs the compiler (set by the package)


def install(compiler: Compiler | None) -> None:
    """Make ``compiler`` the one the core asks (None: none, the kernels stay in Python)."""
    global _installed
    _installed = compiler


def installed() -> Compiler | None:
    """The installed compiler, None when none is yet (nothing loaded)."""
    return _installed


def compiler() -> Compiler | None:
    """The installed compiler, the compile room imported on first need (see ``loader``)."""
    if _installed is None and loader is not None:
        loader()
    return _installed
