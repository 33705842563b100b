"""Named layouts for the compiled kernels: one ordered list of names gives each name's position,
the argument tuples the kernels take and the buffers they read, so that a caller builds them by
name and adding or reordering a name cannot misalign it. No numba, no YADE.

A ``Layout`` is a module object whose attributes are the positions: numba reads the attributes
of a global module as compile-time constants, so that a kernel takes part ``WATER_FLOATS.U`` of
a buffer, or item ``LAW.du`` of a tuple, at the cost of a literal index.
"""
import inspect
import types
from operator import itemgetter

import numpy as np


class Layout(types.ModuleType):
    """The ordered list ``names``; ``layout.<name>`` is its position in the list."""

    def __init__(self, kind, names):
        super().__init__(kind)
        names = tuple(names)
        taken = {"names", "_get", "fields", "not_read"} | set(dir(type(self))) | set(vars(self))
        bad = sorted({n for n in names if names.count(n) > 1 or n in taken})
        if bad or len(names) < 2:
            raise ValueError(f"layout {kind}: two or more names, each once, none an attribute of Layout; got {bad or names}")
        self.names = names
        for k, name in enumerate(names):
            setattr(self, name, k)
        self._get = itemgetter(*names)

    @classmethod
    def of(cls, kernel, skip):
        """The parameters of the numba kernel ``kernel`` after its first ``skip``: the tuple of
        arguments a caller passes as ``kernel(first, ..., *values)``."""
        return cls(kernel.__name__, list(inspect.signature(kernel.py_func).parameters)[skip:])

    @classmethod
    def of_fields(cls, kind, fields, not_read, extra=()):
        """The layout of a parameter vector: the names of ``fields`` (a settings' field list, in its
        order) but those of ``not_read`` ({name: why no kernel reads it}, each a field), then the
        names ``extra`` (values that are no field, e.g. dt). Kept as ``fields`` and ``not_read``."""
        stray = sorted(set(not_read) - set(fields))
        if stray:
            raise ValueError(f"layout {kind}: {stray} listed as not read but no field of {sorted(fields)}")
        layout = cls(kind, [n for n in fields if n not in not_read] + list(extra))
        layout.fields, layout.not_read = tuple(fields), dict(not_read)
        return layout

    def vector(self, source=None, **given):
        """The float vector of this layout: each name's value from ``given``, else the attribute of
        ``source`` by that name (a settings object)."""
        return np.array([given[n] if n in given else getattr(source, n) for n in self.names], float)

    def check(self, *parts):
        """This layout, checked to be ``parts`` one after the other (layouts, or tuples of names):
        the parameters of a kernel that spells out those of the kernels it calls."""
        expected = tuple(n for p in parts for n in (p.names if isinstance(p, Layout) else p))
        if self.names != expected:
            raise TypeError(f"{self.__name__}: the names {self.names} are not those of its parts {expected}")
        return self

    def values(self, **by_name):
        """The tuple of the values given by name, in the list's order (every name once)."""
        if len(by_name) != len(self.names):
            raise TypeError(f"{self.__name__}: got {sorted(by_name)}, expected {sorted(self.names)}")
        return self._get(by_name)

    def pack(self, parts, dtype):
        """(buffer, offsets): the arrays parts[name] flattened one after the other in the list's
        order into one buffer of ``dtype``; part k is buffer[offsets[k]:offsets[k + 1]]."""
        arrays = [np.ravel(np.asarray(p, dtype)) for p in self.values(**parts)]
        at = np.cumsum([0] + [len(a) for a in arrays]).astype(np.int64)
        return np.concatenate(arrays), at

    def part(self, buffer, offsets, name):
        """A view of the part ``name`` of a buffer made by ``pack``."""
        k = getattr(self, name)
        return buffer[offsets[k]:offsets[k + 1]]
