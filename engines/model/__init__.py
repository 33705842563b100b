"""The seed-000 physics in NumPy: contact law, separation, pores, water, loading, limits, the step.

May import: NumPy, SciPy, and engines.compiled (the model classes run their compiled twins when
asked, compiled=True). Never YADE: everything here is tested with plain pytest (tests/model/).
"""
