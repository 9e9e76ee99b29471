"""The diagnostics of docs/examples/turbulence_hover.py: the two-stage inputs and the fixed
cyclic delay (the slow tests in test_docs_examples_study.py run the example itself)."""

import attrs
import numpy as np
import pytest
from docs_examples import load_example
from rotorid import FlightCondition, Maneuver, ManeuverSet, ModelStructure
from rotorid.model.hybrid import FLAP_CONTROL_DELAYS, hybrid_from_six_dof
from rotorid_signals.signals import Multistep

DT = 0.02
SIGNAL = {"step_width": 0.4, "start": 1.0, "trailing": 6.0, "sample_time": DT}
#: Correlation time of the synthetic loop part, s.
LOOP_TIME = 0.5


@pytest.fixture(scope="module")
def example():
    return load_example("turbulence_hover")


def _records(seed: int = 0):
    """Two axes, each flown with a 3211 and a 2311 both ways, as the hover case does. The
    excited stick is 0.8 times the multistep 0.1 s late and the other stick −0.3 times it,
    each plus a 'loop' part independent of it (first-order Gauss-Markov, :data:`LOOP_TIME`);
    returns the records and each record's multistep-driven part."""
    rng = np.random.default_rng(seed)
    records, driven = [], []
    for column, axis in enumerate(("long", "lat")):
        for kind, direction in ((k, d) for k in ("3211", "2311") for d in (1, -1)):
            signal = Multistep(kind, 5.0 * direction, **SIGNAL)
            time = np.arange(round(signal.duration / DT)) * DT
            excitation = signal(time)
            lagged = np.concatenate([np.zeros(5), excitation[:-5]])
            part = np.zeros((time.size, 4))
            part[:, column] = 0.8 * lagged
            part[:, 1 - column] = -0.3 * excitation
            decay = np.exp(-DT / LOOP_TIME)
            loop = np.zeros((time.size, 4))
            for n in range(1, time.size):
                loop[n] = decay * loop[n - 1] + rng.normal(0.0, 0.3, 4)
            metadata = {"axis": axis, "signal": {"type": "Multistep", "kind": kind,
                                                 "amplitude": 5.0 * direction, **SIGNAL}}
            records.append(Maneuver(f"{kind}_{axis}{direction:+d}", time, part + loop,
                                    np.zeros((time.size, 8)), metadata=metadata))
            driven.append(part)
    return ManeuverSet(records), driven


def test_two_stage_inputs_keep_what_the_multistep_drives_and_drop_the_rest(example):
    records, driven = _records()
    projected = example.two_stage_inputs(records)
    for original, new, part in zip(records, projected, driven):
        loop = original.inputs - part
        left = new.inputs - part
        rms = lambda x: float(np.sqrt(np.mean(x ** 2)))             # noqa: E731
        # What stays of the loop part is the fit's chance share: its 176 taps on 4·490
        # samples keep about √(176/1960) = 0.3 of it (0.23–0.34 here).
        assert rms(left[:, :2]) < 0.45 * rms(loop[:, :2]), original.name
        assert np.array_equal(new.inputs[0], original.inputs[0])
        assert np.array_equal(new.outputs, original.outputs)
        assert np.array_equal(new.time, original.time)
    # Without the loop part the inputs lie in the filter's span and come back exactly.
    driven_only = attrs.evolve(records, maneuvers=[
        attrs.evolve(record, inputs=part) for record, part in zip(records, driven)])
    for new, part in zip(example.two_stage_inputs(driven_only), driven):
        assert np.allclose(new.inputs, part, atol=1e-9)
    # The given records are left as they were.
    assert np.array_equal(records[0].inputs, _records()[0][0].inputs)


def test_the_cyclic_delay_is_fixed_on_the_four_flap_derivatives(example):
    six_dof = ModelStructure.six_dof(FlightCondition.from_airspeed(0.0, 2.0))
    values = {**dict(zip(six_dof.parameter_names, six_dof.initial_values())),
              "L_p": -12.0, "M_q": -3.5, "L_lat": 13.0, "M_long": -5.0}
    hybrid = hybrid_from_six_dof(six_dof, six_dof.as_vector(values))
    delayed = example.with_cyclic_delay(hybrid, 0.09)
    for name in FLAP_CONTROL_DELAYS:
        delay = delayed.derivative(name).delay
        assert delay.fixed and delay.initial == pytest.approx(0.09)
        assert f"tau_{name}" not in delayed.parameter_names
    assert delayed.names == hybrid.names
