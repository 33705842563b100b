"""The companion models, each in one home: particle_potential (seed 002, energy minimisation),
biaxial (seed 003: the CEM contact law, the periodic packing, the biaxial specimen, calibration),
sand_layer (seed 004: the Monte-Carlo sand layer and its mechanics).

May import: engines.model, engines.compiled, packing, engines.yade, and YADE.
"""
