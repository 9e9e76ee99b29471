"""Built-in input signals: 3211, 2311 and doublet multisteps and the logarithmic sweep."""
