"""Writes an example bundle's CSV as a MATLAB .mat file with scipy.io.savemat (an independent
writer): python make_mat.py IN.csv OUT.mat COMPRESS [NAME=COLUMN*SCALE ...].
Each NAME is a variable holding COLUMN of the CSV times SCALE, as a column vector (float64),
or as int32 when NAME ends in _i32 (counts). COMPRESS is 1 for v7 compression, 0 for v5."""
import sys

import numpy as np
import scipy.io

src, out, compress = sys.argv[1], sys.argv[2], sys.argv[3] == "1"
data = np.genfromtxt(src, delimiter=",", names=True)
variables = {}
for spec in sys.argv[4:]:
    name, rest = spec.split("=")
    column, scale = rest.split("*")
    values = data[column] * float(scale)
    if name.endswith("_i32"):
        values = np.round(values).astype(np.int32)
    variables[name] = values.reshape(-1, 1)
scipy.io.savemat(out, variables, format="5", do_compression=compress)
