//! `rigtwin fmu`: the two .fmu archives (FMI 3.0 and FMI 2.0, co-simulation and model
//! exchange) from the shared library of the `fmu` crate and a parameter set.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::files::{Outputs, Target};
use plant::Rig;
use rigtwin_fmu::{describe, FmuParams, RigPlant, Version, MODEL_IDENTIFIER, PARAMS_RESOURCE};

/// The FMU's shared library for this platform, built by build.rs (the `fmu` crate, profile
/// `fmu`: optimised and stripped) and carried inside the `rigtwin` binary.
static EMBEDDED_LIBRARY: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/rigtwin_fmu_library"));

/// The FMI platform folders of this machine: (FMI 3, FMI 2).
pub fn platform_folders() -> anyhow::Result<(&'static str, &'static str)> {
    match (std::env::consts::ARCH, std::env::consts::OS) {
        ("x86_64", "linux") => Ok(("x86_64-linux", "linux64")),
        ("aarch64", "linux") => Ok(("aarch64-linux", "linux64")),
        ("x86_64", "windows") => Ok(("x86_64-windows", "win64")),
        ("x86_64", "macos") => Ok(("x86_64-darwin", "darwin64")),
        ("aarch64", "macos") => Ok(("aarch64-darwin", "darwin64")),
        (a, o) => anyhow::bail!("no FMI platform folder is defined for {a}/{o}"),
    }
}

/// The shared library the FMUs carry: the file `RIGTWIN_FMU_LIB` names if it is set (e.g. a
/// debug build of the `fmu` crate), else the one inside this binary.
pub fn library() -> anyhow::Result<std::borrow::Cow<'static, [u8]>> {
    match std::env::var_os("RIGTWIN_FMU_LIB") {
        Some(p) => {
            let p = PathBuf::from(p);
            let bytes = std::fs::read(&p).map_err(|e| anyhow::anyhow!("RIGTWIN_FMU_LIB={}: {e}", p.display()))?;
            Ok(bytes.into())
        }
        None => Ok(EMBEDDED_LIBRARY.into()),
    }
}

/// The FMU parameter set of a rig: its reduced model and variant, its drive-path effects, and
/// its bearing block if it describes one.
pub fn params_of_rig(rig: &Rig) -> anyhow::Result<FmuParams> {
    rig.effects.validate().map_err(|e| anyhow::anyhow!("{}: {e}", rig.name))?;
    Ok(FmuParams::of_rig(RigPlant {
        powertrain: rig.model.clone(),
        variant: rig.variant,
        bearing: rig.bearing.clone(),
        effects: rig.effects,
    }))
}

/// The FMU parameter set of a file given to `--params` (`modelfile::read`): a drive model
/// (`kind = "drive_model"`, as `rigtwin diagnose --write-model` writes it for a drive test), a
/// `drive_test` bundle's declared model, or a rig file (any other file: the paper rig's
/// structure with its values).
pub fn params_of_file(file: &Path) -> anyhow::Result<FmuParams> {
    params_of_model(&modelfile::read(file)?.model)
}

/// The FMU parameter set of a model read from a file.
pub fn params_of_model(model: &modelfile::Model) -> anyhow::Result<FmuParams> {
    match model {
        modelfile::Model::Drive(drive) => Ok(FmuParams::of_drive(drive.clone())),
        modelfile::Model::Rig(rig) => params_of_rig(rig),
    }
}

/// Claims the two modelDescription.xml files `--descriptions DIR` writes: `DIR/fmi3/` and
/// `DIR/fmi2/` (created if missing).
pub fn description_targets(outs: &mut Outputs, dir: &Path) -> anyhow::Result<[Target; 2]> {
    let [fmi3] = outs.in_folder(&dir.join("fmi3"), "--descriptions", ["modelDescription.xml"])?;
    let [fmi2] = outs.in_folder(&dir.join("fmi2"), "--descriptions", ["modelDescription.xml"])?;
    Ok([fmi3, fmi2])
}

/// Writes both modelDescription.xml files (FMI 3, FMI 2) to their checked targets.
pub fn write_descriptions(p: &FmuParams, targets: &[Target; 2]) -> anyhow::Result<()> {
    for (version, target) in [Version::Fmi3, Version::Fmi2].into_iter().zip(targets) {
        crate::files::write(target, describe(p, version).as_bytes())?;
    }
    Ok(())
}

/// The .fmu archive of parameter set `p` for `version`.
pub fn archive(p: &FmuParams, lib: &[u8], version: Version) -> anyhow::Result<Vec<u8>> {
    let (p3, p2) = platform_folders()?;
    let platform = if version == Version::Fmi3 { p3 } else { p2 };
    let params_json = serde_json::to_vec_pretty(p)?;
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut zip = zip::ZipWriter::new(&mut buf);
        let opts = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
        zip.start_file("modelDescription.xml", opts)?;
        zip.write_all(describe(p, version).as_bytes())?;
        zip.start_file(format!("binaries/{platform}/{MODEL_IDENTIFIER}{}", std::env::consts::DLL_SUFFIX), opts)?;
        zip.write_all(lib)?;
        zip.start_file(format!("resources/{PARAMS_RESOURCE}"), opts)?;
        zip.write_all(&params_json)?;
        zip.finish()?;
    }
    Ok(buf.into_inner())
}

/// The file names of the FMUs `rigtwin fmu` writes (FMI 3, FMI 2): `rigtwin-fmi3.fmu` and
/// `rigtwin-fmi2.fmu`, or `rigtwin-mpc-fmi3.fmu` and `rigtwin-mpc-fmi2.fmu` for the controller.
pub fn fmu_names(controller: bool) -> [&'static str; 2] {
    if controller {
        ["rigtwin-mpc-fmi3.fmu", "rigtwin-mpc-fmi2.fmu"]
    } else {
        ["rigtwin-fmi3.fmu", "rigtwin-fmi2.fmu"]
    }
}

/// The file name of the closed loop's SSP archive.
pub const SSP_NAME: &str = "rigtwin-closed-loop.ssp";

/// Writes the FMI 3 and FMI 2 FMUs of `p` to their checked targets (see [`fmu_names`]).
pub fn package(p: &FmuParams, lib: &[u8], targets: &[Target; 2]) -> anyhow::Result<()> {
    // the parameters must describe a model before anything is written
    rigtwin_fmu::check(p).map_err(|e| anyhow::anyhow!("the parameter set does not describe a model: {e}"))?;
    let archives = [archive(p, lib, Version::Fmi3)?, archive(p, lib, Version::Fmi2)?];
    for (bytes, target) in archives.iter().zip(targets) {
        crate::files::write(target, bytes)?;
    }
    Ok(())
}

/// The closed loop's connections, each (from element, its connector, to element, its connector):
/// every measurement from the plant's output of that name to the controller's input, every
/// command from the controller's output to the plant's input of that name — the one description
/// both `rigtwin-closed-loop.ssp` and the tests' masters use. Refused when the plant lacks one
/// of the controller's signals.
pub fn loop_connections(plant: &FmuParams, controller: &FmuParams) -> anyhow::Result<Vec<[String; 4]>> {
    let spec = controller.controller.as_ref().ok_or_else(|| anyhow::anyhow!("the second FMU is not a controller"))?;
    if plant.controller.is_some() {
        anyhow::bail!("the plant is a controller FMU");
    }
    let ports = spec.ports(controller).map_err(|e| anyhow::anyhow!("the controller: {e}"))?;
    let table = rigtwin_fmu::table(plant);
    let has = |name: &str, causality: rigtwin_fmu::variables::Causality| {
        table.variables.iter().any(|v| v.name == name && v.causality == causality)
    };
    let mut connections = Vec::new();
    for q in &ports.inputs[..ports.measured] {
        if !has(&q.name, rigtwin_fmu::variables::Causality::Output) {
            anyhow::bail!("the controller measures `{}`, which the plant does not output", q.name);
        }
        connections.push(["plant".into(), q.name.to_string(), "controller".into(), q.name.to_string()]);
    }
    for q in &ports.outputs {
        if !has(&q.name, rigtwin_fmu::variables::Causality::Input) {
            anyhow::bail!("the controller commands `{}`, which is not an input of the plant", q.name);
        }
        connections.push(["controller".into(), q.name.to_string(), "plant".into(), q.name.to_string()]);
    }
    Ok(connections)
}

/// Writes `rigtwin-closed-loop.ssp` ([`SSP_NAME`]) to `target`: an SSP 1.0 archive with the FMI 2
/// FMUs of the plant `plant` and the controller `controller` (as `resources/plant.fmu` and
/// `resources/controller.fmu`) and their connections ([`loop_connections`]), which OSP libcosim
/// and other SSP importers load as one system. The references (the rig's `w_m2_ref`,
/// `w_m3_ref`, `M_drive_ref`) stay open inputs of the controller.
pub fn closed_loop_ssp(plant: &FmuParams, controller: &FmuParams, lib: &[u8], target: &Target) -> anyhow::Result<()> {
    rigtwin_fmu::check(plant)
        .map_err(|e| anyhow::anyhow!("the plant's parameter set does not describe a model: {e}"))?;
    let connections = loop_connections(plant, controller)?;
    let mut ssd = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<ssd:SystemStructureDescription \
         xmlns:ssc=\"http://ssp-standard.org/SSP1/SystemStructureCommon\" \
         xmlns:ssd=\"http://ssp-standard.org/SSP1/SystemStructureDescription\" version=\"1.0\" \
         name=\"rigtwin closed loop\">\n  <ssd:System name=\"rig_with_mpc\">\n    <ssd:Elements>\n",
    );
    for name in ["plant", "controller"] {
        let kinds = connections.iter().map(|[from, c, _, _]| (c, if from == name { "output" } else { "input" }));
        ssd += &format!(
            "      <ssd:Component name=\"{name}\" source=\"resources/{name}.fmu\" type=\"application/x-fmu-sharedlibrary\">\n        <ssd:Connectors>\n"
        );
        for (c, kind) in kinds {
            ssd += &format!("          <ssd:Connector name=\"{c}\" kind=\"{kind}\"><ssc:Real/></ssd:Connector>\n");
        }
        ssd += "        </ssd:Connectors>\n      </ssd:Component>\n";
    }
    ssd += "    </ssd:Elements>\n    <ssd:Connections>\n";
    for [a, ac, b, bc] in &connections {
        ssd += &format!(
            "      <ssd:Connection startElement=\"{a}\" startConnector=\"{ac}\" endElement=\"{b}\" endConnector=\"{bc}\"/>\n"
        );
    }
    ssd += "    </ssd:Connections>\n  </ssd:System>\n  <ssd:DefaultExperiment startTime=\"0\" stopTime=\"1\"/>\n</ssd:SystemStructureDescription>\n";
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut zip = zip::ZipWriter::new(&mut buf);
        let opts = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
        zip.start_file("SystemStructure.ssd", opts)?;
        zip.write_all(ssd.as_bytes())?;
        for (name, p) in [("plant", plant), ("controller", controller)] {
            zip.start_file(format!("resources/{name}.fmu"), opts)?;
            zip.write_all(&archive(p, lib, Version::Fmi2)?)?;
        }
        zip.finish()?;
    }
    crate::files::write(target, buf.get_ref())
}
