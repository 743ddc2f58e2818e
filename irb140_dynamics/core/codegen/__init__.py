"""Generated code: an algorithm of ``core.algorithms`` traced into straight-line Python for
one model (``trace``), an array form writing into given buffers (``array_code``), and the
compiled kernels of a model, cached per arm (``kernels``: ``kernels_of(model)``). Models
do not import this room; the public verbs (``core.dynamics``) call ``kernels_of``.

May import: ``core.algorithms``, ``core.model``, ``core.scalars``.
"""
