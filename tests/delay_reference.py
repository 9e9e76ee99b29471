"""An independent reference for the delayed linear model: a fine-step trapezoidal integration of
the delay differential equation on a grid that contains every delay exactly (so that its
history needs no interpolation), and the outputs read from that solution term by term."""

from __future__ import annotations

import numpy as np


def _fine_inputs(t, u, dt, hold, grid):
    """The controls on the fine grid: held (ZOH) or linearly interpolated (FOH), (G, m)."""
    if hold == "zoh":
        return u[np.minimum(np.floor(grid / dt + 1e-9).astype(int), t.size - 1)]
    return np.column_stack([np.interp(grid, t, u[:, i]) for i in range(u.shape[1])])


def _fine_lags(table, fine):
    lags = np.rint(table.delay / fine).astype(int)
    assert np.allclose(lags * fine, table.delay), "delays must lie on the fine grid"
    return lags


def fine_states(structure, values, t, u, dt, hold, fine):
    """States (G, n) on the grid of step ``fine`` (s) from t = 0 to t[-1], trim before t = 0.

    Held inputs take the value of the step's own interval, so a ZOH switch is never smeared.
    """
    table = structure.terms(values)
    a0 = structure.known_state_matrix()
    sub = int(round(dt / fine))
    steps = (t.size - 1) * sub
    grid = np.arange(steps + 1) * fine
    u_fine = _fine_inputs(t, u, dt, hold, grid)
    lags = _fine_lags(table, fine)
    n = structure.n_states
    x = np.zeros((steps + 1, n))

    def rhs(i, xi, interval):
        """ẋ at grid point i."""
        dx = a0 @ xi
        for eq, src, g, lag in zip(table.equation, table.source, table.gain, lags):
            if src < n:
                j = i - lag
                z = xi[src] if lag == 0 else (x[j, src] if j >= 0 else 0.0)
            else:
                j = (interval if hold == "zoh" else i) - lag
                z = u_fine[j, src - n] if j >= 0 else 0.0
            dx[eq] += g * z
        return dx

    for i in range(steps):
        k1 = rhs(i, x[i], i)
        predictor = x[i] + fine * k1
        x[i + 1] = predictor
        x[i + 1] = x[i] + 0.5 * fine * (k1 + rhs(i + 1, predictor, i))
    return x


def sampled_outputs(structure, values, t, u, dt, hold, fine):
    """Outputs (N, p) at the samples t_n from :func:`fine_states`.

    The known output rows read the states (and D0 the controls); each term an output reads
    (a specific force, a state derivative) adds its weight times its gain times its source at t_n − τ: a state read on the fine grid, a control held at the
    sample whose interval contains t_n − τ (ZOH: the earlier one when t_n − τ falls on a
    sample and τ > 0, the value just before the switch) or interpolated (FOH).
    """
    table = structure.terms(values)
    x = fine_states(structure, values, t, u, dt, hold, fine)
    sub = int(round(dt / fine))
    lags = _fine_lags(table, fine)
    n = structure.n_states
    y = x[::sub] @ structure.known_output_matrix().T + u @ structure.known_feedthrough().T
    points = np.arange(t.size) * sub
    for src, g, tau, lag, out, weight in zip(table.source, table.gain, table.delay, lags,
                                             table.output, table.weight):
        if out < 0:
            continue
        if src < n:
            j = points - lag
            z = np.where(j >= 0, x[np.maximum(j, 0), src], 0.0)
        elif hold == "zoh":
            when = t - tau
            held = np.ceil(when / dt - 1e-9).astype(int) - 1 if tau > 0 else np.arange(t.size)
            z = np.where(held >= 0, u[np.maximum(held, 0), src - n], 0.0)
        else:
            z = np.interp(t - tau, t, u[:, src - n], left=0.0)
        y[:, out] += weight * g * z
    return y
