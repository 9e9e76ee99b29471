"""The ``rotorid`` command."""
