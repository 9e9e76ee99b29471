"""Simulation of the delayed linear model: discrete maps, batched simulation with sensitivities, analytic frequency response."""
