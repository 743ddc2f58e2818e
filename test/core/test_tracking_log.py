"""core.monitoring.tracking: each error paired with the state of its stamp (else the latest),
one plot sample per step, the RMS over the last window, memory bounded."""

import numpy as np

from irb140_dynamics.core.monitoring.tracking import TrackingLog


def test_errors_pair_with_their_state_and_the_rms_covers_the_window():
    log = TrackingLog(step=0.01, states=3)
    assert log.rms(0.0) is None
    log.error(0.0, 5, [1e-3, 2e-3])  # no state yet: counted, no plot sample
    assert log.rms(0.0) is None and not log.history
    for stamp in range(10):
        log.state(stamp, [float(stamp), 0.0])
    assert len(log._positions) == 3  # the newest states only
    log.error(0.5, 8, [1e-3, 0.0])
    log.error(0.505, 9, [3e-3, 0.0])  # within a step of the last sample: RMS only
    log.error(1.0, 2, [2e-3, 0.0])  # its state is gone: the latest stands in
    t, reference, actual = log.arrays()
    np.testing.assert_array_equal(t, [0.5, 1.0])
    np.testing.assert_array_equal(actual, [[8.0, 0.0], [9.0, 0.0]])
    np.testing.assert_allclose(reference - actual, [[1e-3, 0.0], [2e-3, 0.0]], rtol=1e-12)
    np.testing.assert_allclose(log.rms(1.0, window=0.6), [np.sqrt((1 + 9 + 4) / 3) * 1e-3, 0.0], rtol=1e-12)
    np.testing.assert_allclose(log.rms(1.2, window=0.6), [2e-3, 0.0], rtol=1e-12)
