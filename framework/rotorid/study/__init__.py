"""Studies: flight cases, the paper's pipeline per case, speed sweeps and Monte Carlo runs."""
