"""Link inertials from shapes: the report's appendix A.1, Figure 5 and Table 2."""

import math

import numpy as np
import pytest

from irb140_dynamics.core import irb140
from irb140_dynamics.core.model.irb140 import (
    IRB140_MOVING_MASS,
    box_inertia,
    cylinder_inertia,
    irb140_volumes,
    solve_density,
)

# Rows of Figure 5 (the A.1 script's output): r, a1, a2, a3, rho, W1, W2, W3, W4.
# r: link 1 cylinder radius (h 0.2); a1: link 2 square side (l 0.36); a2: link 4 square side
# (l 0.38); a3: link 6 cylinder radius (h 0.065).
FIGURE_5 = [
    (0.096, 0.150, 0.146, 0.108, 3200.329097, 18.531773, 25.922666, 25.922922, 7.622639),
    (0.096, 0.146, 0.150, 0.104, 3220.078909, 18.646136, 24.710113, 27.531675, 7.112077),
    (0.096, 0.150, 0.130, 0.100, 3489.211813, 20.204573, 28.262616, 22.407718, 7.125093),
    (0.096, 0.150, 0.142, 0.104, 3282.611531, 19.008236, 26.589153, 25.152420, 7.250190),
    (0.100, 0.130, 0.130, 0.108, 3684.282463, 23.149029, 22.415175, 23.660462, 8.775334),
]
PRINTED = 0.5e-6 + 1e-9  # %f prints 6 decimals: half a unit in the last place, plus slack


@pytest.mark.parametrize("row", FIGURE_5, ids=[f"rho={row[4]}" for row in FIGURE_5])
def test_solve_density_reproduces_figure_5(row):
    r, a1, a2, a3, rho_printed, *masses_printed = row
    volumes = irb140_volumes(
        link1=dict(radius=r, height=0.2),
        link2=(0.36, a1, a1),
        link4=(a2, 0.38, a2),
        link6=dict(radius=a3, height=0.065),
    )
    rho = solve_density(IRB140_MOVING_MASS, volumes)
    assert abs(rho - rho_printed) <= PRINTED
    for volume, mass_printed in zip(volumes, masses_printed):
        assert abs(rho * volume - mass_printed) <= PRINTED


def test_irb140_masses_are_table_2():
    masses = [joint.link.mass for joint in irb140().joints]
    assert [round(m, 2) for m in masses] == [19.31, 25.92, 0.0, 25.92, 0.0, 7.62]
    assert masses[0] == pytest.approx(3200 * math.pi * 0.098**2 * 0.2, rel=1e-15)
    assert masses[1] == pytest.approx(3200 * 0.36 * 0.15 * 0.15, rel=1e-15)
    assert masses[3] == pytest.approx(3200 * 0.38 * 0.146 * 0.146, rel=1e-15)
    assert masses[5] == pytest.approx(3200 * math.pi * 0.108**2 * 0.065, rel=1e-15)


def test_irb140_inertials_are_the_report_formulas():
    """REFERENCE.md: I1, I2, I4, I6 about the CoMs, in frames 1, 2, 4, 6; links 3, 5 empty."""
    links = [joint.link for joint in irb140().joints]
    m1, m2, m4, m6 = (links[i].mass for i in (0, 1, 3, 5))
    r1, h1 = 0.098, 0.2
    l2, b2, h2 = 0.36, 0.15, 0.15
    l4, b4, h4 = 0.38, 0.146, 0.146
    r6, h6 = 0.108, 0.065
    expected = {
        0: ((0, -0.1, 0), [m1 / 12 * (3 * r1**2 + h1**2), m1 / 2 * r1**2, m1 / 12 * (3 * r1**2 + h1**2)]),
        1: ((-0.18, 0, 0), [m2 / 12 * (b2**2 + h2**2), m2 / 12 * (l2**2 + h2**2), m2 / 12 * (b2**2 + l2**2)]),
        3: ((0, 0.19, 0), [m4 / 12 * (b4**2 + l4**2), m4 / 12 * (b4**2 + h4**2), m4 / 12 * (h4**2 + l4**2)]),
        5: ((0, 0, -0.0325), [m6 / 12 * (3 * r6**2 + h6**2), m6 / 12 * (3 * r6**2 + h6**2), m6 / 2 * r6**2]),
    }
    for i, link in enumerate(links):
        if i in expected:
            com, diagonal = expected[i]
            np.testing.assert_allclose(link.com, com, rtol=0, atol=1e-15)
            np.testing.assert_allclose(link.inertia, diagonal + [0, 0, 0], rtol=1e-14, atol=0)
        else:
            assert link.mass == 0.0 and link.inertia == (0.0,) * 6


def test_shape_inertias_by_hand():
    m = 2.0
    np.testing.assert_allclose(box_inertia(m, (0.1, 0.2, 0.3)), [m / 12 * 0.13, m / 12 * 0.10, m / 12 * 0.05, 0, 0, 0])
    across, along = m / 12 * (3 * 0.04 + 0.09), m / 2 * 0.04
    np.testing.assert_allclose(cylinder_inertia(m, 0.2, 0.3, "x"), [along, across, across, 0, 0, 0])
    np.testing.assert_allclose(cylinder_inertia(m, 0.2, 0.3, "y"), [across, along, across, 0, 0, 0])
    np.testing.assert_allclose(cylinder_inertia(m, 0.2, 0.3, "z"), [across, across, along, 0, 0, 0])
