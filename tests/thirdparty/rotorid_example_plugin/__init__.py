"""A third-party rotorid plugin written from docs/plugins.md alone (tests only).

It provides one component of several families: a data source simulating a small pitch/roll
model, an envelope of each kind, a reduction criterion and an estimator wrapping the built-in
output error. ``tests/test_thirdparty_plugin.py`` "installs" it through a ``*.dist-info``
folder whose ``entry_points.txt`` names :mod:`rotorid_example_plugin.plugin`.
"""
