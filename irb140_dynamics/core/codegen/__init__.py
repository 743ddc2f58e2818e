"""Generated code: an algorithm of ``core.algorithms`` traced once per model (``trace``)
into one intermediate form (``program``: single assignments), which three emitters read:
straight-line Python on floats or NumPy arrays (``python_code``), a NumPy form writing into
given buffers (``array_code``) and C (``c_code``), compiled as a CPython extension for the
single-state verbs (``native``). ``kernels`` keeps each model's kernels, found by name in
one table and shared per arm (``kernels_of(model)``). Models do not import this room; the
public verbs (``core.dynamics``) call ``kernels_of``.

May import: ``core.algorithms``, ``core.model``, ``core.scalars``.
"""
