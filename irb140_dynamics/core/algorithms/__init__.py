"""The algorithms, each written once on scalar components (floats, arrays, dual numbers,
intervals, or the symbols of ``core.codegen``): ``recursions`` (RNEA, CRBA and their
building blocks), ``derivatives`` (by dual numbers: the partials of tau, the Christoffel
Coriolis matrix; forward dynamics), ``regressor`` (torques linear in the inertial
parameters), ``momentum`` (generalized momentum and dT/dq for the observer), ``regrouping`` (the
same joint torques from fewer nonzero inertial parameters).

May import: ``core.model`` (constants of a model), ``core.scalars``. Never ``codegen``:
the code generator runs these, not the other way round.
"""
