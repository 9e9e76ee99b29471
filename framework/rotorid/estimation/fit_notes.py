"""Notes on a finished fit that point at the data or the setup: maneuvers whose residuals
stand out, delays the zero-order hold hides from an output, smoothly moving inputs held by it,
and modes faster than the records resolve."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rotorid.model.modes import modes

#: A maneuver whose residual power, per output in units of R, exceeds this multiple of the
#: maneuvers' median stands out.
OUTLIER_FACTOR = 4.0
#: A mode whose |λ| times the records' sample time exceeds this settles within two samples.
FAST_MODE_STEP = 0.5
#: Inputs whose largest change over one sample stays below this fraction of their excursion
#: in every maneuver move smoothly: recorded positions, not commands held between samples.
SMOOTH_INPUT_STEP = 0.5


def outlying_maneuvers(residuals: Sequence[np.ndarray], names: Sequence[str],
                       noise_covariance: np.ndarray) -> str | None:
    """A note naming the maneuvers whose residuals (each (N_i, n_o)) carry more than
    :data:`OUTLIER_FACTOR` times the median maneuver's power, each output counted in units of
    its noise variance R_jj; None when none does or there are fewer than three maneuvers."""
    if len(residuals) < 3:
        return None
    variance = np.maximum(np.diag(noise_covariance), 1e-300)
    power = np.array([np.mean(np.mean(r**2, axis=0) / variance) for r in residuals])
    median = float(np.median(power))
    if median <= 0:
        return None
    ratio = power / median
    worst = [k for k in np.argsort(-ratio) if ratio[k] > OUTLIER_FACTOR]
    if not worst:
        return None
    listed = ", ".join(f"{names[k]} ({ratio[k]:.1f})" for k in worst)
    return (f"maneuvers fitted far worse than the others, their residual power a multiple of "
            f"the median maneuver's: {listed}; turbulence, a bad record or another trim in "
            f"them biases every derivative: look at their time histories, leave them out, or "
            f"fit them with filter error")


def direct_delayed_terms(structure) -> dict[str, tuple[str, ...]]:
    """Delayed free derivatives of ``structure`` that some output reads directly (a control
    derivative of a force equation, read by its accelerometer): name → those outputs."""
    names = structure.parameter_names
    zero = np.zeros(len(names))
    direct_zero = structure.matrices(zero)[3]
    found = {}
    for derivative in structure.free_delays:
        if derivative.name not in names:
            continue
        one = zero.copy()
        one[names.index(derivative.name)] = 1.0
        rows = np.flatnonzero(np.any(structure.matrices(one)[3] != direct_zero, axis=1))
        if rows.size:
            found[derivative.name] = tuple(structure.outputs[i] for i in rows)
    return found


def held_delay_note(structure, hold: str) -> str | None:
    """Under the zero-order hold, a note naming the delays of :func:`direct_delayed_terms`:
    the held input is the same at every sample for any delay below one sample, so those
    outputs see the delay only through the states; None otherwise."""
    if hold != "zoh":
        return None
    found = direct_delayed_terms(structure)
    if not found:
        return None
    listed = ", ".join(f"{name} ({', '.join(outputs)})" for name, outputs in found.items())
    return (f"the delays of {listed} act on outputs directly, which under the zero-order hold "
            f"read the same held input for any delay below one sample: those outputs see the "
            f"delay only through the states; for inputs recorded from moving controls use the "
            f"first-order hold (--hold foh)")


def _setting_derivatives(structure, vector: np.ndarray, states: Sequence[str]) -> list[str]:
    """The free derivatives of ``structure`` that enter A where both the row and the column
    are among ``states`` (the terms that set a mode carried by those states)."""
    index = [structure.states.index(s) for s in states]
    block = np.ix_(index, index)
    nominal = structure.matrices(vector)[0][block]
    found = []
    for i, (name, delay) in enumerate(zip(structure.parameter_names, structure.is_delay())):
        if delay:
            continue
        stepped = vector.copy()
        stepped[i] += 1.0
        if np.any(structure.matrices(stepped)[0][block] != nominal):
            found.append(name)
    return found


def fast_modes_note(structure, values, sample_time: float,
                    turbulence: str = "turbulence in the records (fit with filter error)"
                    ) -> str | None:
    """A note naming the modes of the fitted ``structure`` (a ModelStructure; ``values`` its
    parameter vector or a name → value mapping) that settle within two samples of
    ``sample_time`` s (|λ|·dt > :data:`FAST_MODE_STEP`), with the derivatives that set each;
    None when there is none. The records show such a mode's quasi-static gain only, so those
    derivatives are not determined one by one (a rigid body's velocity damping of 100 1/s
    standing in for a motor's lag). ``turbulence`` names the turbulence among the causes,
    with what the estimator that fitted can do about it."""
    fast = [m for m in modes(structure, values) if m.frequency * sample_time > FAST_MODE_STEP]
    if not fast:
        return None
    vector = structure.as_vector(values)
    listed = "; ".join(
        f"{mode.eigenvalue_text} 1/s ({mode.describe()}, in {', '.join(mode.states)}), set by "
        f"{', '.join(_setting_derivatives(structure, vector, mode.states)) or 'known terms'}"
        for mode in fast)
    return (f"modes faster than the records resolve (settled within two samples of "
            f"{sample_time:g} s): {listed}; the data determine such a mode's quasi-static gain, "
            f"not the derivatives that set it. Unless the aircraft has a mode that fast, it "
            f"stands in for what the fit could not otherwise follow: dynamics the structure "
            f"lacks (actuator or motor lags, delays, rotor states: add them), {turbulence}, "
            f"or a poor start (start elsewhere); else fix or remove those derivatives")


def smooth_inputs_note(maneuvers) -> str | None:
    """Under the zero-order hold, a note when every moving input of every maneuver changes by
    less than :data:`SMOOTH_INPUT_STEP` of its excursion from one sample to the next: such
    inputs are recorded positions (surfaces, actuators) that move between samples, which the
    first-order hold follows and the zero-order hold delays by half a sample; None
    otherwise (a multistep a computer holds jumps by its whole step within one sample)."""
    if maneuvers.hold != "zoh":
        return None
    largest = []
    for maneuver in maneuvers:
        for column in maneuver.inputs.T:
            excursion = float(np.ptp(column))
            if excursion > 0:
                largest.append(float(np.max(np.abs(np.diff(column)))) / excursion)
    if not largest or max(largest) >= SMOOTH_INPUT_STEP:
        return None
    return (f"the inputs move smoothly (no change over one sample above "
            f"{max(largest):.0%} of their excursion): recorded positions rather than commands "
            f"held between samples; the zero-order hold delays them by half a sample, which "
            f"the derivatives then absorb: fit them with the first-order hold (--hold foh, "
            f"[resampling] hold = \"foh\")")
