"""The joint angles' sine and cosine, inline: the same arithmetic in C, on floats and on arrays.

A kernel takes ``sine(theta)`` and ``cosine(theta)`` of each joint angle. Left to libm
(sin, cos, or gcc's sincos), those are n calls one after the other, each a branchy routine
the processor does not overlap with the next: on a 6-joint arm they took about half the
time of the generated C. Here the C computes all the angles of a program first (``batched``:
in pairs of GCC's vector extensions, two angles per SSE2 or NEON register, left there for
the kernel to read, with one branch for every angle beyond the range; for other compilers
one call of ``sin_cos_angles``, a loop without a branch that gcc -O2 vectorizes), and the
Python forms likewise (``hoisted``: one ``sin_cos_rows``):

- Cody-Waite range reduction: k, the integer nearest theta * 2 / pi (rounded by adding and
  subtracting 1.5 * 2^52), and r = theta - k pi / 2 with pi / 2 split in three parts of 33
  bits (each k * part exact while |k| < 2^20), so |r| <= pi / 4;
- fdlibm's minimax polynomials of sin and cos on [-pi / 4, pi / 4] (degrees 13 and 14,
  errors below 2^-58) by Estrin's scheme, the quadrant k mod 4 choosing which one and its
  sign (in C on the bits, without a branch).

For |theta| <= LIBM_BEYOND the result is within 2 ulp of the true value (an error below
2.3e-16; near a multiple of pi / 2, where the result is near 0, below 1e-24; test_sincos
measures both); beyond, and for a theta not finite, libm's sin and cos compute it. The C
(``C_SOURCE``), the Python on floats (``sine``, ``cosine``, ``scalar_sin_cos_rows``) and on
NumPy arrays (``sine_array``, ``cosine_array``, ``sin_cos_rows``; ``ARRAY_SOURCE``, their
text for a module written out)
do the same IEEE operations in the same order, without fused multiply-add: their results
are identical, bit for bit, so a kernel's native form equals its Python form.
"""

from __future__ import annotations

import math
import re

import numpy as np

LIBM_BEYOND = 4.0e5  # rad: |theta| above which libm computes (|k| < 2^18 within)

# The constants of the three forms: 2 / pi, 1.5 * 2^52, pi / 2 in three parts of 33 bits,
# and fdlibm's coefficients (k_sin.c, k_cos.c).
CONSTANTS = {
    "TWO_OVER_PI": 2.0 / math.pi,
    "ROUNDER": 6755399441055744.0,
    "PIO2_1": 1.57079632673412561417e00,
    "PIO2_2": 6.07710050630396597660e-11,
    "PIO2_3": 2.02226624871116645580e-21,
    "S1": -1.66666666666666324348e-01,
    "S2": 8.33333333332248946124e-03,
    "S3": -1.98412698298579493134e-04,
    "S4": 2.75573137070700676789e-06,
    "S5": -2.50507602534068634195e-08,
    "S6": 1.58969099521155010221e-10,
    "C1": 4.16666666666666019037e-02,
    "C2": -1.38888888888741095749e-03,
    "C3": 2.48015872894767294178e-05,
    "C4": -2.75573143513906633035e-07,
    "C5": 2.08757232129817482790e-09,
    "C6": -1.13596475577881948265e-11,
}

# One text of the arithmetic, valid Python and C: theta -> k (rounded: its low bits k mod 4),
# r, s = sin r, c = cos r. The polynomials in z = r^2 by Estrin's scheme (pairs, then z^2 and
# z^4): a dependent path of 3 products and 3 sums where Horner's has 6 of each. cos r is
# 1 - (z / 2 - z^2 C(z)), without the compensation of 1 - z / 2 that fdlibm's k_cos adds:
# three operations an angle fewer, and still within 1 ulp of the correctly rounded values
# (about 1.3 ulp of the exact ones, where the compensated form stays within 1.03).
_STEPS = """\
rounded = theta * TWO_OVER_PI + ROUNDER
k = rounded - ROUNDER
r = ((theta - k * PIO2_1) - k * PIO2_2) - k * PIO2_3
z = r * r
z2 = z * z
z4 = z2 * z2
s = r + (z * r) * (((S1 + z * S2) + z2 * (S3 + z * S4)) + z4 * (S5 + z * S6))
c = 1.0 - (0.5 * z - z2 * (((C1 + z * C2) + z2 * (C3 + z * C4)) + z4 * (C5 + z * C6)))"""


def _python(steps: str, indent: str) -> str:
    return "\n".join(indent + line for line in steps.split("\n"))


def _literal(steps: str) -> str:
    """The steps with the constants written in (a float literal is the fastest to load)."""
    return re.sub(rf"\b({'|'.join(CONSTANTS)})\b", lambda name: repr(CONSTANTS[name[1]]), steps)


_SCALAR_SOURCE = f"""
def sin_cos(theta):
    if not abs(theta) <= {LIBM_BEYOND!r}:
        return math.sin(theta), math.cos(theta)
{_python(_literal(_STEPS), "    ")}
    j = int(k)
    if j & 1:
        s, c = c, s
    return (-s if j & 2 else s), (-c if (j + 1) & 2 else c)


def sin_cos_rows(thetas):
    # the sines of a sequence of floats, then their cosines
    pairs = [sin_cos(theta) for theta in thetas]
    return [s for s, _ in pairs] + [c for _, c in pairs]


def sine(theta):
    return sin_cos(theta)[0]


def cosine(theta):
    return sin_cos(theta)[1]
"""

ARRAY_SOURCE = f'''
{chr(10).join(f"{name} = {value!r}" for name, value in CONSTANTS.items())}


def sin_cos_array(theta):
    """(sin, cos) of each entry of theta, as the C's sin_cos_angles."""
    theta = np.asarray(theta, dtype=float)
    inside = np.abs(theta) <= {LIBM_BEYOND!r}
    theta_in = np.where(inside, theta, 0.0)
{_python(_STEPS.replace("theta", "theta_in"), "    ")}
    j = k.astype(np.int64)
    odd = (j & 1).astype(bool)
    s, c = np.where(odd, c, s), np.where(odd, s, c)
    s, c = np.where(j & 2, -s, s), np.where((j + 1) & 2, -c, c)
    if not inside.all():
        s, c = np.where(inside, s, np.sin(theta)), np.where(inside, c, np.cos(theta))
    return s, c


def sin_cos_rows(thetas):
    """The sines of a sequence of arrays of one shape, then their cosines: rows."""
    return np.concatenate(sin_cos_array(np.array(thetas)))


def sine_array(theta):
    return sin_cos_array(theta)[0]


def cosine_array(theta):
    return sin_cos_array(theta)[1]
'''

_namespace: dict = {"np": np, "math": math}
exec(_SCALAR_SOURCE, _namespace)
# on floats, as the C computes them (sin_cos_rows: the sines of a sequence, then its cosines)
sine, cosine = _namespace["sine"], _namespace["cosine"]
scalar_sin_cos_rows = _namespace["sin_cos_rows"]
exec(ARRAY_SOURCE, _namespace)
# the same on arrays, entry by entry
sin_cos_rows = _namespace["sin_cos_rows"]
sine_array, cosine_array = _namespace["sine_array"], _namespace["cosine_array"]


def _c_steps(theta: str = "theta[i]", scalar: str = "double") -> str:
    named = re.sub(rf"\b({'|'.join(CONSTANTS)})\b", r"SINCOS_\1", _STEPS.replace("theta", theta))
    return "\n".join(f"        const {scalar} {line};" for line in named.split("\n"))


C_SOURCE = (
    "/* sin and cos of the joint angles, inline: Cody-Waite reduction by pi/2 and fdlibm's polynomials\n"
    f"   (the package's core/codegen/sincos.py), within 2 ulp for |theta| <= {LIBM_BEYOND:g}, libm's\n"
    "   beyond. With no call and no branch, the angles are computed side by side (two at a time\n"
    "   in SSE2's registers when gcc vectorizes the loop). Compiled without fused multiply-add\n"
    "   contraction (gcc -O2 on x86-64 has none), the results are the package's, bit for bit. */\n"
    "#include <stdint.h>\n#include <string.h>\n"
    + "".join(f"#define SINCOS_{name} ({value!r})\n" for name, value in CONSTANTS.items())
    + f"""
#if defined(__GNUC__)
#define SINCOS_INLINE static inline __attribute__((always_inline))
#else
#define SINCOS_INLINE static inline
#endif

SINCOS_INLINE void sin_cos_angles(int n, const double *theta, double *sin_theta, double *cos_theta)
{{
    for (int i = 0; i < n; ++i) {{
{_c_steps()}
        /* the quadrant k mod 4 is in the low bits of rounded: sin theta is s, c, -s, -c and
           cos theta c, -s, -c, s by quadrant, chosen and signed on the bits (exact) */
        uint64_t j, s_bits, c_bits;
        memcpy(&j, &rounded, sizeof j);
        memcpy(&s_bits, &s, sizeof s_bits);
        memcpy(&c_bits, &c, sizeof c_bits);
        const uint64_t odd = 0 - (j & 1);
        const uint64_t sin_bits = ((s_bits & ~odd) | (c_bits & odd)) ^ ((j & 2) << 62);
        const uint64_t cos_bits = ((c_bits & ~odd) | (s_bits & odd)) ^ (((j + 1) & 2) << 62);
        memcpy(&sin_theta[i], &sin_bits, sizeof sin_bits);
        memcpy(&cos_theta[i], &cos_bits, sizeof cos_bits);
    }}
    for (int i = 0; i < n; ++i) {{
        if (!(fabs(theta[i]) <= {LIBM_BEYOND!r})) {{
            sin_theta[i] = sin(theta[i]);
            cos_theta[i] = cos(theta[i]);
        }}
    }}
}}

#if defined(__GNUC__)
/* Two angles in one vector of GCC's (and Clang's) extensions, an SSE2 (NEON) register: the
   same steps on both lanes, the results left in registers where the kernels read them
   (sin_cos_angles' arrays cost a store and a load on the way to the first joint's turn). */
#define SINCOS_PAIRS 1
typedef double sincos_pair __attribute__((vector_size(16)));
typedef long long sincos_bits __attribute__((vector_size(16)));

SINCOS_INLINE void sin_cos_pair(sincos_pair theta, sincos_pair *sin_theta, sincos_pair *cos_theta)
{{
{_c_steps("theta", "sincos_pair")}
        const sincos_bits j = (sincos_bits)rounded, s_bits = (sincos_bits)s, c_bits = (sincos_bits)c;
        const sincos_bits odd = 0 - (j & 1);
        *sin_theta = (sincos_pair)(((s_bits & ~odd) | (c_bits & odd)) ^ ((j & 2) << 62));
        *cos_theta = (sincos_pair)(((c_bits & ~odd) | (s_bits & odd)) ^ (((j + 1) & 2) << 62));
}}

/* lanes of -1 where |theta| <= {LIBM_BEYOND!r} (not for a NaN), else 0 */
SINCOS_INLINE sincos_bits sin_cos_inside(sincos_pair theta)
{{
    return (theta <= {LIBM_BEYOND!r}) & (theta >= -{LIBM_BEYOND!r});
}}

/* libm's sine and cosine of a pair's angles beyond {LIBM_BEYOND:g} or not finite */
SINCOS_INLINE void sin_cos_beyond(sincos_pair theta, sincos_pair *sin_theta, sincos_pair *cos_theta)
{{
    for (int i = 0; i < 2; ++i) {{
        if (!(fabs(theta[i]) <= {LIBM_BEYOND!r})) {{
            (*sin_theta)[i] = sin(theta[i]);
            (*cos_theta)[i] = cos(theta[i]);
        }}
    }}
}}
#endif

SINCOS_INLINE double sine(double theta)
{{
    double s, c;
    sin_cos_angles(1, &theta, &s, &c);
    return s;
}}

SINCOS_INLINE double cosine(double theta)
{{
    double s, c;
    sin_cos_angles(1, &theta, &s, &c);
    return c;
}}
"""
)

_ANGLE = re.compile(r"(sine|cosine)\((.*)\)")


def _input_angles(assignments):
    """({theta: index}, [(variable, "sine" or "cosine", index)], the other assignments): the
    assignments ``var = sine(theta)`` / ``cosine(theta)`` whose theta reads only inputs (not
    a mimic joint's scaled angle), which may all be computed first."""
    assigned = {var for var, _ in assignments}
    thetas: dict[str, int] = {}
    angles, rest = [], []
    for var, expr in assignments:
        found = _ANGLE.fullmatch(expr)
        if found is None or assigned & set(re.findall(r"[A-Za-z_]\w*", found[2])):
            rest.append((var, expr))
        else:
            angles.append((var, found[1], thetas.setdefault(found[2], len(thetas))))
    return thetas, angles, rest


def batched(assignments: list[tuple[str, str]]) -> tuple[list[str], list[tuple[str, str]]]:
    """(C lines computing the joint angles' sines and cosines at once, the other assignments):
    every distinct theta of an input (padded to an even count: two per vector), first, in
    pairs of vectors (``sin_cos_pair``) where the compiler has GCC's vector extensions, else
    by one call of ``sin_cos_angles``."""
    thetas, angles, rest = _input_angles(assignments)
    if not thetas:
        return [], rest
    values = [*thetas, *(["0.0"] if len(thetas) % 2 else [])]
    n = len(values)
    pairs = range(n // 2)
    lines = ["#if defined(SINCOS_PAIRS)"]
    lines += [f"    const sincos_pair theta_{p} = {{{values[2 * p]}, {values[2 * p + 1]}}};" for p in pairs]
    lines += [f"    sincos_pair sin_{p}, cos_{p};" for p in pairs]
    lines += [f"    sin_cos_pair(theta_{p}, &sin_{p}, &cos_{p});" for p in pairs]
    inside = " & ".join(f"sin_cos_inside(theta_{p})" for p in pairs)
    lines += [f"    const sincos_bits inside = {inside};", "    if (!(inside[0] & inside[1])) {"]
    lines += [f"        sin_cos_beyond(theta_{p}, &sin_{p}, &cos_{p});" for p in pairs]
    lines += ["    }"]
    lines += [f"    const double {var} = {f[:3]}_{i // 2}[{i % 2}];" for var, f, i in angles]
    lines += ["#else", f"    const double theta[{n}] = {{{', '.join(values)}}};"]
    lines += [f"    double sin_theta[{n}], cos_theta[{n}];", f"    sin_cos_angles({n}, theta, sin_theta, cos_theta);"]
    lines += [f"    const double {var} = {f[:3]}_theta[{i}];" for var, f, i in angles]
    return [*lines, "#endif"], rest


def hoisted(assignments: list[tuple[str, str]]) -> list[tuple[str, str]]:
    """The Python forms' assignments with the angles of an input computed first by one call:
    ("s1, s2, c1, _", "sin_cos_rows((q1 + 0.5, q2))"), ``_`` for a value not used."""
    thetas, angles, rest = _input_angles(assignments)
    if not thetas:
        return rest
    names, aliases = ["_"] * (2 * len(thetas)), []
    for var, function, i in angles:
        slot = i + (len(thetas) if function == "cosine" else 0)
        if names[slot] == "_":
            names[slot] = var
        else:  # the same angle again (a mimic joint that follows at 1x): the value already named
            aliases.append((var, names[slot]))
    return [(", ".join(names), f"sin_cos_rows(({', '.join(thetas)},))"), *aliases, *rest]
