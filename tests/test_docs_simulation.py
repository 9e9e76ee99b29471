"""The example of docs/simulation.md runs and agrees with the API it documents."""

import re
from pathlib import Path

import numpy as np

DOC = Path(__file__).resolve().parents[1] / "docs" / "simulation.md"


def test_simulation_example_runs(capsys):
    (example,) = re.findall(r"```python\n(.*?)```", DOC.read_text(encoding="utf-8"), re.S)
    namespace: dict = {}
    exec(compile(example, str(DOC), "exec"), namespace)
    printed = capsys.readouterr().out
    assert printed.startswith("peak roll rate ") and "(deg/s)/%" in printed
    y, outputs, sens, h = (namespace[k] for k in ("y", "outputs", "sens", "h"))
    structure = namespace["structure"]
    assert y.shape == (500, 8) and np.array_equal(y, outputs[0])
    assert sens[0].shape == (500, structure.n_parameters, 8)
    assert h.shape == (3, 8, 4) and np.iscomplexobj(h)
    p = structure.outputs.index("p")
    assert np.abs(y[:, p]).max() > 0.1     # the doublet rolls the model
