"""Studies of the numerics: speed against accuracy (tradeoffs), the stability map (stability):
their points, metrics and judgements, no YADE; ensembles and their statistics (ensemble); seed
003's judged points (biaxial_judged); the seismic study's reconstruction, its variants (reconstruction).

May import: engines.model, engines.compiled, engines.reference, packing, engines.yade,
engines.seeds; the runs are engines.run.tradeoffs, engines.run.stability,
engines.run.biaxial_study and engines.run.reconstruction, the figures postproc.tradeoffs,
postproc.stability, postproc.biaxial_plots and postproc.liquefaction.
"""
