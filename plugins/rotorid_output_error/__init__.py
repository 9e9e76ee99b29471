"""Built-in estimator: maximum-likelihood output error with Levenberg-Marquardt steps."""
