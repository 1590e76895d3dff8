"""openTorsion's modal analysis of the assemblies tests/modal.rs compares rigtwin against:
python opentorsion_modes.py NAME. Prints JSON: the undamped natural frequencies (Hz, elastic
modes, ascending) and the damping ratios of the underdamped poles (by natural frequency)."""
import json
import sys

import numpy as np
import opentorsion as ot


def chain5():
    # five disks on four shafts (the documentation's example values)
    shafts = [ot.Shaft(i, i + 1, k=25e6) for i in range(4)]
    disks = [ot.Disk(0, I=100), ot.Disk(1, I=10), ot.Disk(2, I=50), ot.Disk(3, I=10), ot.Disk(4, I=80)]
    return ot.Assembly(shafts, disk_elements=disks)


def geared_damped():
    # motor - shaft - pinion (R 10) meshing a wheel (R 30, ratio 3) - shaft - load; shaft damping
    # and damping of the motor and the load to ground
    shafts = [ot.Shaft(0, 1, k=800.0, c=0.5), ot.Shaft(2, 3, k=15000.0, c=2.0)]
    disks = [ot.Disk(0, I=0.004, c=0.02), ot.Disk(3, I=0.06, c=0.3)]
    pinion = ot.Gear(1, I=0.001, R=10)
    wheel = ot.Gear(2, I=0.002, R=30, parent=pinion)
    return ot.Assembly(shafts, disk_elements=disks, gear_elements=[pinion, wheel])


def branched():
    # motor - shaft - a pinion (R 10) meshing two wheels (R 20: ratio 2, R 40: ratio 4), each
    # driving its own load through its own shaft
    shafts = [ot.Shaft(0, 1, k=2000.0), ot.Shaft(2, 3, k=9000.0), ot.Shaft(4, 5, k=30000.0)]
    disks = [ot.Disk(0, I=0.01), ot.Disk(3, I=0.05), ot.Disk(5, I=0.4)]
    pinion = ot.Gear(1, I=0.002, R=10)
    wheel_a = ot.Gear(2, I=0.003, R=20, parent=pinion)
    wheel_b = ot.Gear(4, I=0.008, R=40, parent=pinion)
    return ot.Assembly(shafts, disk_elements=disks, gear_elements=[pinion, wheel_a, wheel_b])


def compliant_motor():
    # geared_damped with a compliance inside the motor: its rotor (0.4 of its 0.004 kg m², where
    # the torque acts) on a 300 N m/rad spring to the rest of it (0.6, with the motor's drag); the
    # spring damped as the motor's shaft is, c/k = 0.5/800
    shafts = [ot.Shaft(0, 1, k=300.0, c=300.0 * 0.5 / 800.0), ot.Shaft(1, 2, k=800.0, c=0.5),
              ot.Shaft(3, 4, k=15000.0, c=2.0)]
    disks = [ot.Disk(0, I=0.4 * 0.004), ot.Disk(1, I=0.6 * 0.004, c=0.02), ot.Disk(4, I=0.06, c=0.3)]
    pinion = ot.Gear(2, I=0.001, R=10)
    wheel = ot.Gear(3, I=0.002, R=30, parent=pinion)
    return ot.Assembly(shafts, disk_elements=disks, gear_elements=[pinion, wheel])


assembly = {"chain5": chain5, "geared_damped": geared_damped, "branched": branched,
            "compliant_motor": compliant_motor}[sys.argv[1]]()
M, K = np.asarray(assembly.M), np.asarray(assembly.K)
w2 = np.linalg.eigvals(np.linalg.solve(M, K)).real
scale = np.abs(w2).max()
f = sorted(np.sqrt(v) / (2 * np.pi) for v in w2 if v > 1e-9 * scale)
wn, wd, zeta = assembly.modal_analysis()
under = sorted({(round(float(n), 9), float(z)) for n, d, z in zip(wn, wd, zeta) if d > 1e-6 * scale ** 0.5})
print(json.dumps({"frequencies_hz": [float(x) for x in f],
                  "underdamped": [{"natural_hz": n / (2 * np.pi), "damping_ratio": z} for n, z in under]}))
