"""The worked example of docs/frequency.md runs and identifies its model."""

import re
from pathlib import Path

import numpy as np
from rotorid.verification.handling_qualities import model_handling_qualities

DOC = Path(__file__).resolve().parents[1] / "docs" / "frequency.md"


def test_frequency_example_runs_and_recovers_the_model(capsys):
    (example,) = re.findall(r"```python\n(.*?)```", DOC.read_text(encoding="utf-8"), re.S)
    namespace: dict = {}
    exec(compile(example, str(DOC), "exec"), namespace)
    printed = capsys.readouterr().out
    estimate, structure, truth = (namespace[k] for k in ("estimate", "structure", "truth"))
    assert estimate.estimator == "frequency-response" and estimate.converged
    errors = np.abs(estimate.values - structure.as_vector(truth))
    assert np.all(errors <= 3.0 * estimate.cramer_rao)
    assert "J p/lat" in printed and "theta/long: bandwidth" in printed
    identified = model_handling_qualities(structure, estimate.values, pairs=["theta/long"])
    reference = model_handling_qualities(structure, truth, pairs=["theta/long"])
    assert abs(identified[0].bandwidth / reference[0].bandwidth - 1.0) < 0.1
