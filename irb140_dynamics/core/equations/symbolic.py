"""The equations of motion on SymPy symbols: the core's own recursions run on them.

``algorithms.rnea`` and ``algorithms.crba`` are written on scalars with ``+ - *`` only, so
they run unchanged on SymPy expressions: q enters as the (cos, sin) pairs the caller gives,
here cos(q_i + offset_i) and sin(q_i + offset_i) (an offset that is a multiple of pi/2 is
taken exactly, so cos(q2 + pi/2) reads -sin(q2)). Nothing of the model is written a second
time. SymPy's automatic distribution of numbers over sums is switched off while the
recursion runs, so the expressions keep the recursion's nested, shared structure; common
subexpressions are then pulled out once per quantity (``reduced``).

    tau = M(q) qdd + C(q, qd) qd + g(q) + tau_f(qd)

tau includes the friction tau_f (as ``rnea`` of the core does); M the armature; Cqd and g
neither (as ``coriolis`` and ``gravity``). The regressor is n x 13 n_links (see ``regressor``):
with mimic joints each link's columns carried by the coordinates, G^T Y_all, and a mimic
joint's friction and armature columns in the row of the joint it follows, as the core's.
With ``symbolic`` parameters each link's inertial parameters, each joint's friction and
armature, and the payload's are named symbols (``Parameter``); otherwise the model's numbers.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields, replace

import sympy as sp
from sympy.core.parameters import distribute

from ..algorithms import recursions as algorithms
from ..algorithms.mimic import Coordinates, coupling
from ..algorithms.regressor import rigid_body_regressor
from ..codegen.trace import quarter_turns
from ..model.rigid_body import shift_inertia
from ..regressor import JOINT_TERMS, LINK_PARAMETERS, PARAMETERS_PER_JOINT

QUANTITIES = ("tau", "M", "C", "g", "regressor")
DEFAULT_QUANTITIES = ("tau", "M", "C", "g")
INERTIA_NAMES = ("XX", "YY", "ZZ", "XY", "XZ", "YZ")  # the order of the core's inertia 6-tuples


@dataclass(frozen=True)
class Parameter:
    """A named model parameter: its symbol, the model's value, and what it is."""

    symbol: sp.Symbol
    value: float
    meaning: str


@dataclass(frozen=True)
class Equations:
    """The quantities asked for, as SymPy expressions of q, qd, qdd (and the parameters).

    ``quantities`` maps a name (tau, M, Cqd, g, regressor) to its entries, matrices row-major.
    """

    n: int
    joint_names: tuple[str, ...]
    q: tuple[sp.Symbol, ...]
    qd: tuple[sp.Symbol, ...]
    qdd: tuple[sp.Symbol, ...]
    gravity: tuple[float, float, float]
    parameters: tuple[Parameter, ...]  # empty unless symbolic
    quantities: dict[str, list]
    shapes: dict[str, tuple[int, ...]]
    arguments: dict[str, tuple[str, ...]]  # which of q, qd, qdd each quantity takes
    regressor_columns: tuple[str, ...] = ()


def joint_symbols(n: int) -> tuple[tuple[sp.Symbol, ...], ...]:
    """q1..qn, qd1..qdn, qdd1..qddn (real)."""
    return tuple(tuple(sp.Symbol(f"{name}{i + 1}", real=True) for i in range(n)) for name in ("q", "qd", "qdd"))


def angle_pair(q: sp.Symbol, offset: float):
    """(cos, sin) of q + offset, an offset of whole quarter turns (``trace.quarter_turns``,
    as the kernels take it) exactly m pi / 2."""
    rest, quarter = quarter_turns(offset)
    theta = q + sp.Float(offset) if rest else q + quarter * sp.pi / 2
    return sp.cos(theta), sp.sin(theta)


def joint_input(q: sp.Symbol, link):
    """What the recursions take for joint i, as the core's kernels give it: (cos, sin) of
    q + offset for a revolute joint, (q,) for a prismatic one (a Link marked ``prismatic``)."""
    if getattr(link, "prismatic", False):
        return (q,)
    return angle_pair(q, link.theta_offset)


def _angles(coordinates, q) -> list:
    """What the recursions take for each coordinate's joint, then for each mimic joint
    (cos, sin) of multiplier q_k + offset, or (multiplier q_k + offset,) (see ``Coordinates``)."""
    independent = [i for i, c in enumerate(coordinates.coupled or range(len(q))) if isinstance(c, int)]
    cs = [joint_input(q_i, coordinates.links[i]) for q_i, i in zip(q, independent)]
    for k, multiplier, offset, prismatic in coordinates.mimic_angles:
        x = _exact(multiplier) * q[k]
        cs.append((x + _exact(offset),) if prismatic else angle_pair(x, offset))
    return cs


def derive(
    model,
    what=DEFAULT_QUANTITIES,
    symbolic: bool = False,
    progress: Callable[[str], None] = None,
    unexpressed: frozenset = frozenset(),
):
    """The Equations of ``model`` for the quantities ``what`` (names from QUANTITIES); those
    named in ``unexpressed`` (tau, M, Cqd, g) with their shape and arguments but no
    expressions (an empty list): the C and Python forms of a model with numbers write them
    from the code generator's programs (see traced), SymPy need not derive them."""
    unknown = [w for w in what if w not in QUANTITIES]
    if unknown:
        raise ValueError(f"unknown quantity {unknown[0]!r}: choose from {', '.join(QUANTITIES)}")
    progress = progress or (lambda stage: None)
    n = model.n
    q, qd, qdd = joint_symbols(n)
    if model.mimics is not None and symbolic:
        raise ValueError("a model with mimic joints is written with its numbers (no symbolic parameters)")
    if model.flange_joint is not None and symbolic:
        raise ValueError("symbolic parameters take the payload on the last link (no flange_joint)")
    links, parameters, friction = links_of(model, symbolic)
    coordinates = Coordinates(links, coupling(model))
    cs = coordinates.expanded(_angles(coordinates, q))[0]
    zeros = [0] * len(links)
    project = coordinates.projected
    full_qd, full_qdd = coordinates.expanded(cs, qd, qdd)[1:]
    quantities, shapes, arguments = {}, {}, {}
    with distribute(False):
        if "tau" in what:
            shapes["tau"], arguments["tau"] = (n,), ("q", "qd", "qdd")
            if _derived(quantities, "tau", unexpressed, progress, "tau by Newton-Euler"):
                tau = project(algorithms.rnea(links, cs, full_qd, full_qdd, _exact(model.gravity)))
                quantities["tau"] = [t + _friction(friction, i, qd[i]) for i, t in enumerate(tau)]
        if "M" in what:
            shapes["M"], arguments["M"] = (n, n), ("q",)
            if _derived(quantities, "M", unexpressed, progress, "M by composite rigid bodies"):
                M = coordinates.projected_matrix(algorithms.crba(links, cs))
                quantities["M"] = [M[i][j] for i in range(n) for j in range(n)]
        if "C" in what:
            shapes["Cqd"], arguments["Cqd"] = (n,), ("q", "qd")
            if _derived(quantities, "Cqd", unexpressed, progress, "C(q, qd) qd by Newton-Euler"):
                quantities["Cqd"] = project(algorithms.rnea(links, cs, full_qd, zeros, (0, 0, 0)))
        if "g" in what:
            shapes["g"], arguments["g"] = (n,), ("q",)
            if _derived(quantities, "g", unexpressed, progress, "g by Newton-Euler"):
                quantities["g"] = project(algorithms.rnea(links, cs, zeros, zeros, _exact(model.gravity)))
        if "regressor" in what:
            progress("the regressor")
            Y = rigid_body_regressor(links, cs, full_qd, full_qdd, _exact(model.gravity))
            Y = list(zip(*(project(column) for column in zip(*Y))))  # G^T Y_all, column by column
            quantities["regressor"] = _with_joint_columns(Y, qd, qdd, model.smoothing_velocity, model.coordinates)
            width = PARAMETERS_PER_JOINT * len(links)
            shapes["regressor"], arguments["regressor"] = (n, width), ("q", "qd", "qdd")
    columns = _regressor_columns(len(links)) if "regressor" in what else ()
    return Equations(
        n,
        model.joint_names,
        q,
        qd,
        qdd,
        tuple(model.gravity),
        parameters,
        {k: [sp.sympify(x) for x in v] for k, v in quantities.items()},
        shapes,
        arguments,
        columns,
    )


def _derived(quantities: dict, name: str, unexpressed, progress, stage: str) -> bool:
    """Whether the quantity ``name`` is to be derived here (``progress`` told the stage);
    it is listed in ``quantities`` either way, without expressions until derived."""
    quantities[name] = []
    if name in unexpressed:
        return False
    progress(stage)
    return True


def reduced(expressions: list, prefix: str = "x"):
    """(replacements, outputs): common subexpressions pulled out (sympy.cse), deterministic;
    the replacements nothing uses left out."""
    replacements, outputs = sp.cse(expressions, symbols=sp.numbered_symbols(prefix), order="none")
    needed = set().union(*(sp.sympify(x).free_symbols for x in outputs))
    kept = []
    for symbol, expr in reversed(replacements):
        if symbol in needed:
            kept.append((symbol, expr))
            needed |= expr.free_symbols
    return kept[::-1], outputs


# -- the links on symbols --------------------------------------------------------------


def links_of(model, symbolic: bool, scalar: Callable = None):
    """The recursion's links (numbers, or symbols with their Parameters) and the friction
    per joint ((viscous, coulomb, smoothing velocity) or None). ``scalar(k, symbol)``, if
    given, is what stands for the k-th parameter in the links (default: its symbol)."""
    links = exact_links(algorithms.chain(model))
    if not symbolic:
        friction = None
        if model.friction is not None:  # per coordinate, a mimic joint's carried by its joint
            f = model.friction
            friction = [(v, c, model.smoothing_velocity) for v, c in zip(f.viscous.tolist(), f.coulomb.tolist())]
        return links, (), friction
    arm = exact_links(algorithms.chain(model.with_payload(type(model.payload)())))
    parameters: list[Parameter] = []

    def named(name, value, meaning):
        parameters.append(Parameter(sp.Symbol(name, real=True), float(value), meaning))
        symbol = parameters[-1].symbol
        return scalar(len(parameters) - 1, symbol) if scalar else symbol

    symbolic_links, friction = [], []
    for i, (link, joint) in enumerate(zip(arm, model.joints), start=1):
        symbolic_links.append(
            replace(
                link,
                m=named(f"m{i}", link.m, f"link {i} mass [kg]"),
                h=tuple(
                    named(f"m{axis}{i}", x, f"link {i} first moment m c_{axis} [kg m]")
                    for axis, x in zip("xyz", link.h)
                ),
                I=tuple(
                    named(f"{name}{i}", x, f"link {i} inertia {name} about its frame's origin [kg m^2]")
                    for name, x in zip(INERTIA_NAMES, link.I)
                ),
                armature=named(f"Ia{i}", joint.armature, f"joint {i} armature [kg m^2]"),
            )
        )
        friction.append(
            (
                named(f"fv{i}", joint.friction.viscous, f"joint {i} viscous friction [N m s/rad]"),
                named(f"fc{i}", joint.friction.coulomb, f"joint {i} Coulomb friction [N m]"),
                model.smoothing_velocity,
            )
        )
    symbolic_links[-1] = _with_payload(symbolic_links[-1], model, named)
    return tuple(symbolic_links), tuple(parameters), friction


def exact_links(links):
    """The links with their whole-number constants as integers: SymPy keeps 1.0 * x as it is,
    but 1 * x is x (the recursion leaves such products to the scalar type)."""
    return tuple(replace(link, **{f.name: _exact(getattr(link, f.name)) for f in fields(link)}) for link in links)


def _exact(value):
    if isinstance(value, tuple):
        return tuple(_exact(x) for x in value)
    if isinstance(value, float) and value.is_integer() and abs(value) < 2**53:
        return int(value)
    return value


def _with_payload(last, model, named):
    """The last link with a payload of symbolic parameters (about the flange origin, in the
    flange frame) rigidly added."""
    m_p, h_p, i_p = model.payload.about_origin()
    m = named("mP", m_p, "payload mass [kg]")
    h = tuple(
        named(f"m{axis}P", x, f"payload first moment m c_{axis} [kg m], flange frame") for axis, x in zip("xyz", h_p)
    )
    inertia = tuple(
        named(f"{name}P", x, f"payload inertia {name} about the flange origin [kg m^2]")
        for name, x in zip(INERTIA_NAMES, i_p)
    )
    if not model.flange.is_identity:
        R = [[float(x) for x in row] for row in model.flange.rotation()]
        h = algorithms.rotate(R, h)
        inertia = _rotated_inertia(R, inertia)
        # from the flange origin F to the link's L = F - r: r = L -> F, the flange's position
        m, h, inertia = shift_inertia(m, h, inertia, tuple(float(x) for x in model.flange.xyz))
    return replace(last, m=last.m + m, h=algorithms.add(last.h, h), I=tuple(a + b for a, b in zip(last.I, inertia)))


def _rotated_inertia(R, inertia):
    """R I R^T of an inertia 6-tuple."""
    xx, yy, zz, xy, xz, yz = inertia
    full = ((xx, xy, xz), (xy, yy, yz), (xz, yz, zz))
    RI = [[sum(R[i][k] * full[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    out = [[sum(RI[i][k] * R[j][k] for k in range(3)) for j in range(3)] for i in range(3)]
    return (out[0][0], out[1][1], out[2][2], out[0][1], out[0][2], out[1][2])


def _friction(friction, i, qd_i):
    if friction is None:
        return 0
    viscous, coulomb, smoothing = friction[i]
    return viscous * qd_i + coulomb * sp.tanh(qd_i / sp.Float(smoothing))


def _with_joint_columns(Y, qd, qdd, smoothing, coordinates):
    """The n x 13 n_links regressor, row-major: the rigid-body block, then each joint's
    friction and armature columns [qd, tanh(qd/v_s), qdd], in the row of its coordinate k
    (``coordinates``: (k, multiplier m, offset) per joint): a mimic joint's m^2 qd_k,
    tanh(qd_k/v_s) when |m| = 1 (else 0: no such term), m^2 qdd_k (virtual work, as
    ``regressor.regressor_batch``)."""
    links = len(coordinates)
    rows = [list(Y[k]) + [0] * (JOINT_TERMS * links) for k in range(len(Y))]
    for i, (k, m, _) in enumerate(coordinates):
        m2 = _exact(m * m)
        coulomb = sp.tanh(qd[k] / sp.Float(smoothing)) if abs(m) == 1.0 else 0
        start = len(Y[k]) + JOINT_TERMS * i
        rows[k][start : start + JOINT_TERMS] = [m2 * qd[k], coulomb, m2 * qdd[k]]
    return [x for row in rows for x in row]


def _regressor_columns(n: int) -> tuple[str, ...]:
    names = [f"{p}{i + 1}" for i in range(n) for p in LINK_PARAMETERS]
    return tuple(names + [f"{p}{i + 1}" for i in range(n) for p in ("viscous", "coulomb", "armature")])
