"""docs/examples/full_vs_diagonal_noise.py, the worked example of full against diagonal R in
docs/estimation.md, on a few seeds."""

from docs_examples import load_example


def _example():
    return load_example("full_vs_diagonal_noise")


def test_the_full_noise_covariance_uses_the_correlation_the_diagonal_ignores():
    """With α and a_z noise 0.95 correlated, full R reports smaller bounds for the
    derivatives those outputs measure than the diagonal."""
    example = _example()
    results = example.main(["--seeds", "4"])
    full_bounds, diagonal_bounds = results["full"][0], results["diagonal"][0]
    names = example.aeroplane().parameter_names
    for name in ("Z_u", "Z_elevator", "M_u", "M_w"):
        k = names.index(name)
        assert full_bounds[k] < 0.7 * diagonal_bounds[k], name
