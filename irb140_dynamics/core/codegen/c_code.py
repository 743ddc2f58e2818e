"""A Program (see ``program``) as C: the kernel function, and a CPython extension calling it.

The body is the infix text of ``python_code.statements``, the very operations of the
Python form in the same order. Compiled without contraction or fast-math (no fused
multiply-add), with the joint angles' sine and cosine inline (``sincos``, the Python form's
arithmetic) and tanh left to libm, its results are the Python form's, bit for bit (the
``native`` room checks that before use).

``kernel_source`` is ``int kernel(const double *x, const double *k, double *out)``;
``extension_source`` adds a module ``<name>`` whose ``bind(k: bytes)`` returns the kernel
with constants ``k`` as a Python function of NumPy arrays, called with METH_FASTCALL: it
takes the argument groups but ``k`` (1-D float64 arrays of their lengths, any stride) and
returns a new array, or None for anything else or a result that is not finite (the caller
then takes the Python form, which says why). A program whose outputs are ``matrices`` (see
``Program``) returns them as a tuple of new square arrays. ``bind_batch(k: bytes)`` returns
the same kernel over N states: it takes each group as (length, N) float64 columns (any
strides) and returns a new (N, outputs) array (N whole n x n matrices with ``full_matrix``),
the per-state results row by row, or None as the per-state call would for any state (the
caller then takes the Python form for them all).
"""

from __future__ import annotations

from irb140_dynamics.core.codegen import sincos
from irb140_dynamics.core.codegen.layout import whole_matrix
from irb140_dynamics.core.codegen.program import Program
from irb140_dynamics.core.codegen.python_code import statements

INPUT_NOT_FINITE, OUTPUT_NOT_FINITE = 1, 2  # what a kernel returns instead of 0
# Operations from which a kernel is compiled for size (GCC's optimize("Os")), writes each
# output as soon as it is computed (not kept to the end) and sums its outputs for the
# finiteness check in CHECK_SUMS independent sums: straight-line code that large
# runs from the instruction cache's misses, and smaller code runs faster (the derivatives
# of the dynamics); the operations and their order are the same.
COMPACT_FROM = 1500
CHECK_SUMS = 8  # partial sums of a large kernel's outputs in its finiteness check


def kernel_source(program: Program, full_matrix: int = 0) -> tuple[str, int, int]:
    """(C source, number of input doubles, number of outputs) of ``program``:
    ``int kernel(const double *x, const double *k, double *out)`` with x the inputs (the
    groups but k, in order). It returns 0, or INPUT_NOT_FINITE / OUTPUT_NOT_FINITE (then
    ``out`` is not to be used). With ``full_matrix`` n, the outputs (an upper triangle row
    by row) are written as the whole n x n matrix. The checks are on the sum of the inputs,
    then of the outputs: finite values whose sum overflows are sent to the Python form too,
    which tells them apart."""
    body, results = statements(program)
    angles, body = sincos.batched(body)
    if full_matrix:
        results = whole_matrix(results, full_matrix)
    lines = ["#include <math.h>", "", sincos.C_SOURCE]
    if len(program.ops) >= COMPACT_FROM:
        lines += ["#if defined(__GNUC__) && !defined(__clang__)", '__attribute__((optimize("Os")))', "#endif"]
    lines.append("int kernel(const double *x, const double *k, double *out) {")
    count = 0
    for group, length in program.groups:
        for i in range(length):
            if group == "k":
                lines.append(f"    const double k{i} = k[{i}];")
            else:
                lines.append(f"    const double {group}{i} = x[{count}];")
                count += 1
    lines.append("    double check = 0.0;")
    lines.append(f"    for (int i = 0; i < {count}; ++i) check += x[i];")
    lines.append(f"    if (!isfinite(check)) return {INPUT_NOT_FINITE};")
    lines += angles
    if len(program.ops) >= COMPACT_FROM:
        stores: dict[str, list[int]] = {}
        for j, expression in enumerate(results):
            stores.setdefault(expression, []).append(j)
        for var, expr in body:
            lines.append(f"    const double {var} = {expr};")
            lines += [f"    out[{j}] = {var};" for j in stores.pop(var, ())]
        lines += [f"    out[{j}] = {expression};" for expression, js in stores.items() for j in js]
    else:
        lines += [f"    const double {var} = {expr};" for var, expr in body]
        lines += [f"    out[{j}] = {expression};" for j, expression in enumerate(results)]
    if len(program.ops) >= COMPACT_FROM and len(results) >= 2 * CHECK_SUMS:
        # CHECK_SUMS partial sums, not one chain of additions each waiting for the last
        sums = ", ".join(f"check{m} = 0.0" for m in range(CHECK_SUMS))
        lines.append(f"    double {sums};")
        lines.append("    int i = 0;")
        step = "; ".join(f"check{m} += out[i + {m}]" for m in range(CHECK_SUMS))
        lines.append(f"    for (; i + {CHECK_SUMS} <= {len(results)}; i += {CHECK_SUMS}) {{ {step}; }}")
        lines.append(f"    for (; i < {len(results)}; ++i) check0 += out[i];")
        lines.append(f"    check = {' + '.join(f'check{m}' for m in range(CHECK_SUMS))};")
    else:
        lines.append("    check = 0.0;")
        lines.append(f"    for (int i = 0; i < {len(results)}; ++i) check += out[i];")
    lines.append(f"    return isfinite(check) ? 0 : {OUTPUT_NOT_FINITE};")
    return "\n".join(lines) + "\n}\n", count, len(results)


def extension_source(program: Program, module: str, full_matrix: int = 0) -> str:
    """The kernel and the CPython module ``module`` around it (see the module's doc)."""
    kernel, inputs, outputs = kernel_source(program, full_matrix)
    lengths = [length for group, length in program.groups if group != "k"]
    shape = f"{{{full_matrix}, {full_matrix}}}" if full_matrix else f"{{{outputs}}}"
    takes = []
    start = 0
    for i, length in enumerate(lengths):
        takes.append(f"!take(args[{i}], x + {start}, {length})")
        start += length
    takes = " || ".join(takes) or "0"
    if program.matrices:
        side = round((outputs // program.matrices) ** 0.5)
        results = ", ".join(f"take_matrix(out + {m * side * side})" for m in range(program.matrices))
        call = _MATRICES_CALL.format(
            inputs=max(inputs, 1),
            outputs=outputs,
            side=side,
            count=program.matrices,
            results=results,
            groups=len(lengths),
            takes=takes,
        )
    else:
        call = _ARRAY_CALL.format(
            inputs=max(inputs, 1), groups=len(lengths), takes=takes, ndim=2 if full_matrix else 1, shape=shape
        )
    if lengths:
        batch = _BATCH_CALL.format(
            inputs=max(inputs, 1),
            outputs=outputs,
            groups=len(lengths),
            rows=", ".join(map(str, lengths)),
            ndim=3 if full_matrix else 2,
            per_state=f"{full_matrix}, {full_matrix}" if full_matrix else f"{outputs}",
        )
    else:  # no states to count
        batch = _NO_BATCH
    return _EXTENSION.format(call=call, batch=batch, kernel=kernel, module=module)


# the extension's header (name, text): Python's and NumPy's API, the bulk of a compile, one
# header that a compiler may precompile once (see native.library.precompiled_header)
EXTENSION_HEADER = (
    "irb140_extension.h",
    "#define PY_SSIZE_T_CLEAN\n#include <Python.h>\n"
    "#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION\n#include <numpy/arrayobject.h>\n",
)
_EXTENSION = """#include "irb140_extension.h"

{kernel}
/* x[0:n] from a 1-D native float64 array of n entries; 0 for anything else */
static int take(PyObject *o, double *x, npy_intp n) {{
    if (!PyArray_CheckExact(o)) return 0;
    PyArrayObject *a = (PyArrayObject *)o;
    if (PyArray_TYPE(a) != NPY_DOUBLE || PyArray_NDIM(a) != 1 || PyArray_DIM(a, 0) != n
        || !PyArray_ISNOTSWAPPED(a) || !PyArray_ISALIGNED(a)) return 0;
    const char *p = PyArray_BYTES(a);
    const npy_intp stride = PyArray_STRIDE(a, 0);
    for (npy_intp i = 0; i < n; ++i) x[i] = *(const double *)(p + i * stride);
    return 1;
}}

{call}

{batch}

static PyMethodDef call_method = {{"kernel", (PyCFunction)(void (*)(void))call, METH_FASTCALL, NULL}};
static PyMethodDef batch_method = {{"batch", (PyCFunction)(void (*)(void))batch, METH_FASTCALL, NULL}};

static PyObject *bound(PyMethodDef *method, PyObject *k) {{
    if (!PyBytes_CheckExact(k)) {{
        PyErr_SetString(PyExc_TypeError, "bind: the constants as bytes of doubles");
        return NULL;
    }}
    return PyCFunction_NewEx(method, k, NULL);
}}

static PyObject *bind(PyObject *module, PyObject *k) {{
    (void)module;
    return bound(&call_method, k);
}}

static PyObject *bind_batch(PyObject *module, PyObject *k) {{
    (void)module;
    return bound(&batch_method, k);
}}

static PyMethodDef methods[] = {{
    {{"bind", bind, METH_O, NULL}}, {{"bind_batch", bind_batch, METH_O, NULL}}, {{NULL, NULL, 0, NULL}}
}};
static struct PyModuleDef definition = {{PyModuleDef_HEAD_INIT, "{module}", NULL, -1, methods}};

PyMODINIT_FUNC PyInit_{module}(void) {{
    import_array();
    return PyModule_Create(&definition);
}}
"""

_ARRAY_CALL = """static PyObject *call(PyObject *k, PyObject *const *args, Py_ssize_t nargs) {{
    double x[{inputs}];
    if (nargs != {groups} || {takes}) Py_RETURN_NONE;
    npy_intp shape[] = {shape};
    PyObject *result = PyArray_SimpleNew({ndim}, shape, NPY_DOUBLE);
    if (result == NULL) return NULL;
    if (kernel(x, (const double *)PyBytes_AS_STRING(k), (double *)PyArray_DATA((PyArrayObject *)result)) != 0) {{
        Py_DECREF(result);
        Py_RETURN_NONE;
    }}
    return result;
}}"""

_MATRICES_CALL = """/* a new {side} x {side} array of the doubles at p; NULL when out of memory */
static PyObject *take_matrix(const double *p) {{
    npy_intp shape[] = {{{side}, {side}}};
    PyObject *m = PyArray_SimpleNew(2, shape, NPY_DOUBLE);
    if (m != NULL) memcpy(PyArray_DATA((PyArrayObject *)m), p, sizeof(double) * {side} * {side});
    return m;
}}

static PyObject *call(PyObject *k, PyObject *const *args, Py_ssize_t nargs) {{
    double x[{inputs}], out[{outputs}];
    if (nargs != {groups} || {takes}) Py_RETURN_NONE;
    if (kernel(x, (const double *)PyBytes_AS_STRING(k), out) != 0) Py_RETURN_NONE;
    PyObject *items[] = {{{results}}};
    PyObject *result = PyTuple_New({count});
    for (int i = 0; i < {count}; ++i) {{
        if (items[i] == NULL || result == NULL) {{
            for (int j = 0; j < {count}; ++j) Py_XDECREF(items[j]);
            Py_XDECREF(result);
            return NULL;
        }}
    }}
    for (int i = 0; i < {count}; ++i) PyTuple_SET_ITEM(result, i, items[i]);
    return result;
}}"""


_BATCH_CALL = """/* a 2-D native float64 array of rows x N (N the first array's): its data and strides; 0 for anything else */
static int columns(PyObject *o, npy_intp rows, npy_intp *N, const char **data, npy_intp *strides) {{
    if (!PyArray_CheckExact(o)) return 0;
    PyArrayObject *a = (PyArrayObject *)o;
    if (PyArray_TYPE(a) != NPY_DOUBLE || PyArray_NDIM(a) != 2 || PyArray_DIM(a, 0) != rows
        || !PyArray_ISNOTSWAPPED(a) || !PyArray_ISALIGNED(a)) return 0;
    if (*N < 0) *N = PyArray_DIM(a, 1);
    else if (PyArray_DIM(a, 1) != *N) return 0;
    *data = PyArray_BYTES(a);
    strides[0] = PyArray_STRIDE(a, 0);
    strides[1] = PyArray_STRIDE(a, 1);
    return 1;
}}

static PyObject *batch(PyObject *k, PyObject *const *args, Py_ssize_t nargs) {{
    static const npy_intp rows[{groups}] = {{{rows}}};
    const char *data[{groups}];
    npy_intp strides[{groups}][2], N = -1;
    if (nargs != {groups}) Py_RETURN_NONE;
    for (int g = 0; g < {groups}; ++g)
        if (!columns(args[g], rows[g], &N, &data[g], strides[g])) Py_RETURN_NONE;
    npy_intp shape[] = {{N, {per_state}}};
    PyObject *result = PyArray_SimpleNew({ndim}, shape, NPY_DOUBLE);
    if (result == NULL) return NULL;
    double *out = (double *)PyArray_DATA((PyArrayObject *)result);
    const double *constants = (const double *)PyBytes_AS_STRING(k);
    int failed = 0;
    Py_BEGIN_ALLOW_THREADS
    double x[{inputs}];
    for (npy_intp s = 0; s < N && !failed; ++s) {{
        double *to = x;
        for (int g = 0; g < {groups}; ++g) {{
            const char *p = data[g] + s * strides[g][1];
            for (npy_intp i = 0; i < rows[g]; ++i) *to++ = *(const double *)(p + i * strides[g][0]);
        }}
        failed = kernel(x, constants, out + s * {outputs}) != 0;
    }}
    Py_END_ALLOW_THREADS
    if (failed) {{
        Py_DECREF(result);
        Py_RETURN_NONE;
    }}
    return result;
}}"""

_NO_BATCH = """static PyObject *batch(PyObject *k, PyObject *const *args, Py_ssize_t nargs) {
    (void)k, (void)args, (void)nargs;
    Py_RETURN_NONE;
}"""
