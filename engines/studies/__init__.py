"""Studies of the numerics: speed against accuracy (tradeoffs), the stability map (stability):
their points, metrics and judgements, no YADE; ensembles and their statistics (ensemble); seed
003's judged points (biaxial_judged).

May import: engines.model, engines.compiled, engines.reference, packing, engines.yade,
engines.seeds; the runs are engines.run.tradeoffs, engines.run.stability and
engines.run.biaxial_study, the figures postproc.tradeoffs, postproc.stability and
postproc.biaxial_plots.
"""
