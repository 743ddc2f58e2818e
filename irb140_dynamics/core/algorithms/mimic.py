"""The coordinates of a model with mimic joints, on scalars: every link's (cos, sin),
velocity and acceleration from the independent joints', and their torques and M carried
back by virtual work (tau = G^T tau_all, M = G^T M_all G), written with + - * only like the
recursions, so that the kernels trace them (see ``codegen.kernels``)."""

from __future__ import annotations

from irb140_dynamics.core.scalars.dual import Dual


def coupling(model) -> tuple | None:
    """Per link of the model, the index k of its coordinate q_k (an independent joint) or
    (k, multiplier, offset) (a mimic joint: multiplier q_k + offset); None: no mimic joint,
    link i is q_i."""
    if model.mimics is None:
        return None
    return tuple(
        k if mimic is None else (k, multiplier, offset)
        for (k, multiplier, offset), mimic in zip(model.coordinates, model.mimics)
    )


class Coordinates:
    """The links' coordinates: ``n`` independent ones (the state's), ``n_links`` links;
    ``angles`` the independent joints' angle offsets (None: prismatic), ``mimic_angles`` the
    mimic joints' (k, multiplier, offset, prismatic) (see ``codegen.trace``)."""

    def __init__(self, links, coupled=None):
        self.links = links
        self.coupled = coupled  # see ``coupling``: None, every link its own coordinate
        self.n_links = len(links)
        if coupled is None:
            self.n = len(links)
            self.angles = [None if link.prismatic else link.theta_offset for link in links]
            self.mimic_angles = ()
            return
        independent = [i for i, c in enumerate(coupled) if isinstance(c, int)]
        followers = [i for i, c in enumerate(coupled) if not isinstance(c, int)]
        self.n = len(independent)
        self.angles = [None if links[i].prismatic else links[i].theta_offset for i in independent]
        self.mimic_angles = tuple(
            (
                coupled[i][0],
                coupled[i][1],
                coupled[i][2] + (0.0 if links[i].prismatic else links[i].theta_offset),
                links[i].prismatic,
            )
            for i in followers
        )
        # where each link's (cos, sin) is in the traced cs: the coordinates', then the followers'
        self._slot = {i: coupled[i] for i in independent}
        self._slot.update({i: self.n + j for j, i in enumerate(followers)})

    def expanded(self, cs, *vectors):
        """(every link's cs, every link's value of each vector) from the traced cs (the
        coordinates', then the mimic joints', see trace) and vectors of the coordinates: a
        mimic joint's velocity or acceleration is multiplier times its joint's."""
        if self.coupled is None:
            return (cs, *vectors)
        all_cs = [cs[self._slot[i]] for i in range(self.n_links)]
        out = [all_cs]
        for v in vectors:
            out.append([v[c] if isinstance(c, int) else v[c[0]] * c[1] for c in self.coupled])
        return tuple(out)

    def projected(self, tau):
        """G^T tau: every link's torque carried by the coordinates (virtual work)."""
        if self.coupled is None:
            return list(tau)
        out = [None] * self.n
        for c, t in zip(self.coupled, tau):
            if isinstance(c, int):
                out[c] = t
        for c, t in zip(self.coupled, tau):
            if not isinstance(c, int):
                out[c[0]] = out[c[0]] + c[1] * t
        return out

    def projected_matrix(self, M):
        """G^T M G, rows then columns."""
        if self.coupled is None:
            return M
        columns = [self.projected([row[j] for row in M]) for j in range(self.n_links)]  # of G^T M
        return [self.projected([column[a] for column in columns]) for a in range(self.n)]

    def dual_angles(self, cs, parts: int):
        """The traced cs (coordinates', then mimic joints') as dual numbers of ``parts``
        parts carrying d/dq_k (parts 0..n-1): a mimic joint's multiplier times its joint's
        (d/dq_k cos(m q_k + o) = -m sin(m q_k + o))."""
        zeros = (0.0,) * parts

        def unit(k, value):
            return zeros[:k] + (value,) + zeros[k + 1 :]

        scales = [(k, 1.0) for k in range(self.n)] + [(k, m) for k, m, _, _ in self.mimic_angles]
        return [
            (Dual(x[0], unit(k, m)),)
            if len(x) == 1
            else (Dual(x[0], unit(k, x[1] * -m if m != 1.0 else -x[1])), Dual(x[1], unit(k, x[0] * m)))
            for x, (k, m) in zip(cs, scales)
        ]
