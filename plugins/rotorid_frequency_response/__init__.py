"""The ``frequency-response`` estimator: a model structure fitted to frequency responses."""
