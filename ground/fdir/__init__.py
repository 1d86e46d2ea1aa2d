"""Ground FDIR: detection, isolation and identification of faults from the information cost
(paper Sec. III-IV; docs/fdir.md).  Pure functions here; the ground
app that runs them is ``ground.apps.fdir``."""
