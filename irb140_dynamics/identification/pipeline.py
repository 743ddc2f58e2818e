"""Identification of a recording, end to end: read, filter, select, accumulate, estimate, validate.

One pass over the recording, chunk by chunk, turns the samples into fit points
(``signals``: filtered and decimated to about 4 cut-offs per second). A torque row is left
out when its joint is too slow for the Coulomb model: |qd| below ``min_speed`` (default 3
smoothing velocities, where tanh is 99.5 % of its level) anywhere in the filter window,
judged by |qd| < min_speed + |qdd| half-window. Then ``selection`` trims the rest at both
ends of the recording and holds out the last ``held_out`` fraction of the points that
move (or uses a second recording, trimmed alike): the others go into the training normal
equations, the held-out ones into theirs, so that any parameter vector's held-out RMS
error follows from those sums exactly. Memory holds one chunk of samples, the fit points
(``FitPoints``: (4 n + 2) doubles each, some 30 MB per hour of a 6-joint recording at the
default cut-off), the sums and at most ``plot_points`` held-out points for the plots.

The estimate's covariance is scaled by the measured correlation of its residuals
(``correlation``: on a real arm, what the model lacks correlates them far more than the
filter does), so that the pull toward the prior is weighed against what the data really
tell. With ``offsets``, each joint's torque gets a constant offset (a torque sensor's
bias), fitted and eliminated from the sums (``NormalEquations.centred``); off by default.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.regressor import inertial_parameters, parameter_count, regressor_batch
from irb140_dynamics.identification.base import BaseParameters, find_base_parameters
from irb140_dynamics.identification.consistent import (
    ConsistentFit,
    PhysicalCheck,
    consistent_parameters,
    physical_check,
)
from irb140_dynamics.identification.correlation import residual_correlation
from irb140_dynamics.identification.least_squares import Estimate, NormalEquations, weighted_least_squares
from irb140_dynamics.identification.recording import CHUNK_SIZE, DEFAULT_TOPIC, Recording, RecordingError
from irb140_dynamics.identification.selection import Selection, rows_used, select
from irb140_dynamics.identification.signals import DEFAULT_CUTOFF, Differentiator, FilterDesign, FitPoints, joined

SLOW_SPEEDS = 3.0  # min_speed in smoothing velocities
FIT_BATCH = 8192  # fit points gathered before the regressor and the sums run: few, large array operations


@dataclass(frozen=True)
class IdentificationSettings:
    topic: str = DEFAULT_TOPIC
    cutoff: float = DEFAULT_CUTOFF  # Hz
    min_speed: float | None = None  # rad/s; None: SLOW_SPEEDS smoothing velocities
    held_out: float = 0.2  # fraction at the end of the recording, without a validation recording
    prior_weight: float = 1.0  # the pull toward the prior (see consistent.py and docs/identification.md)
    offsets: bool = False  # a constant torque offset per joint
    plot_points: int = 20_000
    correlation_points: int = 8192  # training fit points kept to measure the residuals' correlation
    chunk_size: int = CHUNK_SIZE


@dataclass
class SampleTally:
    """What became of a recording's samples."""

    path: str
    expected: int = 0  # samples the recording announces
    read: int = 0
    skipped: Counter = field(default_factory=Counter)  # messages not used, by reason
    invalid: int = 0  # a missing (effort, velocity) or non-finite value
    edges: int = 0  # within half a filter window of a gap or an end
    fit_points: int = 0
    slow_rows: np.ndarray | None = None  # per joint, among the selected fit points
    design: FilterDesign | None = None
    has_velocity: bool = False
    selection: Selection | None = None  # of the fit points: rest trimmed, held-out part
    start: float = 0.0  # s: the first and last valid sample's times
    end: float = 0.0
    rest_start: float = 0.0  # s of rest trimmed before the first moving fit point
    rest_end: float = 0.0  # and after the last
    held_from: float = 0.0  # s from the start: where the held-out part begins (== span end: none)

    @property
    def used(self) -> int:
        return self.read - self.invalid - self.edges


@dataclass(frozen=True, eq=False)
class Result:
    prior: RobotModel
    identified: RobotModel
    base: BaseParameters
    estimate: Estimate
    fit: ConsistentFit
    train: NormalEquations
    held_out: NormalEquations
    tallies: list[SampleTally]
    plot_points: FitPoints | None
    held_out_source: str
    physical: PhysicalCheck
    correlation: float = 1.0  # the factor the covariance was scaled by (see correlation.py)
    offsets: np.ndarray | None = None  # (n,) N m, with settings.offsets

    def rms(self, which: str) -> np.ndarray:
        """Held-out RMS torque error per joint [N m] of 'prior' or 'identified'."""
        if which == "prior":
            return self.held_out.rms(inertial_parameters(self.prior))
        return self.held_out.rms(self.fit.pi, self.offsets)


Progress = Callable[[str, int, int], None]  # (path, samples done, samples expected)


def identify(
    prior: RobotModel,
    path,
    settings: IdentificationSettings = IdentificationSettings(),
    validate=None,
    progress: Progress | None = None,
) -> Result:
    """Identify ``prior``'s parameters from the recording at ``path`` (see the module's docstring)."""
    if not 0.0 < settings.held_out < 1.0 and validate is None:
        raise ValueError(f"held_out: must be within (0, 1), got {settings.held_out}")
    if not settings.prior_weight > 0.0 or not (settings.min_speed is None or settings.min_speed >= 0.0):
        raise ValueError(
            f"prior_weight must be > 0 and min_speed >= 0, got {settings.prior_weight}, {settings.min_speed}"
        )
    P = parameter_count(prior)
    train, held_out = NormalEquations(prior.n, P), NormalEquations(prior.n, P)
    min_speed = settings.min_speed if settings.min_speed is not None else SLOW_SPEEDS * prior.smoothing_velocity
    recordings = [Recording(path, prior.joint_names, settings.topic, settings.chunk_size)]
    if validate is not None:
        recordings.append(Recording(validate, prior.joint_names, settings.topic, settings.chunk_size))
    tallies, held_points, training_points = [], None, None
    for k, recording in enumerate(recordings):
        tally, points = read_fit_points(prior, recording, settings, progress)
        fraction = settings.held_out if validate is None else (0.0 if k == 0 else 1.0)
        held, training = _accumulate(
            prior, tally, points, fraction, min_speed, (train, held_out), settings.correlation_points
        )
        held_points = held if held is not None else held_points
        training_points = training if k == 0 else training_points
        tallies.append(tally)
    for tally, equations, use in ((tallies[0], train, "to fit"), (tallies[-1], held_out, "to validate")):
        if equations.rows.sum() == 0:
            raise RecordingError(tally.path, nothing_usable(tally, use, min_speed))
    base = find_base_parameters(prior)  # after the recordings are read: a bad one is refused at once
    filter_correlation = tallies[0].design.noise_correlation()
    estimate = weighted_least_squares(train.centred() if settings.offsets else train, base, filter_correlation)
    beta_offsets = (train.t - train.s[:, base.independent] @ estimate.beta) / np.maximum(train.rows, 1)
    correlation = filter_correlation
    if training_points is not None:
        half_window = tallies[0].design.half / tallies[0].design.rate
        use = rows_used(training_points.qd, training_points.qdd, min_speed, half_window)
        correlation, _ = residual_correlation(
            prior,
            base,
            estimate.beta,
            training_points,
            use,
            beta_offsets if settings.offsets else None,
            filter_correlation,
        )
    estimate = replace(estimate, covariance=estimate.covariance * (correlation / filter_correlation))
    fit = consistent_parameters(prior, base, estimate, settings.prior_weight)
    offsets = train.offsets(fit.pi) if settings.offsets else None
    check = physical_check(prior, base, estimate, fit)
    source = (
        f"{validate} (rest trimmed)"
        if validate is not None
        else f"the last {100 * settings.held_out:g} % of the moving fit points of the recording"
    )
    plots = (
        None
        if held_points is None
        else held_points.take(slice(None, None, _every(len(held_points), settings.plot_points)))
    )
    return Result(
        prior, fit.model, base, estimate, fit, train, held_out, tallies, plots, source, check, correlation, offsets
    )


def read_fit_points(prior, recording, settings, progress) -> tuple[SampleTally, FitPoints | None]:
    """A recording's fit points (all of them, in order) and its tally."""
    tally = SampleTally(str(recording.path), recording.total, slow_rows=np.zeros(prior.n, dtype=np.int64))
    differentiator, parts, times = None, [], []
    if progress:
        progress(tally.path, 0, tally.expected)
    for chunk in recording.chunks():
        tally.read += len(chunk)
        if differentiator is None:
            try:
                design = FilterDesign.of(_rate(recording, chunk), settings.cutoff)
            except ValueError as error:
                raise RecordingError(recording.path, str(error)) from None
            tally.design, tally.has_velocity = design, bool(np.isfinite(chunk.velocity).all())
            differentiator = Differentiator(design, prior.n, tally.has_velocity)
        finite = chunk.time[np.isfinite(chunk.time)]
        if len(finite):
            times += [float(finite.min()), float(finite.max())]
        points = differentiator.push(chunk)
        if points is not None:
            parts.append(points)
        if progress:
            progress(tally.path, tally.read + sum(recording.skipped.values()), tally.expected)
    if differentiator is not None:
        differentiator.finish()
        tally.invalid, tally.edges = differentiator.invalid_samples, differentiator.edge_samples
    tally.skipped = recording.skipped
    if times:
        tally.start, tally.end = min(times), max(times)
    points = joined(parts)
    tally.fit_points = 0 if points is None else len(points)
    return tally, points


def _accumulate(
    prior,
    tally: SampleTally,
    points: FitPoints | None,
    held_out: float,
    min_speed: float,
    where: tuple[NormalEquations, NormalEquations],
    training_limit: int,
) -> tuple[FitPoints | None, FitPoints | None]:
    """Select ``points`` (rest trimmed, the last ``held_out`` fraction of the moving ones held
    out), add them to the training and held-out sums ``where``; the held-out points, and the
    first ``training_limit`` training points (for the residuals' correlation)."""
    if points is None or len(points) == 0:
        return None, None
    half_window = tally.design.half / tally.design.rate
    moves = rows_used(points.qd, points.qdd, min_speed, half_window).any(axis=1)
    selection = tally.selection = select(moves, held_out)
    if selection is None:
        return None, None
    tally.rest_start = float(points.time[selection.first] - tally.start)
    tally.rest_end = float(tally.end - points.time[selection.end - 1])
    tally.held_from = float(points.time[min(selection.split, selection.end - 1)] - tally.start)
    for part, equations in ((selection.train, where[0]), (selection.held, where[1])):
        for batch in range(part.start, part.stop, FIT_BATCH):
            _add(
                prior,
                points.take(slice(batch, min(batch + FIT_BATCH, part.stop))),
                min_speed,
                half_window,
                tally,
                equations,
            )
    held = points.take(selection.held) if selection.split < selection.end else None
    train = selection.train
    first = slice(train.start, min(train.stop, train.start + training_limit))
    return held, (points.take(first) if first.stop > first.start else None)


def _add(prior, points: FitPoints, min_speed, half_window, tally, equations: NormalEquations) -> None:
    Y = regressor_batch(prior, points.q, points.qd, points.qdd)
    use = rows_used(points.qd, points.qdd, min_speed, half_window)
    tally.slow_rows += np.sum(~use, axis=0)
    equations.add(Y, points.tau, use)


def _every(count: int, limit: int) -> int:
    """The step that keeps at most about ``limit`` of ``count`` points."""
    return max(1, -(-count // max(limit, 1)))


def _rate(recording: Recording, chunk) -> float:
    steps = np.diff(chunk.time[np.isfinite(chunk.time)])
    steps = steps[steps > 0]
    if len(steps) == 0:
        raise RecordingError(recording.path, "its time stamps do not increase: cannot tell the sampling rate")
    return 1.0 / float(np.median(steps))


def nothing_usable(tally: SampleTally, use: str, min_speed: float) -> str:
    if tally.read == 0:
        reasons = ", ".join(f"{count} {kind.replace('_', ' ')}" for kind, count in tally.skipped.items())
        return f"no usable joint states of the model's joints ({reasons or 'no messages'})"
    if tally.invalid == tally.read:
        return "no sample has efforts (and positions) for every joint of the model"
    if tally.fit_points and tally.selection is None:
        return (
            f"nothing moves: every joint is slower than {min_speed:.3g} rad/s throughout ({tally.read} samples); "
            "record a motion (or lower --min-speed)"
        )
    return (
        f"no torque rows left {use}: {tally.read} samples, {tally.invalid} without effort, {tally.edges} at "
        f"gaps and ends, the rest too slow; record a longer, faster motion"
    )
