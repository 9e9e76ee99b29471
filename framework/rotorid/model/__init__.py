"""Model structures: derivatives, flight conditions, known terms and model files."""
