"""Generated code: an algorithm of ``core.algorithms`` traced into straight-line Python for
one model (``trace``), an array form writing into given buffers (``array_code``), and the
compiled kernels of a model, cached per arm (``kernels``: ``kernels_of(model)``), and the
same code compiled as C for the single-state verbs (``native``). Models do not import this
room; the public verbs (``core.dynamics``) call ``kernels_of``.

May import: ``core.algorithms``, ``core.model``, ``core.scalars``.
"""
