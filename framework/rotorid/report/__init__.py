"""Figures and HTML reports (a leaf: nothing that computes imports it)."""
