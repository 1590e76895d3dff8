"""Replays measured inputs through rigtwin's FMUs with fmpy; writes the outputs as JSON.

    fmu_replay.py FMU_DIR DATA.csv INPUTS START.json OUTPUTS OUT.json ME_SECONDS

INPUTS: comma-separated `csv_column=fmu_input`; OUTPUTS: comma-separated FMU output names.
Called by tests/diagnose.rs (a sweep through the rig's FMU) and tests/diagnose_drive.rs (a
drive_test through a drive model's FMU) on the FMUs `rigtwin fmu --params` builds from the model
`rigtwin diagnose --write-model` wrote. Each FMU is first validated by fmpy and
checked by fmutool. Co-simulation (FMI 3 and 2) runs the whole record at the sampling step, the
inputs applied at each communication point and held over the step (as a DAQ's command is);
model exchange (FMI 3 and 2) runs the first ME_SECONDS with CVode (relative tolerance 1e-9, and
again at 1e-8: where the two part, the integration no longer sets the trajectory), the inputs
given as steps (each sample repeated at the next sample time) so that the importer holds them
too.
"""
import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import fmpy
from fmpy.validation import validate_fmu

fmu_dir, data, inputs, start_file, outputs, out_file, me_seconds = sys.argv[1:8]
rows = list(csv.DictReader(open(data)))
t = np.array([float(r["time_s"]) for r in rows])
pairs = [p.split("=") for p in inputs.split(",")]
u = {var: np.array([float(r[col]) for r in rows]) for col, var in pairs}
outputs = outputs.split(",")
dt = t[1] - t[0]
start = json.loads(Path(start_file).read_text())
report = {"validate": {}, "fmutool": {}}
fmutool = Path(sys.executable).parent / "fmutool"

dtype = [("time", np.float64)] + [(var, np.float64) for _, var in pairs]
table = np.array([tuple([t[k]] + [u[var][k] for _, var in pairs]) for k in range(len(t))], dtype=dtype)
n_me = int(round(float(me_seconds) / dt))
steps = [tuple([t[0]] + [u[var][0] for _, var in pairs])]
for k in range(1, n_me + 1):
    steps.append(tuple([t[k]] + [u[var][k - 1] for _, var in pairs]))
    steps.append(tuple([t[k]] + [u[var][k] for _, var in pairs]))
held = np.array(steps, dtype=dtype)


def model_exchange(path, tolerance):
    """The first ME_SECONDS with CVode at `tolerance`, the outputs at the sample times."""
    me = fmpy.simulate_fmu(path, fmi_type="ModelExchange", stop_time=t[n_me], output_interval=dt,
                           relative_tolerance=tolerance, start_values=start, input=held, output=outputs)
    keep = [int(np.searchsorted(me["time"], tk + 1e-9)) - 1 for tk in t[: n_me + 1]]
    return {name: me[name][keep].tolist() for name in outputs}


for version in ("fmi3", "fmi2"):
    path = str(Path(fmu_dir) / f"rigtwin-{version}.fmu")
    report["validate"][version] = [str(p) for p in validate_fmu(path)]
    run = subprocess.run([str(fmutool), "-input", path, "-check"], capture_output=True, text=True)
    report["fmutool"][version] = {"returncode": run.returncode, "output": run.stdout + run.stderr}
    cs = fmpy.simulate_fmu(path, fmi_type="CoSimulation", stop_time=t[-1], step_size=dt, output_interval=dt,
                           start_values=start, input=table, output=outputs)
    report[f"{version}_cs"] = {name: cs[name].tolist() for name in outputs}
    report[f"{version}_me"] = model_exchange(path, 1e-9)
    # the same at a 10x looser tolerance: where the two part, the model's trajectory is no
    # longer set by the integration to that tolerance (a grazing contact in a play)
    report[f"{version}_me_loose"] = model_exchange(path, 1e-8)

Path(out_file).write_text(json.dumps(report))
