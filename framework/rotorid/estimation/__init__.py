"""Estimation: the model protocol, estimates and their statistics, equation-error starts and the reduction loop."""
