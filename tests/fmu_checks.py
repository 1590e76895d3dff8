"""Runs the FMUs in the tools engineers use and prints what they saw as JSON.

Called by tests/fmu_python.rs, which compares the numbers with `plant`'s own solution:
fmpy validate, fmutool -check, fmpy simulations (CS and ME, FMI 3 and 2) of a free response
after an initial twist and of a drive-torque step, a step in model exchange at fmpy's default
solver settings, OSP libcosim running the FMI 2 FMU and Ecos running both.

Usage: fmu_checks.py DIR [EFFECTS_DIR [DRIVE_DIR]]; EFFECTS_DIR holds FMUs with drive-path
effects, which get the model-exchange check at default settings too; DRIVE_DIR the FMUs of a drive
model (motor - shaft - hub - gear - load), spun up by a constant 1 N.m on the motor for 20 s (to
angles of 10^4 rad) in co-simulation and in model exchange at fmpy's defaults: its couplings'
torques.
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
                                 relative_tolerance=1e-12, start_values={"twist": 0.02}, output=outputs)
        report["free"][key] = {"time": free["time"].tolist(), "w_drive": free["w_drive"].tolist()}
        # a 10 Nm drive-torque step from rest, 1 s
        step = fmpy.simulate_fmu(str(path), fmi_type=fmi_type, stop_time=1.0, output_interval=1e-3,
                                 relative_tolerance=1e-12, start_values={"M_drive": 10.0}, output=outputs)
        report["step"][key] = {name: step[name].tolist() for name in ["time"] + outputs}


def step_at_defaults(path, fmi_type):
    """A 10 Nm drive-torque step at 0.1 s, 4 s, output every 1 ms, at the importer's default
    solver settings (no tolerance given): the ring in w_m2."""
    signal = np.array([(0.0, 0.0), (0.1, 0.0), (0.1, 10.0), (4.0, 10.0)],
                      dtype=[("time", np.float64), ("M_drive", np.float64)])
    r = fmpy.simulate_fmu(str(path), fmi_type=fmi_type, stop_time=4.0, output_interval=1e-3,
                          input=signal, output=["w_m2"])
    return {"time": r["time"].tolist(), "w_m2": r["w_m2"].tolist()}


report["defaults"] = {}
sets = {"default": fmus}
if len(sys.argv) > 2:
    eff = Path(sys.argv[2])
    sets["effects"] = {"fmi3": eff / "rigtwin-fmi3.fmu", "fmi2": eff / "rigtwin-fmi2.fmu"}
for name, paths in sets.items():
    for version, path in paths.items():
        for kind, fmi_type in (("cs", "CoSimulation"), ("me", "ModelExchange")):
            report["defaults"][f"{name}_{version}_{kind}"] = step_at_defaults(path, fmi_type)

if len(sys.argv) > 3:
    drive = Path(sys.argv[3])
    spin = np.array([(0.0, 1.0), (20.0, 1.0)], dtype=[("time", np.float64), ("M_motor", np.float64)])
    report["drive_spin"] = {}
    for version in ("fmi3", "fmi2"):
        for kind, fmi_type in (("cs", "CoSimulation"), ("me", "ModelExchange")):
            r = fmpy.simulate_fmu(str(drive / f"rigtwin-{version}.fmu"), fmi_type=fmi_type, stop_time=20.0,
                                  output_interval=1e-3, input=spin,
                                  output=["T_coupling_1", "T_coupling_2", "phi_load"])
            report["drive_spin"][f"{version}_{kind}"] = {n: r[n].tolist() for n in ["T_coupling_1", "T_coupling_2", "phi_load"]}

# FMU state and directional derivatives through the C calls of a real importer
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

report["state"] = {}
report["derivative"] = {}
for version, path in fmus.items():
    md = read_model_description(str(path))
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    unzip = extract(str(path))
    cls = FMU3Slave if version == "fmi3" else FMU2Slave
    fmu = cls(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier, instanceName="state")
    fmu.instantiate()
    if version == "fmi3":
        get, set_ = (lambda names: fmu.getFloat64([vrs[n] for n in names])), (lambda names, v: fmu.setFloat64([vrs[n] for n in names], v))
        save, load, ser, deser = fmu.getFMUState, fmu.setFMUState, fmu.serializeFMUState, fmu.deserializeFMUState
        derivative = lambda u, k: fmu.getDirectionalDerivative([vrs[n] for n in u], [vrs[n] for n in k], [1.0] * len(k))
    else:
        fmu.setupExperiment(startTime=0.0)
        get, set_ = (lambda names: fmu.getReal([vrs[n] for n in names])), (lambda names, v: fmu.setReal([vrs[n] for n in names], v))
        save, load, ser, deser = fmu.getFMUstate, fmu.setFMUstate, fmu.serializeFMUstate, fmu.deSerializeFMUstate
        derivative = lambda u, k: fmu.getDirectionalDerivative([vrs[n] for n in u], [vrs[n] for n in k], [1.0] * len(k))
    set_(["twist"], [0.02])
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    t, h = 0.0, 1e-3
    for _ in range(100):
        fmu.doStep(t, h)
        t += h
    state = save()
    blob = ser(state)
    for _ in range(100):
        fmu.doStep(t, h)
        t += h
    first = get(["w_drive", "T_short"])
    load(state)
    t = 0.1
    for _ in range(100):
        fmu.doStep(t, h)
        t += h
    again = get(["w_drive", "T_short"])
    load(deser(blob))
    t = 0.1
    for _ in range(100):
        fmu.doStep(t, h)
        t += h
    from_bytes = get(["w_drive", "T_short"])
    report["state"][version] = {"first": list(first), "again": list(again), "from_bytes": list(from_bytes), "bytes": len(blob)}
    # ∂ der(w_drive) / ∂ twist, ∂ der(w_drive) / ∂ M_drive, ∂ T_short / ∂ twist, and the
    # computed angle ∂ phi_drive / ∂ (twist, phi_m2)
    report["derivative"][version] = {
        "dwdot_dtwist": list(derivative(["der(w_drive)"], ["twist"])),
        "dwdot_dM": list(derivative(["der(w_drive)"], ["M_drive"])),
        "dT_dtwist": list(derivative(["T_short"], ["twist"])),
        "dphi_dtwist": list(derivative(["phi_drive"], ["twist"])),
        "dphi_dphi_m2": list(derivative(["phi_drive"], ["phi_m2"])),
    }
    fmu.terminate()
    fmu.freeInstance()

# OSP libcosim runs the FMI 2 FMU: initial twist, 1 ms steps to 0.5 s
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimSlave import CosimLocalSlave
from libcosimpy.CosimObserver import CosimObserver

execution = CosimExecution.from_step_size(step_size=int(1e6))  # nanoseconds
slave = execution.add_local_slave(CosimLocalSlave(fmu_path=str(fmus["fmi2"]), instance_name="rig"))
variables = {v.name.decode() if isinstance(v.name, bytes) else v.name: v.reference for v in execution.slave_variables(slave)}
execution.real_initial_value(slave, variables["twist"], 0.02)
observer = CosimObserver.create_last_value()
execution.add_observer(observer)
ok = execution.simulate_until(target_time=int(0.5e9))
values = observer.last_real_values(slave, [variables["w_drive"], variables["phi_drive"]])
report["libcosim"] = {"ok": bool(ok), "w_drive": values[0], "phi_drive": values[1], "time_s": 0.5}

# Ecos (ecospy) runs both FMUs: the same initial twist, 1 ms steps to 0.5 s
from ecospy import EcosSimulation, EcosSimulationStructure

report["ecos"] = {}
for version, path in fmus.items():
    structure = EcosSimulationStructure()
    structure.add_model("rig", str(path))
    structure.add_parameter_set("initial", {"rig::twist": 0.02})
    with EcosSimulation(structure=structure, step_size=1e-3) as sim:
        sim.init(parameter_set="initial")
        sim.step_until(0.5)
        report["ecos"][version] = {"time_s": sim.get_time(), "w_drive": sim.get_real("rig::w_drive")}
        sim.terminate()

(out / "report.json").write_text(json.dumps(report))
