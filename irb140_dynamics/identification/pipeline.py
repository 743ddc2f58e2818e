"""Identification of a recording, end to end: read, filter, accumulate, estimate, validate.

One pass over the recording, chunk by chunk. Fit points (``signals``) before the held-out
part go into the training normal equations, the others into the held-out ones (the last
``held_out`` fraction of the samples, or a second recording): any parameter vector's
held-out RMS error then follows from those sums exactly, so nothing has to be read twice.
A torque row is left out when its joint is too slow for the Coulomb model: |qd| below
``min_speed`` (default 3 smoothing velocities, where tanh is 99.5 % of its level) anywhere
in the filter window, judged by |qd| < min_speed + |qdd| half-window. Memory holds one
chunk, the sums and at most ``plot_points`` held-out fit points for the plots.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.regressor import inertial_parameters, regressor_batch
from irb140_dynamics.identification.base import BaseParameters, find_base_parameters
from irb140_dynamics.identification.consistent import ConsistentFit, consistent_parameters
from irb140_dynamics.identification.least_squares import Estimate, NormalEquations, weighted_least_squares
from irb140_dynamics.identification.recording import CHUNK_SIZE, DEFAULT_TOPIC, Recording, RecordingError
from irb140_dynamics.identification.signals import DEFAULT_CUTOFF, Differentiator, FilterDesign, FitPoints, _joined

SLOW_SPEEDS = 3.0  # min_speed in smoothing velocities
FIT_BATCH = 8192  # fit points gathered before the regressor and the sums run: few, large array operations


@dataclass(frozen=True)
class IdentificationSettings:
    topic: str = DEFAULT_TOPIC
    cutoff: float = DEFAULT_CUTOFF  # Hz
    min_speed: float | None = None  # rad/s; None: SLOW_SPEEDS smoothing velocities
    held_out: float = 0.2  # fraction at the end of the recording, without a validation recording
    prior_weight: float = 1.0
    plot_points: int = 20_000
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
    slow_rows: np.ndarray | None = None  # per joint
    design: FilterDesign | None = None
    has_velocity: bool = False

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

    def rms(self, which: str) -> np.ndarray:
        """Held-out RMS torque error per joint [N m] of 'prior' or 'identified'."""
        pi = inertial_parameters(self.prior) if which == "prior" else self.fit.pi
        return self.held_out.rms(pi)


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
    base = find_base_parameters(prior)
    P = 13 * prior.n
    train, held_out = NormalEquations(prior.n, P), NormalEquations(prior.n, P)
    min_speed = settings.min_speed if settings.min_speed is not None else SLOW_SPEEDS * prior.smoothing_velocity
    keeper = _PlotKeeper(settings.plot_points)
    recordings = [Recording(path, prior.joint_names, settings.topic, settings.chunk_size)]
    if validate is not None:
        recordings.append(Recording(validate, prior.joint_names, settings.topic, settings.chunk_size))
    tallies = []
    for k, recording in enumerate(recordings):
        if validate is None:
            if recording.total <= 0:
                raise RecordingError(
                    recording.path,
                    "it does not tell how many messages it holds, so its last "
                    f"{100 * settings.held_out:g} % cannot be held out: validate with --validate",
                )
            split = int(round(recording.total * (1.0 - settings.held_out)))
        else:
            split = np.iinfo(np.int64).max if k == 0 else 0
        tallies.append(_accumulate(prior, recording, split, (train, held_out), min_speed, settings, keeper, progress))
    for tally, equations, use in ((tallies[0], train, "to fit"), (tallies[-1], held_out, "to validate")):
        if equations.rows.sum() == 0:
            raise RecordingError(tally.path, _nothing_usable(tally, use))
    estimate = weighted_least_squares(train, base, tallies[0].design.noise_correlation())
    fit = consistent_parameters(prior, base, estimate, settings.prior_weight)
    source = str(validate) if validate is not None else f"the last {100 * settings.held_out:g} % of the recording"
    return Result(prior, fit.model, base, estimate, fit, train, held_out, tallies, keeper.points(), source)


def _accumulate(prior, recording, split, where, min_speed, settings, keeper, progress) -> SampleTally:
    tally = SampleTally(str(recording.path), recording.total, slow_rows=np.zeros(prior.n, dtype=np.int64))
    differentiator, pending = None, []
    if progress:
        progress(tally.path, 0, tally.expected)
    for chunk in recording.chunks():
        tally.read += len(chunk)
        if differentiator is None:
            design = FilterDesign.of(_rate(recording, chunk), settings.cutoff)
            tally.design, tally.has_velocity = design, bool(np.isfinite(chunk.velocity).all())
            differentiator = Differentiator(design, prior.n, tally.has_velocity)
            keeper.expect(max(recording.total - min(split, recording.total), 0) / design.stride)
        points = differentiator.push(chunk)
        if points is not None:
            pending.append(points)
            if sum(len(p) for p in pending) >= FIT_BATCH:
                _add(prior, _joined(pending), split, where, min_speed, tally, keeper)
                pending = []
        if progress:
            progress(tally.path, tally.read + sum(recording.skipped.values()), tally.expected)
    if pending:
        _add(prior, _joined(pending), split, where, min_speed, tally, keeper)
    if differentiator is not None:
        differentiator.finish()
        tally.invalid, tally.edges = differentiator.invalid_samples, differentiator.edge_samples
    tally.skipped = recording.skipped
    return tally


def _add(prior, points: FitPoints, split, where, min_speed, tally, keeper) -> None:
    tally.fit_points += len(points)
    Y = regressor_batch(prior, points.q, points.qd, points.qdd)
    half_window = tally.design.half / tally.design.rate
    use = np.abs(points.qd) >= min_speed + np.abs(points.qdd) * half_window
    tally.slow_rows += np.sum(~use, axis=0)
    training = int(np.searchsorted(points.index, split))  # the points are in the recording's order
    for part, equations in ((slice(0, training), where[0]), (slice(training, None), where[1])):
        if len(points.index[part]):
            equations.add(Y[part], points.tau[part], use[part])  # views, not copies
    if training < len(points):
        keeper.add(points.take(slice(training, None)))


def _rate(recording: Recording, chunk) -> float:
    steps = np.diff(chunk.time[np.isfinite(chunk.time)])
    steps = steps[steps > 0]
    if len(steps) == 0:
        raise RecordingError(recording.path, "its time stamps do not increase: cannot tell the sampling rate")
    return 1.0 / float(np.median(steps))


def _nothing_usable(tally: SampleTally, use: str) -> str:
    if tally.read == 0:
        reasons = ", ".join(f"{count} {kind.replace('_', ' ')}" for kind, count in tally.skipped.items())
        return f"no usable joint states of the model's joints ({reasons or 'no messages'})"
    if tally.invalid == tally.read:
        return "no sample has efforts (and positions) for every joint of the model"
    return (
        f"no torque rows left {use}: {tally.read} samples, {tally.invalid} without effort, {tally.edges} at "
        f"gaps and ends, the rest too slow; record a longer, faster motion"
    )


class _PlotKeeper:
    """Every k-th held-out fit point, at most about ``limit`` of them."""

    def __init__(self, limit: int):
        self.limit, self.every, self.parts, self.seen = limit, 1, [], 0

    def expect(self, count: float) -> None:
        self.every = max(1, int(np.ceil(count / max(self.limit, 1))))

    def add(self, points: FitPoints) -> None:
        keep = (self.seen + np.arange(len(points))) % self.every == 0
        self.seen += len(points)
        if keep.any() and sum(len(p) for p in self.parts) < 2 * self.limit:
            self.parts.append(points.take(keep))

    def points(self) -> FitPoints | None:
        return _joined(self.parts)
