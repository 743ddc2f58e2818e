"""What an identification gives, as text: the summary and the identified parameter file."""

from __future__ import annotations

from datetime import UTC, datetime

import numpy as np

from irb140_dynamics.core.io.params_file import parameter_file_text
from irb140_dynamics.identification.pipeline import Result, SampleTally

LARGE_DEVIATION = 3.0  # standard deviations


def _count(x: int) -> str:
    return f"{x:,}"


def _tally_lines(tally: SampleTally, names) -> list[str]:
    left_out = tally.read - tally.used
    reasons = [f"{_count(tally.invalid)} without effort (or another value)", f"{_count(tally.edges)} at gaps and ends"]
    lines = [
        f"{tally.path}: {_count(tally.read)} samples read, {_count(tally.used)} used, {_count(left_out)} left out "
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
            f"  {design.rate:.1f} Hz, filtered to {design.cutoff:g} Hz (window {design.window} samples), "
            f"fit at {design.rate / design.stride:.1f} Hz: {_count(tally.fit_points)} points; qd from {source}"
        )
        slow = ", ".join(
            f"{name} {100.0 * k / max(tally.fit_points, 1):.1f} %" for name, k in zip(names, tally.slow_rows)
        )
        lines.append(f"  torque rows too slow for Coulomb friction, left out: {slow}")
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
    lines.append(f"held out: {result.held_out_source} ({_count(int(result.held_out.rows.max()))} points)")
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
    worst = int(np.argmax(np.abs(fit.deviation)))
    consistent = "yes" if fit.consistent else "NO"
    lines.append(
        f"physically consistent: {consistent} (every link's pseudo-inertia positive semidefinite, "
        f"friction and armature >= 0)"
    )
    verdict = (
        "the data agree with a physical arm"
        if abs(fit.deviation[worst]) <= LARGE_DEVIATION
        else "the data ask for an unphysical arm: check the recording (effort units, joint names, payload)"
    )
    lines.append(
        f"its base parameters vs the least-squares estimate: at most {abs(fit.deviation[worst]):.2f} sigma "
        f"({result.base.labels()[worst]}): {verdict}"
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
