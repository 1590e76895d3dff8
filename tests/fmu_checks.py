"""Runs the FMUs in the tools engineers use and prints what they saw as JSON.

Called by tests/fmu_python.rs, which compares the numbers with `plant`'s own solution:
fmpy validate, fmutool -check, fmpy simulations (CS and ME, FMI 3 and 2) of a free response
after an initial twist and of a drive-torque step, and OSP libcosim running the FMI 2 FMU.
"""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import fmpy
from fmpy.validation import validate_fmu

out = Path(sys.argv[1])
fmus = {"fmi3": out / "rigtwin-fmi3.fmu", "fmi2": out / "rigtwin-fmi2.fmu"}
report = {"validate": {}, "fmutool": {}, "free": {}, "step": {}}
fmutool = Path(sys.executable).parent / "fmutool"

for version, path in fmus.items():
    report["validate"][version] = [str(p) for p in validate_fmu(str(path))]
    run = subprocess.run([str(fmutool), "-input", str(path), "-check"], capture_output=True, text=True)
    report["fmutool"][version] = {"returncode": run.returncode, "output": run.stdout + run.stderr}

outputs = ["w_m2", "w_drive", "w_m3", "phi_drive", "T_short", "T_long"]
for version, path in fmus.items():
    for kind, fmi_type in (("cs", "CoSimulation"), ("me", "ModelExchange")):
        key = f"{version}_{kind}"
        # free response after an initial twist of the drive: 4 s at 1 kHz (ME: CVode at rtol 1e-12,
        # so the importer's integrator stays below the 1e-6 the step is held to)
        free = fmpy.simulate_fmu(str(path), fmi_type=fmi_type, stop_time=4.0, output_interval=1e-3,
                                 relative_tolerance=1e-12, start_values={"phi_drive": 0.01}, output=outputs)
        report["free"][key] = {"time": free["time"].tolist(), "w_drive": free["w_drive"].tolist()}
        # a 10 Nm drive-torque step from rest, 1 s
        step = fmpy.simulate_fmu(str(path), fmi_type=fmi_type, stop_time=1.0, output_interval=1e-3,
                                 relative_tolerance=1e-12, start_values={"M_drive": 10.0}, output=outputs)
        report["step"][key] = {name: step[name].tolist() for name in ["time"] + outputs}

# OSP libcosim runs the FMI 2 FMU: initial twist, 1 ms steps to 0.5 s
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimSlave import CosimLocalSlave
from libcosimpy.CosimObserver import CosimObserver

execution = CosimExecution.from_step_size(step_size=int(1e6))  # nanoseconds
slave = execution.add_local_slave(CosimLocalSlave(fmu_path=str(fmus["fmi2"]), instance_name="rig"))
variables = {v.name.decode() if isinstance(v.name, bytes) else v.name: v.reference for v in execution.slave_variables(slave)}
execution.real_initial_value(slave, variables["phi_drive"], 0.01)
observer = CosimObserver.create_last_value()
execution.add_observer(observer)
ok = execution.simulate_until(target_time=int(0.5e9))
values = observer.last_real_values(slave, [variables["w_drive"], variables["phi_drive"]])
report["libcosim"] = {"ok": bool(ok), "w_drive": values[0], "phi_drive": values[1], "time_s": 0.5}

(out / "report.json").write_text(json.dumps(report))
