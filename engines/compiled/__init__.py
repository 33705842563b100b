"""The numba twins of engines.model: the same arithmetic as compiled kernels (kernels: contact,
water, the whole step; pores: the pore build and re-meshing, and its BUILD, REMESH steps), tested
equal to the NumPy path to round-off (tests/compiled/); layout: the named lists of the kernels'
arguments and buffers. The model's classes by the same names, stepped by the kernels: contact
(ContactLaw), paper_law (PaperLaw), water_model (WaterModel), pore_dem (PoreDEM, with the whole
step as one kernel call); each subclasses its engines.model class and overrides only what runs
compiled.

numba's cache folder is keyed by the sources of engines/model and engines/compiled (cache: a
kernel never runs code older than its callees and layouts); it is set here, before any of these
modules loads numba.

May import: NumPy, numba, engines.model. Never YADE.
"""
from engines.compiled import cache

cache.use()
