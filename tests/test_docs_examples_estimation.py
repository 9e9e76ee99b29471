"""docs/examples/nonlinear_model.py runs and identifies its aircraft (docs/estimation.md)."""

import matplotlib
import numpy as np
from docs_examples import load_example
from rotorid.model.nonlinear import has_own_jacobians

matplotlib.use("Agg")


def _load():
    return load_example("nonlinear_model")


def test_nonlinear_example_identifies_the_aerodynamic_coefficients(tmp_path, capsys):
    example = _load()
    assert not has_own_jacobians(example.LongitudinalAircraft)          # finite differences
    figure = tmp_path / "fit.png"
    estimate = example.main(["--seed", "7", "--plot", str(figure)])
    out = capsys.readouterr().out
    assert "[[Parameters]]" in out and "C_La2" in out and "error/CR" in out
    assert estimate.converged, estimate.stop_reason
    truth = np.array([example.TRUTH[n] for n in estimate.parameter_names])
    start = np.array([p.start for p in example.LongitudinalAircraft.parameters if not p.fixed])
    assert np.all(np.abs(start - truth) > 0.15 * np.abs(truth))        # a real start error
    assert np.all(np.abs(estimate.values - truth) <= 4 * estimate.cramer_rao)
    assert np.all(np.abs(estimate.values - truth) <= 0.03 * np.abs(truth))
    assert figure.stat().st_size > 10_000


def test_nonlinear_example_data_follow_the_seed():
    example = _load()
    _, first = example.flight_test(seed=3)
    _, again = example.flight_test(seed=3)
    _, other = example.flight_test(seed=4)
    assert all(np.array_equal(a.outputs, b.outputs) for a, b in zip(first, again))
    assert not np.array_equal(first[0].outputs, other[0].outputs)
