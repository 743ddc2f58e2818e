"""The payload proof: certified maxima of static joint torques over boxes of joint angles.

``harmonic`` writes the static torques as finite harmonic sums with rigorous (interval)
coefficients, ``bounds`` bounds such sums over a box, ``certify`` runs branch and bound on
them; ``interval_bounds`` is the plainer proof for arms with too many joints for the sums.
A maximum from here is proven, never sampled.

May import: ``core.scalars``, ``core.algorithms``, ``core.codegen``, ``core.model``.
"""
