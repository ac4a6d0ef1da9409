"""Result objects of tacho, torsiograph, instruments and the synthetic bench tabulate and plot
(figure returned, never shown)."""

import matplotlib
import numpy as np

from measure.instruments import vibrograph
from measure.synth.profile import ramp
from measure.tacho import angle_from_pulses, count_pitches, speed_from_pulses
from measure.torsiograph import angular_vibration, calibrate_teeth, error_floor

matplotlib.use("Agg")


def test_results_tabulate_and_plot():
    from matplotlib.figure import Figure

    t = np.arange(1200) / 1500.0
    objs = [speed_from_pulses(t, pulses_per_rev=60), angle_from_pulses(t, pulses_per_rev=60),
            count_pitches(t, pulses_per_rev=60),
            calibrate_teeth(t, pulses_per_rev=60),
            angular_vibration(t, pulses_per_rev=60, max_order=4),
            error_floor(speed_rpm=1500, pulses_per_rev=60, timer_resolution=1e-7),
            vibrograph(natural_frequency=5.0, damping_ratio=0.6),
            vibrograph(natural_frequency=5.0, damping_ratio=0.6).correct(
                np.sin(np.arange(4000) / 100.0), fs=1000.0),
            ramp(500.0, 900.0, duration=3.0)]
    for obj in objs:
        frame = obj.to_frame()
        assert len(frame) > 0
        fig = obj.plot()
        assert isinstance(fig, Figure)
        matplotlib.pyplot.close(fig)
