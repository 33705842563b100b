"""The numba twins of engines.model: the same arithmetic as compiled kernels (kernels: contact,
water, the whole step; pores: the pore build and re-meshing), tested equal to the NumPy path to
round-off (tests/compiled/); layout: the named lists of the kernels' arguments and buffers.

May import: NumPy, numba. Nothing else of the project; never YADE.
"""
