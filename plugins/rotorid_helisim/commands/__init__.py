"""The truth model's own ``rotorid`` subcommands (``trim``, ``linearize``)."""
