"""Studies of the numerics: speed against accuracy (tradeoffs), the stability map (stability).

May import: engines.model, engines.compiled, engines.reference, packing, engines.yade; the
scripts that run them are yade_scripts/tradeoffs.py and yade_scripts/stability.py.
"""
