"""Built-in data source: maneuver files in CSV, NumPy ``.npz`` and MATLAB ``.mat`` format."""
