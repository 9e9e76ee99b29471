"""The ``filter-error`` estimator: maximum likelihood with process noise (steady-state Kalman
filter) for linear model structures."""
