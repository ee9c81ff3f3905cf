from pathlib import Path
import numpy as np
from hfcdem.io.series import read_facets, read_pvd
fr = read_pvd(Path("scratch_tmp/s12/interfaces.pvd"))
c, a, d0 = read_facets(Path("scratch_tmp/s12") / fr[-3][1])
_, _, d1 = read_facets(Path("scratch_tmp/s12") / fr[-2][1])
_, _, d2 = read_facets(Path("scratch_tmp/s12") / fr[-1][1])
old = d0["state"] > 0
for nm, d in [("217", d0), ("229", d1), ("240", d2)]:
    o = d["opening_m"][old]; tn = d["normal_traction_MPa"][old]; fp = d["fluid_pressure_MPa"][old]
    print(nm, "old: open>1e-8", (o > 1e-8).sum(), "closed<=0", (o <= 0).sum(), "traction pct", np.percentile(tn, [0, 10, 50, 90, 100]).round(2), "fluid p", np.percentile(fp, [0, 50, 100]).round(2))
print(Path("scratch_tmp/s12/interfaces").exists())
