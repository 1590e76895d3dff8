"""Closes the loop of the plant FMU and the controller FMU in fmpy; writes the speeds as JSON.

    closed_loop_fmus.py PLANT_DIR CONTROLLER_DIR START.json STEPS OUT.json [LOOP.ssp]

PLANT_DIR holds rigtwin-fmi3.fmu / rigtwin-fmi2.fmu (`rigtwin fmu --params TRUE`),
CONTROLLER_DIR rigtwin-mpc-fmi3.fmu / rigtwin-mpc-fmi2.fmu (`rigtwin fmu --controller --params
MODEL`). START.json: {"plant": {name: start value}, "references": {name: value}, "step_at": k,
"step": {reference: value from step k on}, "controller": {setting: value}}. Both FMUs are validated (fmpy validate, fmutool -check), then run as
co-simulation FMUs by a small master that does what `rigtwin mpc` does in process, at every
1 ms communication point: read the plant's measured outputs, set them and the references (those
of "references", then "step"'s from step k on) as the controller's inputs, read its commands
(direct feedthrough: the controller steps when they are read), set them as the plant's inputs,
step both (Gauss-Seidel: no delay in the loop); the connections are read from LOOP.ssp when it
is given. With LOOP.ssp (`rigtwin fmu --controller`
writes rigtwin-closed-loop.ssp: both FMI 2 FMUs and their connections), OSP libcosim loads the
system from it and runs it with its fixed-step (Jacobi) master: every FMU steps on the others'
outputs of the point before, so the plant gets the controller's command one sample late; the
references and the start values are set as above, the reference step by an override
manipulator.
"""
import json
import subprocess
import sys
from pathlib import Path

import fmpy
from fmpy import read_model_description, extract
from fmpy.validation import validate_fmu

plant_dir, ctrl_dir, start_file, steps, out_file = sys.argv[1:6]
ssp = sys.argv[6] if len(sys.argv) > 6 else None
start = json.loads(Path(start_file).read_text())
steps = int(steps)
dt = 1e-3
fmutool = Path(sys.executable).parent / "fmutool"
report = {"validate": {}, "fmutool": {}}

REFERENCES = list(start["references"].keys())


def references(k):
    """The references at communication point k."""
    now = dict(start["references"])
    if k >= start["step_at"]:
        now.update(start["step"])
    return [now[n] for n in REFERENCES]


if ssp is not None:
    # the connections as the SSP describes them, the one description of the loop
    import xml.etree.ElementTree as ET
    import zipfile
    ns = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription"}
    root = ET.fromstring(zipfile.ZipFile(ssp).read("SystemStructure.ssd"))
    links = [(c.get("startElement"), c.get("startConnector"), c.get("endElement"), c.get("endConnector"))
             for c in root.iter("{%s}Connection" % ns["ssd"])]
else:
    links = [("plant", n, "controller", n) for n in ["w_m2", "w_drive", "w_m3"]] + \
            [("controller", n, "plant", n) for n in ["M_m2", "M_drive", "M_m3"]]
TO_CONTROLLER = [(a, b) for (e, a, _, b) in links if e == "plant"]
TO_PLANT = [(a, b) for (e, a, _, b) in links if e == "controller"]
MEASURED = [a for a, _ in TO_CONTROLLER]
COMMANDS = [a for a, _ in TO_PLANT]
assert MEASURED and COMMANDS, links


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
    speeds = pget(MEASURED)
    cput([b for _, b in TO_CONTROLLER] + REFERENCES, list(speeds) + references(0))
    plant.exitInitializationMode()
    ctrl.exitInitializationMode()
    rows = []
    t = 0.0
    for k in range(steps):
        speeds = pget(MEASURED)
        cput([b for _, b in TO_CONTROLLER] + REFERENCES, list(speeds) + references(k))
        torques = cget(COMMANDS)
        pput([b for _, b in TO_PLANT], torques)
        rows.append(list(speeds) + list(torques))
        plant.doStep(currentCommunicationPoint=t, communicationStepSize=dt)
        ctrl.doStep(currentCommunicationPoint=t, communicationStepSize=dt)
        t = (k + 1) * dt
    report[version] = rows
    for fmu in (plant, ctrl):
        fmu.terminate()
        fmu.freeInstance()

if ssp is not None:
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver

    ex = CosimExecution.from_ssp_file(ssp_path=ssp, step_size=int(round(dt * 1e9)))
    index = {s.name.decode(): s.index for s in ex.slave_infos()}
    refs = {i: {v.name.decode(): v.reference for v in ex.slave_variables(i)} for i in index.values()}
    plant, ctrl = index["plant"], index["controller"]
    for name, value in start["plant"].items():
        ex.real_initial_value(plant, refs[plant][name], value)
    for a, b in TO_CONTROLLER:
        ex.real_initial_value(ctrl, refs[ctrl][b], start["plant"].get(a, 0.0))
    for name, value in list(start["references"].items()) + list(start.get("controller", {}).items()):
        ex.real_initial_value(ctrl, refs[ctrl][name], value)
    observer = CosimObserver.create_last_value()
    ex.add_observer(observer)
    override = CosimManipulator.create_override()
    ex.add_manipulator(override)
    rows = []
    speeds = [start["plant"].get(n, 0.0) for n in MEASURED]
    for k in range(steps):
        if k == start["step_at"]:
            stepped = list(start["step"].items())
            override.slave_real_values(ctrl, [refs[ctrl][n] for n, _ in stepped], [v for _, v in stepped])
        ex.step()
        applied = observer.last_real_values(plant, [refs[plant][n] for n in COMMANDS])
        rows.append(list(speeds) + list(applied))
        speeds = observer.last_real_values(plant, [refs[plant][n] for n in MEASURED])
    report["libcosim"] = rows

Path(out_file).write_text(json.dumps(report))
