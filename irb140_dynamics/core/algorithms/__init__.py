"""The algorithms, each written once on scalar components (floats, arrays, dual numbers,
intervals, or the symbols of ``core.codegen``): ``recursions`` (RNEA, CRBA, Christoffel
Coriolis and their building blocks), ``regressor`` (torques linear in the inertial
parameters), ``momentum`` (generalized momentum and dT/dq for the observer).

May import: ``core.model`` (constants of a model), ``core.scalars``. Never ``codegen``:
the code generator runs these, not the other way round.
"""
