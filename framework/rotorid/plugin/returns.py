"""What a plugin component returns, checked where rotorid uses it (a leaf module: the
verification's envelopes use it as well as the contracts' callers)."""

from __future__ import annotations

from rotorid.errors import PluginError


def returned(value, expected: type | tuple[type, ...], call: str):
    """``value`` when it is one of ``expected`` (None among them allows None); otherwise a
    :class:`PluginError` naming ``call`` (e.g. ``"data source 'fdx': case_data"``), what it
    returned and what the contract wants."""
    kinds = expected if isinstance(expected, tuple) else (expected,)
    if isinstance(value, kinds):
        return value
    wanted = " or ".join("None" if k is type(None) else k.__name__ for k in kinds)
    raise PluginError(f"{call} returned {type(value).__name__}, not {wanted}; see "
                      f"docs/plugins.md")
