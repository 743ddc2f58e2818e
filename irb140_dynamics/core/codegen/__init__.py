"""Generated code: an algorithm of ``core.algorithms`` traced once per arm (``trace``) into
one intermediate form (``program``: single assignments), which three emitters read:
straight-line Python on floats or NumPy arrays (``python_code``), a NumPy form writing into
given buffers (``array_code``) and C (``c_code``). ``recipes`` names every kernel;
``kernels`` makes a model's kernels an object of their own (``Kernels(model)``, or
``kernels_of(model)``, the public verbs'), apart from the model. Compiling the C is not
done here: the core starts no process, the ``native`` room above it compiles (reached
through ``native_hook``). Models do not import this room; the public verbs
(``core.dynamics``) call ``kernels_of``.

May import: ``core.algorithms``, ``core.model``, ``core.scalars``; ``native_hook``.
"""
