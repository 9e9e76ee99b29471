"""``rotorid identify`` with a hybrid model that measures its tip-path-plane tilts: a model file
of the ``hybrid-flap`` template and maneuver files that carry ``beta1c beta1s`` columns
(docs/conventions.md), written and read back through the files plugin."""

import json

import numpy as np
from hybrid_reference import hybrid_reference, open_loop_maneuvers, six_dof_of, true_values
from rotorid.cli import main as cli
from rotorid.model.hybrid import hybrid_from_six_dof
from rotorid.model.modelfile import save_model
from rotorid_files.formats import read_maneuver, write_maneuver


def test_identify_reads_the_rotor_angle_columns(truth_model, trim_70kt, tmp_path, capsys):
    condition, a, b = hybrid_reference(truth_model, trim_70kt)
    six_dof, six_values = six_dof_of(condition, a, b)
    structure = hybrid_from_six_dof(six_dof, six_values, flap_time_constant=0.12,
                                    template="hybrid-flap")
    values = true_values(structure, a, b)
    model, data = tmp_path / "hybrid.toml", tmp_path / "data"
    save_model(structure, model)
    data.mkdir()
    for maneuver in open_loop_maneuvers(structure, values, seed=3):
        write_maneuver(maneuver, data / f"{maneuver.name}.csv")
    stored = read_maneuver(data / "3211_long_+1.csv")
    assert {"beta1c", "beta1s"} <= set(stored.extra_channels)
    header = (data / "3211_long_+1.csv").read_text(encoding="utf-8").splitlines()
    assert next(line for line in header if line.startswith("time")).endswith("beta1c,beta1s")

    out = tmp_path / "result.json"
    status = cli.main(["identify", str(model), str(data), "--out", str(out)])
    assert status == 0, capsys.readouterr().err
    record = json.loads(out.read_text(encoding="utf-8"))
    assert record["converged"] is True
    estimates = {**record["parameters"],
                 **{f"tau_{n}": e for n, e in record["delays"].items()}}
    errors = {n: (estimates[n]["value"] - v) / estimates[n]["cramer_rao"]
              for n, v in zip(structure.parameter_names, values)}
    assert max(abs(e) for e in errors.values()) < 3.0, errors
    assert len(np.diag(record["noise_covariance"])) == 10
