"""Read-only containers for the fields of frozen values: arrays that cannot be written and
mappings that cannot be changed (and still pickle, so results travel between processes)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np


def readonly_array(value, dtype=float) -> np.ndarray:
    """A read-only copy of ``value`` as an array of ``dtype``."""
    array = np.array(value, dtype=dtype, copy=True)
    array.setflags(write=False)
    return array


class FrozenMapping(Mapping):
    """A read-only mapping that, unlike ``types.MappingProxyType``, pickles."""

    def __init__(self, mapping):
        self._items = dict(mapping)

    def __getitem__(self, key):
        return self._items[key]

    def __iter__(self):
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._items!r})"
