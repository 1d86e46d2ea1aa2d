"""Ground FDIR: detection, isolation and identification of faults from the information cost
(paper Sec. III-IV; docs/fdir.md).  The algorithms as pure functions, the pipeline that judges
each FDI window through its stages (``pipeline.py``); the app that feeds it from the bus is
``ground.apps.fdir``."""
