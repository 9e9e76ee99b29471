"""Built-in flight cases, declared as TOML data (see :mod:`rotorid.study.case`)."""
