"""Closes the loop of the plant FMU and the controller FMU in fmpy; writes the speeds as JSON.

    closed_loop_fmus.py PLANT_DIR CONTROLLER_DIR START.json STEPS OUT.json

PLANT_DIR holds rigtwin-fmi3.fmu / rigtwin-fmi2.fmu (`rigtwin fmu --params TRUE`),
CONTROLLER_DIR rigtwin-mpc-fmi3.fmu / rigtwin-mpc-fmi2.fmu (`rigtwin fmu --controller --params
MODEL`). START.json: {"plant": {name: start value}, "speed_radps": w, "step_at": k,
"step_nm": T, "controller": {setting: value}}. Both FMUs are validated (fmpy validate, fmutool -check), then run as
co-simulation FMUs by a small master that does what `rigtwin mpc` does in process, at every
1 ms communication point: read the plant's speeds, set them and the references (speeds w, drive
torque 0 then T from step k on) as the controller's inputs, read its torque commands
(direct feedthrough: the controller steps when they are read), set them as the plant's inputs,
step both. The connection is the one `tests/closed_loop.ssp` describes.
"""
import json
import subprocess
import sys
from pathlib import Path

import fmpy
from fmpy import read_model_description, extract
from fmpy.validation import validate_fmu

plant_dir, ctrl_dir, start_file, steps, out_file = sys.argv[1:6]
start = json.loads(Path(start_file).read_text())
steps = int(steps)
dt = 1e-3
fmutool = Path(sys.executable).parent / "fmutool"
report = {"validate": {}, "fmutool": {}}

MEASURED = ["w_m2", "w_drive", "w_m3"]
REFERENCES = ["w_m2_ref", "w_m3_ref", "M_drive_ref"]
COMMANDS = ["M_m2", "M_drive", "M_m3"]


def open_fmu(path, name):
    md = read_model_description(path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipped = extract(path)
    if md.fmiVersion.startswith("3"):
        from fmpy.fmi3 import FMU3Slave
        fmu = FMU3Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                        instanceName=name)
        fmu.instantiate()
        fmu.enterInitializationMode(startTime=0.0)
        get = lambda names: fmu.getFloat64([vr[n] for n in names])
        put = lambda names, values: fmu.setFloat64([vr[n] for n in names], list(values))
    else:
        from fmpy.fmi2 import FMU2Slave
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                        instanceName=name)
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        get = lambda names: fmu.getReal([vr[n] for n in names])
        put = lambda names, values: fmu.setReal([vr[n] for n in names], list(values))
    return fmu, get, put


for version in ("fmi3", "fmi2"):
    plant_path = str(Path(plant_dir) / f"rigtwin-{version}.fmu")
    ctrl_path = str(Path(ctrl_dir) / f"rigtwin-mpc-{version}.fmu")
    report["validate"][version] = [str(p) for p in validate_fmu(ctrl_path)]
    run = subprocess.run([str(fmutool), "-input", ctrl_path, "-check"], capture_output=True, text=True)
    report["fmutool"][version] = {"returncode": run.returncode, "output": run.stdout + run.stderr}

    plant, pget, pput = open_fmu(plant_path, "plant")
    ctrl, cget, cput = open_fmu(ctrl_path, "controller")
    names = list(start["plant"].keys())
    pput(names, [start["plant"][n] for n in names])
    settings = list(start.get("controller", {}).keys())
    cput(settings, [start["controller"][n] for n in settings])
    w = start["speed_radps"]
    speeds = pget(MEASURED)
    cput(MEASURED + REFERENCES, list(speeds) + [w, w, 0.0])
    plant.exitInitializationMode()
    ctrl.exitInitializationMode()
    rows = []
    t = 0.0
    for k in range(steps):
        speeds = pget(MEASURED)
        drive_ref = start["step_nm"] if k >= start["step_at"] else 0.0
        cput(MEASURED + REFERENCES, list(speeds) + [w, w, drive_ref])
        torques = cget(COMMANDS)
        pput(COMMANDS, torques)
        rows.append(list(speeds) + list(torques))
        plant.doStep(currentCommunicationPoint=t, communicationStepSize=dt)
        ctrl.doStep(currentCommunicationPoint=t, communicationStepSize=dt)
        t = (k + 1) * dt
    report[version] = rows
    for fmu in (plant, ctrl):
        fmu.terminate()
        fmu.freeInstance()

Path(out_file).write_text(json.dumps(report))
