"""Studies of the numerics: speed against accuracy (tradeoffs), the stability map (stability):
their points, metrics and judgements, no YADE.

May import: engines.model, engines.compiled, engines.reference, packing, engines.yade; the
runs are engines.run.tradeoffs and engines.run.stability, the figures postproc.tradeoffs and
postproc.stability.
"""
