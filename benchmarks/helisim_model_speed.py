"""Speed of the Bo-105 truth model's ``derivatives`` on a batch of 20 maneuvers.

Target: one call on a batch of 20 well under 1 ms, so that 20 maneuvers of 60 s at
dt = 0.004 s (RK4, 4 calls per step) integrate in about a minute. The baseline, measured in
the same run, is the same work done row by row (20 calls with a batch of 1): the ratio shows
what the vectorisation over maneuvers buys. Trim time is printed too (target < 1 s).

Run: ``.venv/bin/python benchmarks/helisim_model_speed.py``
"""

from __future__ import annotations

import time

import numpy as np
from rotorid_helisim.model import Bo105Model
from rotorid_helisim.parameters import Bo105Config
from rotorid_helisim.trim import trim


def _best(function, repeat=5, number=200):
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(number):
            function()
        best = min(best, (time.perf_counter() - start) / number)
    return best


def main(batch: int = 20) -> None:
    for inflow in ("baseline", "pitt-peters"):
        model = Bo105Model(Bo105Config(inflow=inflow))
        start = time.perf_counter()
        result = trim(model, 70.0)
        trim_time = time.perf_counter() - start
        rng = np.random.default_rng(0)
        x = result.state + 1e-3 * rng.standard_normal((batch, model.n_states))
        stick = np.repeat(result.stick[None], batch, axis=0)
        batched = _best(lambda: model.derivatives(x, stick))
        rows = _best(lambda: [model.derivatives(x[i:i + 1], stick[i:i + 1])
                              for i in range(batch)], number=20)
        print(f"{inflow:12s} derivatives, batch {batch}: {batched * 1e6:7.1f} µs per call; "
              f"row by row {rows * 1e6:8.1f} µs; speed-up {rows / batched:5.1f}x; "
              f"60 s at dt 0.004 s (RK4): {batched * 4 * 15000:5.1f} s; trim 70 kt "
              f"{trim_time * 1e3:.0f} ms")


if __name__ == "__main__":
    main()
