"""What is derived from a model once and kept while the model lives, apart from it.

Models are immutable, so what is computed from one never goes stale. It is kept here, by
the model's identity (an equal model is another model, with its own), and dropped when the
model goes, so an id is never another model's: the model itself holds nothing of it.
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Callable
from typing import Generic, TypeVar

Derived = TypeVar("Derived")


class PerModel(Generic[Derived]):
    """``get(model)``: ``make(model)``, made on the first call for that model and kept while
    it lives (one per model, also when threads ask at once)."""

    def __init__(self, make: Callable[[object], Derived]):
        self._make = make
        self.kept: dict[int, Derived] = {}  # id(model) -> what was made of it; read directly on hot paths
        self._lock = threading.Lock()

    def get(self, model) -> Derived:
        found = self.kept.get(id(model))
        return found if found is not None else self._made(model)

    def _made(self, model) -> Derived:
        with self._lock:
            found = self.kept.get(id(model))
            if found is None:
                found = self.kept[id(model)] = self._make(model)
                weakref.finalize(model, self.kept.pop, id(model), None)
            return found
