"""The kernels' sine and cosine (codegen.sincos): within 2 ulp of the true values over the
range they compute (numbers to 120 bits by mpmath), libm's beyond it, and the same bits in
C, on floats and on NumPy arrays."""

import ctypes
import math
import subprocess

import mpmath
import numpy as np
import pytest

from irb140_dynamics.core.codegen.sincos import (
    C_SOURCE,
    LIBM_BEYOND,
    batched,
    cosine,
    cosine_array,
    sine,
    sine_array,
)

from .equations.support import CC_FLAGS, compiler

FUNCTIONS = (("s", "sine"), ("c", "cosine"))


def exact(function, x: np.ndarray) -> np.ndarray:
    with mpmath.workprec(120):
        return np.array([float(function(mpmath.mpf(float(t)))) for t in x])


def angles(seed: int, boundaries: bool = False) -> np.ndarray:
    """Angles of every size the kernels meet, signed: joint ranges, turns of a wheel, far out
    (and with ``boundaries``, multiples of pi / 2, where the result is near 0 or +-1)."""
    rng = np.random.default_rng(seed)
    parts = [rng.uniform(0.0, 7.0, 800), rng.uniform(7.0, 1e3, 400), rng.uniform(1e3, LIBM_BEYOND, 400)]
    if boundaries:
        parts.append(rng.integers(-2000, 2000, 200) * (math.pi / 2))
    x = np.concatenate(parts)
    return x * rng.choice([-1.0, 1.0], len(x))


def test_within_two_ulp_of_the_true_values():
    x = angles(1)
    for ours, function in ((sine_array, mpmath.sin), (cosine_array, mpmath.cos)):
        want = exact(function, x)
        ulps = np.abs(ours(x) - want) / np.spacing(np.abs(want))
        assert ulps.max() <= 2.0, f"{function.__name__}: {ulps.max()} ulp at {x[ulps.argmax()]!r}"


def test_near_a_multiple_of_a_right_angle_the_error_stays_tiny():
    rng = np.random.default_rng(2)
    x = rng.integers(-250_000, 250_000, 300) * (math.pi / 2) + rng.normal(0.0, 1e-9, 300)
    for ours, function in ((sine_array, mpmath.sin), (cosine_array, mpmath.cos)):
        assert np.abs(ours(x) - exact(function, x)).max() <= 1e-24


def test_beyond_the_range_and_not_finite_is_libm():
    x = np.array([LIBM_BEYOND * 1.5, -3e9, 1e300, np.inf, -np.inf, np.nan])
    with np.errstate(invalid="ignore"):
        assert sine_array(x).tobytes() == np.sin(x).tobytes()
        assert cosine_array(x).tobytes() == np.cos(x).tobytes()
    assert sine(3e9) == math.sin(3e9) and cosine(-3e9) == math.cos(-3e9)
    assert math.isnan(sine(math.nan))


def test_floats_and_arrays_give_the_same_bits():
    x = np.concatenate([angles(3, boundaries=True), [0.0, -0.0, 1e-300, -5e-324, LIBM_BEYOND, -LIBM_BEYOND, 2e6]])
    assert np.array([sine(float(t)) for t in x]).tobytes() == sine_array(x).tobytes()
    assert np.array([cosine(float(t)) for t in x]).tobytes() == cosine_array(x).tobytes()


@pytest.mark.skipif(compiler() is None, reason="no C compiler (cc or gcc) on this machine")
def test_the_c_gives_the_same_bits(tmp_path):
    """Four angles at a time, as the kernels compute them: in pairs of vectors where the
    compiler has GCC's vector extensions (SINCOS_PAIRS), and by the loop (vectorized by gcc
    -O2) that other compilers run; values beyond the range take libm's in both."""
    names = [f"t{i}" for i in range(3)]  # padded to a fourth angle, as a kernel's
    angle_lines, _ = batched(
        [(f"{f}{i}", f"{function}({t})") for i, t in enumerate(names) for f, function in FUNCTIONS]
    )
    loop = "#undef SINCOS_PAIRS\n" + "\n".join(angle_lines)
    source = "#include <math.h>\n" + C_SOURCE
    source += "void angles4(const double *t, double *s, double *c) { sin_cos_angles(4, t, s, c); }\n"
    for name, lines in (("pairs3", "\n".join(angle_lines)), ("loop3", loop)):
        source += f"void {name}(const double *t, double *s, double *c) {{\n"
        source += "".join(f"    const double {t} = t[{i}];\n" for i, t in enumerate(names))
        source += lines + "\n" + "".join(f"    s[{i}] = s{i}; c[{i}] = c{i};\n" for i in range(3)) + "}\n"
    (tmp_path / "sincos.c").write_text(source)
    library = tmp_path / "libsincos.so"
    command = [compiler(), *CC_FLAGS, "-shared", "-fPIC", str(tmp_path / "sincos.c"), "-o", str(library), "-lm"]
    subprocess.run(command, check=True, capture_output=True, timeout=60)
    x = np.concatenate([angles(4, boundaries=True), [0.0, -0.0, LIBM_BEYOND, 2e6, np.inf, np.nan, -np.inf, -2e6]])
    for name, size in (("angles4", 4), ("pairs3", 3), ("loop3", 3)):
        function = getattr(ctypes.CDLL(str(library)), name)
        t = np.concatenate([x, np.zeros(-len(x) % size)])
        s, c = np.empty_like(t), np.empty_like(t)
        pointer = ctypes.POINTER(ctypes.c_double)
        for i in range(0, len(t), size):
            function(*(a[i:].ctypes.data_as(pointer) for a in (t, s, c)))
        with np.errstate(invalid="ignore"):
            assert s.tobytes() == sine_array(t).tobytes(), name
            assert c.tobytes() == cosine_array(t).tobytes(), name
