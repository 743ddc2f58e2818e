"""What an identification gives, as text: the summary and the identified parameter file."""

from __future__ import annotations

from datetime import UTC, datetime

import numpy as np

from irb140_dynamics.core.errors import counted
from irb140_dynamics.core.io.params_file import parameter_file_text
from irb140_dynamics.core.io.urdf import export_urdf
from irb140_dynamics.identification.consistent import PHYSICAL_CONFIDENCE
from irb140_dynamics.identification.pipeline import Result, SampleTally


def _count(x: int) -> str:
    return f"{x:,}"


def _tally_lines(tally: SampleTally, names) -> list[str]:
    left_out = tally.read - tally.used
    reasons = [
        f"{_count(tally.invalid)} invalid (a value missing, not finite or beyond 1e6)",
        f"{_count(tally.edges)} at gaps and ends",
    ]
    lines = [
        f"{tally.path}: {counted(tally.read, 'sample')} read, {_count(tally.used)} used, {_count(left_out)} left out "
        f"({', '.join(reasons)})"
    ]
    if tally.skipped:
        skipped = ", ".join(
            f"{_count(count)} {kind.replace('_', ' ')}" for kind, count in sorted(tally.skipped.items())
        )
        lines.append(f"  messages not used: {skipped}")
    design = tally.design
    if design is not None:
        source = "measured velocities" if tally.has_velocity else "differentiated positions"
        lines.append(
            f"  {design.rate:.1f} Hz, filtered to {design.cutoff:g} Hz (window {counted(design.window, 'sample')}), "
            f"fit at {design.rate / design.stride:.1f} Hz: {counted(tally.fit_points, 'point')}; qd from {source}"
        )
        slow = ", ".join(
            f"{name} {100.0 * k / max(tally.fit_points, 1):.1f} %" for name, k in zip(names, tally.slow_rows)
        )
        lines.append(f"  torque rows too slow for Coulomb friction, left out: {slow}")
    selection = tally.selection
    if selection is not None:
        span = tally.end - tally.start
        motion = f"{tally.rest_start:.2f} s to {span - tally.rest_end:.2f} s of {span:.2f} s"
        lines.append(
            f"  motion: {motion} (rest trimmed: {tally.rest_start:.2f} s at the start, "
            f"{tally.rest_end:.2f} s at the end)"
        )
        if 0 < selection.held_moving < selection.moving:
            lines.append(
                f"  held out from {tally.held_from:.2f} s on: the last {_count(selection.held_moving)} of "
                f"{_count(selection.moving)} moving fit points"
            )
    return lines


def summary(result: Result) -> str:
    """The summary the identify command prints."""
    names = result.prior.joint_names
    estimate, fit = result.estimate, result.fit
    lines = []
    for tally in result.tallies:
        lines += _tally_lines(tally, names)
    lines.append(
        f"base parameters: {result.base.count} of {len(result.base.names)}; condition number of the "
        f"base regressor: {estimate.condition_number:.1f}"
    )
    lines.append(
        f"held out: {result.held_out_source} ({_count(int(result.held_out.rows.max()))} torque rows); "
        "a fit point moves when a joint is fast enough to use its torque row"
    )
    lines.append("")
    lines.append(
        f"{'joint':<12} {'peak [N m]':>10}   {'prior RMS [N m]':>15} {'(% peak)':>9}   "
        f"{'identified RMS [N m]':>20} {'(% peak)':>9}"
    )
    prior, identified, peak = result.rms("prior"), result.rms("identified"), result.held_out.peak
    for name, p, e_prior, e_identified in zip(names, peak, prior, identified):
        lines.append(
            f"{name:<12} {p:>10.3f}   {e_prior:>15.4f} {_percent(e_prior, p):>9}   "
            f"{e_identified:>20.4f} {_percent(e_identified, p):>9}"
        )
    lines.append("")
    if result.offsets is not None:
        offsets = ", ".join(f"{name} {x:+.3f}" for name, x in zip(names, result.offsets))
        lines.append(f"torque offsets [N m] (fitted, added to the model's torques above): {offsets}")
    lines.append(
        f"residual correlation: {result.correlation:.1f} fit points (the estimate's covariance scaled by "
        f"{result.correlation / result.tallies[0].design.noise_correlation():.1f} over the filter's own)"
    )
    consistent = "yes" if fit.consistent else "NO"
    lines.append(
        f"physically consistent: {consistent} (every link's pseudo-inertia positive semidefinite, "
        f"friction and armature >= 0)"
    )
    check = result.physical
    worst = int(np.argmax(np.abs(fit.deviation)))
    lines.append(
        f"its base parameters vs the least-squares estimate: at most {abs(fit.deviation[worst]):.2f} sigma "
        f"({result.base.labels()[worst]})"
    )
    if check.physical:
        lines.append(
            f"the nearest physical arm is within the estimate's uncertainty (chi2 {check.chi2:.1f}, "
            f"{100 * PHYSICAL_CONFIDENCE:g} % bound {check.bound:.1f} for {check.base_parameters} base parameters): "
            "the data agree with a physical arm"
        )
    else:
        lines.append(
            f"WARNING: the data ask for an unphysical arm: the nearest physical one is beyond the estimate's "
            f"uncertainty (chi2 {check.chi2:.1f} > {100 * PHYSICAL_CONFIDENCE:g} % bound {check.bound:.1f}); a mass "
            "< 0 or an inertia that is no body's: check the recording (effort units and signs, joint names, a "
            "payload) and the prior's kinematics"
        )
    return "\n".join(lines)


def _percent(error: float, peak: float) -> str:
    return f"({100.0 * error / peak:.2f} %)" if peak > 0 else "(-)"


def base_parameter_lines(result: Result) -> list[str]:
    """Each base parameter: its combination, the estimate and its standard deviation."""
    estimate = result.estimate
    lines = []
    for text, value, std in zip(result.base.describe(), estimate.beta, estimate.std):
        label, _, combination = text.partition(" = ")
        lines.append(f"{label.strip()} = {value: .8g} +- {std:.3g}: {combination}")
    return lines


def identified_file(result: Result, command: str) -> str:
    """The identified model as a complete parameter file, the summary and base parameters as comments."""
    date = datetime.now(UTC).isoformat(timespec="seconds")
    comments = [
        f"{result.identified.n}-joint arm identified by irb140_dynamics `identify` on {date}:",
        f"  {command}",
        "Load it into the nodes with --params-file. Units: SI (m, rad, kg, kg m^2, N m, N m s/rad).",
        "Link inertials, friction and armature are identified; kinematics, limits and gravity are the prior's.",
        "",
        *summary(result).splitlines(),
        "",
        "Base parameters (what the torques determine; units of the parameters: kg, kg m, kg m^2, N m s/rad, N m):",
        *base_parameter_lines(result),
        "",
    ]
    return parameter_file_text(result.identified.to_params(), comments)


def identified_urdf(result: Result, prior_urdf: str | None, command: str) -> str:
    """The identified arm as URDF (``export_urdf``), named as the prior's URDF robot."""
    import xml.etree.ElementTree as ET

    name = (ET.fromstring(prior_urdf).get("name") if prior_urdf else None) or "robot"  # read once already
    text = export_urdf(result.identified, name)
    note = f"<!-- identified by irb140_dynamics `identify`: {command.replace('--', '- -')} -->\n"
    head, separator, rest = text.partition("?>\n")
    return head + separator + note + rest if separator else note + text
