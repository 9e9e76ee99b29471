"""Input signals: step times and levels, the sweep law, zero-order hold, bad parameters."""

import math

import numpy as np
import pytest
from rotorid.errors import DataError
from rotorid.plugin.manager import create, registry
from rotorid_signals.signals import Multistep, Sweep


@pytest.mark.parametrize("kind, levels", [
    ("3211", [1, 1, 1, -1, -1, 1, -1]),
    ("2311", [1, 1, -1, -1, -1, 1, -1]),
    ("doublet", [1, -1]),
])
def test_multistep_levels_on_each_step(kind, levels):
    signal = Multistep(kind, amplitude=-4.0, step_width=0.5, start=1.0, trailing=2.0)
    mids = 1.0 + 0.5 * (np.arange(len(levels)) + 0.5)
    np.testing.assert_array_equal(signal(mids), -4.0 * np.array(levels, float))
    assert signal(0.99) == 0.0 and signal(1.0 + 0.5 * len(levels) + 0.01) == 0.0
    assert signal.duration == pytest.approx(1.0 + 0.5 * len(levels) + 2.0)


def test_multistep_switches_exactly_at_the_step_times():
    signal = Multistep("3211", amplitude=5.0, step_width=0.3, start=2.0, sample_time=0.02)
    edges = [2.0, 2.9, 3.5, 3.8, 4.1]
    np.testing.assert_allclose(signal.switch_times(), edges)
    time = np.arange(0, 400) * 0.02
    values = signal(time)
    changes = time[1:][np.diff(values) != 0]
    np.testing.assert_allclose(changes, edges, atol=1e-12)
    # Right-continuous: the new level holds at the switch instant itself.
    assert signal(np.array([2.0, 2.9])).tolist() == [5.0, -5.0]


def test_sampled_signals_are_zero_order_holds():
    dt = 0.02
    sweep = Sweep(2.0, 1.0, 12.0, 20.0, sample_time=dt)
    fine = np.arange(0, sweep.duration, dt / 10)
    instants = np.floor(fine / dt + 1e-6) * dt
    np.testing.assert_array_equal(sweep(fine), sweep(instants))
    # Within one interval the value is constant and equals the law at the sample instant.
    law = Sweep(2.0, 1.0, 12.0, 20.0)
    samples = np.arange(0, int(sweep.duration / dt)) * dt
    np.testing.assert_allclose(sweep(samples), law(samples), atol=1e-12)


def test_sweep_frequency_follows_the_log_law():
    sweep = Sweep(1.0, 0.5, 12.0, 40.0, lead=3.0, trail=5.0)
    dwell = 2 * 2 * math.pi / 0.5
    assert sweep.dwell == pytest.approx(dwell)
    tau = np.linspace(0.0, sweep.sweep_end, 200)
    expected = 0.5 + 0.0187 * (np.exp(4.0 * tau / 40.0) - 1.0) * (12.0 - 0.5)
    np.testing.assert_allclose(sweep.frequency(3.0 + dwell + tau), expected, rtol=1e-12)
    # The phase is the integral of the frequency (independent numerical check).
    t = np.linspace(3.0, 3.0 + dwell + sweep.sweep_end, 20001)
    from scipy.integrate import cumulative_trapezoid
    integral = cumulative_trapezoid(sweep.frequency(t), t, initial=0.0)
    np.testing.assert_allclose(sweep.phase(t), integral, atol=2e-4)
    # Two full cycles at ω_min come first; the sweep ends near ω_max at a zero of the sine.
    assert sweep.phase(3.0 + dwell) == pytest.approx(4 * math.pi)
    assert math.sin(sweep.phase(3.0 + dwell + sweep.sweep_end)) == pytest.approx(0, abs=1e-9)
    assert sweep.frequency(3.0 + dwell + sweep.sweep_end) > 11.0
    assert sweep(np.array([2.9, sweep.duration - 0.1])).tolist() == [0.0, 0.0]


def test_sweep_amplitude_grows_with_frequency():
    sweep = Sweep(2.0, 0.5, 10.5, 30.0, amplitude_ratio=3.0)
    t = np.array([sweep.lead + 1.0, sweep.lead + sweep.dwell + sweep.sweep_end - 1e-6])
    omega = sweep.frequency(t)
    np.testing.assert_allclose(sweep.envelope(t), 2.0 * (1 + 2.0 * (omega - 0.5) / 10.0))
    assert np.abs(sweep(np.linspace(0, sweep.duration, 5000))).max() <= 6.0 + 1e-12


@pytest.mark.parametrize("build, message", [
    (lambda: Multistep("3212", 5.0, 0.3), "unknown multistep kind"),
    (lambda: Multistep("3211", 5.0, 0.0), "step_width must be"),
    (lambda: Multistep("3211", float("nan"), 0.3), "amplitude must be finite"),
    (lambda: Multistep("3211", 5.0, 0.25, sample_time=0.02), "use 0.24 s or 0.26 s"),
    (lambda: Multistep("3211", 5.0, 0.3, start=-1.0), "start must be"),
    (lambda: Sweep(1.0, 5.0, 2.0, 30.0), "must exceed omega_min"),
    (lambda: Sweep(1.0, 0.5, 40.0, 30.0, sample_time=0.02), "fewer than 10 samples"),
    (lambda: Sweep(1.0, 0.5, 10.0, 0.01), "too short"),
])
def test_bad_parameters_are_rejected(build, message):
    with pytest.raises(DataError, match=message):
        build()


def test_signals_are_registered_plugins():
    assert {"3211", "2311", "doublet", "sweep"} <= set(registry("input-signals"))
    signal = create("input-signals", "2311", amplitude=3.0, step_width=0.4)
    assert isinstance(signal, Multistep) and signal.kind == "2311"
    assert signal.duration == pytest.approx(1.0 + 7 * 0.4 + 8.0)
    sweep = create("input-signals", "sweep", amplitude=1.0, omega_min=1.0, omega_max=10.0,
                   sweep_time=20.0)
    assert sweep(sweep.lead + 0.5) == pytest.approx(math.sin(0.5))
