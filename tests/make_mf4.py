"""Writes the example sweep v1_sweep_b.csv as an ASAM MDF 4 file with asammdf (an independent
writer): python make_mf4.py IN.csv OUT.mf4 MODE.
MODE "one": one channel group, speeds in rpm, the drive torque in N·m, deflate-compressed blocks.
MODE "two": the speeds (rpm) in one group at the CSV's rate, the torque (kNm) in a second group
at half the rate, transposed-deflate compressed."""
import sys

import numpy as np
from asammdf import MDF, Signal

src, out, mode = sys.argv[1:4]
d = np.genfromtxt(src, delimiter=",", names=True)
t = d["time_s"]
rpm = 60.0 / (2.0 * np.pi)
speeds = [
    Signal(samples=d["speed_m2_radps"] * rpm, timestamps=t, name="n_M2", unit="rpm"),
    Signal(samples=d["speed_m3_radps"] * rpm, timestamps=t, name="n_M3", unit="rpm"),
]
mdf = MDF(version="4.10")
if mode == "one":
    torque = Signal(samples=d["torque_drive_Nm"], timestamps=t, name="Trq_Drv", unit="Nm")
    mdf.append(speeds + [torque], comment="rig")
    mdf.save(out, overwrite=True, compression=1)
else:
    torque = Signal(samples=d["torque_drive_Nm"][::2] / 1000.0, timestamps=t[::2], name="Trq_Drv", unit="kNm")
    mdf.append(speeds, comment="load machines")
    mdf.append([torque], comment="drive")
    mdf.save(out, overwrite=True, compression=2)
