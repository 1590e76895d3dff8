"""Replays a measured drive torque through FMUs with fmpy and writes the load speeds as JSON.

    fmu_replay.py FMU_DIR BUNDLE.csv START.json OUT.json ME_SECONDS

Called by tests/diagnose.rs on the FMUs (after fmpy's validation and fmutool's check of each) that `rigtwin fmu --params` builds from the model
`rigtwin diagnose --write-model` wrote. Co-simulation (FMI 3 and 2) runs the whole record at the
sampling step, the torque applied at each communication point and held over the step, as the
rig's converter holds it. Model exchange (FMI 3 and 2) runs the first ME_SECONDS with CVode; the
torque table is given as steps (each sample repeated at the next sample time), so the importer
holds it too, and every sample time is an input event.
"""
import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import fmpy
from fmpy.validation import validate_fmu

fmu_dir, bundle, start_file, out_file, me_seconds = sys.argv[1:6]
rows = list(csv.DictReader(open(bundle)))
t = np.array([float(r["time_s"]) for r in rows])
u = np.array([float(r["torque_drive_Nm"]) for r in rows])
dt = t[1] - t[0]
start = json.loads(Path(start_file).read_text())
outputs = ["w_m2", "w_m3"]
report = {"validate": {}, "fmutool": {}}
fmutool = Path(sys.executable).parent / "fmutool"

ramp = np.array(list(zip(t, u)), dtype=[("time", np.float64), ("M_drive", np.float64)])
n_me = int(round(float(me_seconds) / dt))
steps = [(t[0], u[0])]
for k in range(1, n_me + 1):
    steps += [(t[k], u[k - 1]), (t[k], u[k])]
held = np.array(steps, dtype=[("time", np.float64), ("M_drive", np.float64)])

for version in ("fmi3", "fmi2"):
    path = str(Path(fmu_dir) / f"rigtwin-{version}.fmu")
    report["validate"][version] = [str(p) for p in validate_fmu(path)]
    run = subprocess.run([str(fmutool), "-input", path, "-check"], capture_output=True, text=True)
    report["fmutool"][version] = {"returncode": run.returncode, "output": run.stdout + run.stderr}
    cs = fmpy.simulate_fmu(path, fmi_type="CoSimulation", stop_time=t[-1], step_size=dt, output_interval=dt,
                           start_values=start, input=ramp, output=outputs)
    report[f"{version}_cs"] = {name: cs[name].tolist() for name in outputs}
    me = fmpy.simulate_fmu(path, fmi_type="ModelExchange", stop_time=t[n_me], output_interval=dt,
                           relative_tolerance=1e-9, start_values=start, input=held, output=outputs)
    # the samples at the sample times (events add points)
    times = me["time"]
    keep = [int(np.searchsorted(times, tk + 1e-9)) - 1 for tk in t[: n_me + 1]]
    report[f"{version}_me"] = {name: me[name][keep].tolist() for name in outputs}

Path(out_file).write_text(json.dumps(report))
