"""The companion models, each in one home: particle_potential (seed 002: energy minimisation,
the §4 specimen), biaxial (seed 003: the CEM contact law, the periodic packing, the biaxial
specimen, calibration, the time steps at rest, the study's analysis), sand_layer (seed 004: the
Monte-Carlo sand layer, its mechanics, the study).

May import: engines.model, engines.compiled, packing, engines.yade, and YADE.
"""
