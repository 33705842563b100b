"""The seed-000 physics in NumPy: contact law, separation, pores, water, loading, limits, the step.

The readable path: the compiled twins (engines.compiled) subclass these classes and plug into
their steps, never the other way round. May import: NumPy, SciPy. Never YADE: everything here is
tested with plain pytest (tests/model/).
"""
