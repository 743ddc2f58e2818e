"""What the core takes as a state, and the checks every public function makes of one.

A state (q, qd, qdd, tau, a wrench) is n finite real numbers, one per joint: a sequence of
int and float (NumPy's real scalars too) or a real NumPy array of shape (n,). Anything else
(a dict or set, a string, None, complex or bool values, the wrong length, NaN or inf) is
refused with ValueError naming the argument. Many states at once are (N, n) arrays of the
same. The common cases (a float64 array, a list or tuple of floats) take a fast path: the
check costs well under a microsecond, as it runs on every ``rnea`` call.
"""

from __future__ import annotations

import math
import reprlib

import numpy as np

_ARRAY, _FLOAT64 = np.ndarray, np.dtype(float)
_NUMBERS = frozenset({float, int})
_REAL_KINDS = "fiu"  # float, signed and unsigned integer dtypes; not bool, complex, object, str
_NOT_SEQUENCES = (str, bytes, dict, set, frozenset)


def state(x, n: int, name: str) -> list:
    """``x`` as the kernels want it, a list of n finite Python numbers, or ValueError."""
    kind = type(x)
    if kind is _ARRAY and x.dtype is _FLOAT64 and x.shape == (n,):
        x = x.tolist()
    elif not ((kind is list or kind is tuple) and len(x) == n and _NUMBERS.issuperset(map(type, x))):
        x = real_numbers(x, n, name).tolist()
    # a finite sum is all finite (nan and inf carry through a sum): one sum, not n checks
    if not math.isfinite(sum(x)) and not all(map(math.isfinite, x)):
        raise ValueError(f"{name}: must be finite, got {list(x)}")
    return x


def real_numbers(x, n: int, name: str) -> np.ndarray:
    """n real numbers (any real sequence or array, not yet checked finite) as floats, or
    ValueError naming ``name``: the other cases of ``state``."""
    if x is None or isinstance(x, _NOT_SEQUENCES) or np.ndim(x) != 1:
        raise ValueError(f"{name}: expected {n} real numbers (one per joint), got {_short(x)}")
    if isinstance(x, (list, tuple)) and any(isinstance(v, (bool, np.bool_)) for v in x):
        raise ValueError(f"{name}: expected real numbers, not booleans, got {_short(x)}")
    array = _real_array(x, name)
    if len(array) != n:
        raise ValueError(f"{name}: expected {n} values, got {len(array)}")
    return array


def states(n: int, **arrays) -> list[np.ndarray]:
    """Arrays of N states (N, n), given by name, as the kernels want them: (n, N) columns,
    finite, all of the first one's N; else ValueError naming the argument."""
    columns = []
    for name, X in arrays.items():
        if not isinstance(X, np.ndarray) and _has_bools(X):
            raise ValueError(f"{name}: expected real numbers, not booleans")
        X = _real_array(X, name)
        if X.ndim != 2 or X.shape[1] != n:
            raise ValueError(f"{name}: expected shape (N, {n}), got {X.shape}")
        if columns and X.shape[0] != columns[0].shape[1]:
            first = next(iter(arrays))
            raise ValueError(f"{name}: expected {columns[0].shape[1]} states like {first}, got {X.shape[0]}")
        if not np.isfinite(X).all():
            raise ValueError(f"{name}: must be finite (state {int(np.argmin(np.isfinite(X).all(axis=1)))} is not)")
        columns.append(np.ascontiguousarray(X.T))
    return columns


def finite_result(values, function: str, **inputs):
    """``values`` if all finite, else ValueError: the inputs (named) are too large for the model."""
    if math.isfinite(sum(values)) or all(map(math.isfinite, values)):
        return values
    raise ValueError(f"{function}: the result is not finite for {_named(inputs)}: inputs too large for the model")


def finite_results(values: np.ndarray, function: str, *names: str) -> np.ndarray:
    """Batch form of ``finite_result``: names the first state whose result is not finite."""
    finite = np.isfinite(values).reshape(len(values), -1).all(axis=1)
    if finite.all():
        return values
    raise ValueError(
        f"{function}: the result is not finite at state {int(np.argmin(finite))} "
        f"of {', '.join(names)}: inputs too large for the model"
    )


def _real_array(x, name: str) -> np.ndarray:
    try:
        array = np.asarray(x)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected real numbers, got {_short(x)}") from None
    if array.dtype.kind not in _REAL_KINDS:
        raise ValueError(f"{name}: expected real numbers, got {_short(x)}")
    return array.astype(float, copy=False)


def _has_bools(x) -> bool:
    try:
        flat = np.asarray(x, dtype=object).ravel()
    except (TypeError, ValueError):
        return False
    return any(isinstance(v, (bool, np.bool_)) for v in flat)


def _named(inputs: dict) -> str:
    return ", ".join(f"{name}={_short(value)}" for name, value in inputs.items())


def _short(x) -> str:
    return reprlib.repr(x.tolist() if isinstance(x, np.ndarray) else x)
