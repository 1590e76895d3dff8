//! `rigtwin fmu`: the two .fmu archives (FMI 3.0 and FMI 2.0, co-simulation and model
//! exchange) from the shared library of the `fmu` crate and a parameter set.

use std::io::Write;
use std::path::{Path, PathBuf};

use plant::Rig;
use rigtwin_fmu::{describe, FmuParams, Version, MODEL_IDENTIFIER, PARAMS_RESOURCE};

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
/// its bearing if it describes one (else the identified squeeze-film damper of the default).
pub fn params_of_rig(rig: &Rig) -> anyhow::Result<FmuParams> {
    rig.effects.validate().map_err(|e| anyhow::anyhow!("{}: {e}", rig.name))?;
    let default = FmuParams::default();
    Ok(FmuParams {
        powertrain: rig.model.clone(),
        variant: rig.variant,
        bearing: rig.bearing.clone().unwrap_or(default.bearing),
        effects: rig.effects,
        drive: None,
        controller: None,
    })
}

/// The FMU parameter set of a file given to `--params`: a drive model (`kind = "drive_model"`,
/// as `rigtwin diagnose --write-model` writes it for a drive test), a `drive_test` bundle's
/// declared model, or a rig file (any other file: the paper rig's structure with its values).
pub fn params_of_file(file: &Path) -> anyhow::Result<FmuParams> {
    let text = crate::files::read_text(file).map_err(|e| anyhow::anyhow!("{}: {}", file.display(), e.message))?;
    let kind = toml::from_str::<toml::Table>(&text)
        .ok()
        .and_then(|t| t.get("kind").and_then(|k| k.as_str()).map(str::to_string));
    match kind.as_deref() {
        Some("drive_model" | "drive_test") => {
            let drive = crate::bundle::load_drive_model(file)?;
            Ok(FmuParams { drive: Some(drive), ..FmuParams::default() })
        }
        _ => params_of_rig(&crate::rigfile::load_rig(file)?),
    }
}

/// Writes both modelDescription.xml files into `dir/fmi3/` and `dir/fmi2/`.
pub fn write_descriptions(p: &FmuParams, dir: &Path) -> anyhow::Result<()> {
    for (version, sub) in [(Version::Fmi3, "fmi3"), (Version::Fmi2, "fmi2")] {
        let d = crate::files::output_dir(&dir.join(sub), "--descriptions")?;
        crate::files::write_new(&d.join("modelDescription.xml"), "--descriptions", describe(p, version).as_bytes())?;
    }
    Ok(())
}

/// Writes `rigtwin-fmi3.fmu` and `rigtwin-fmi2.fmu` into `out` (`rigtwin-mpc-fmi3.fmu` and
/// `rigtwin-mpc-fmi2.fmu` for the controller); returns their paths.
pub fn package(p: &FmuParams, lib: &[u8], out: &Path) -> anyhow::Result<[PathBuf; 2]> {
    // the parameters must describe a model before anything is written
    rigtwin_fmu::check(p).map_err(|e| anyhow::anyhow!("the parameter set does not describe a model: {e}"))?;
    let (p3, p2) = platform_folders()?;
    let dir = crate::files::output_dir(out, "--out")?;
    let params_json = serde_json::to_vec_pretty(p)?;
    let mut written = Vec::new();
    let stem = if p.controller.is_some() { "rigtwin-mpc" } else { "rigtwin" };
    for (version, platform, name) in
        [(Version::Fmi3, p3, format!("{stem}-fmi3.fmu")), (Version::Fmi2, p2, format!("{stem}-fmi2.fmu"))]
    {
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
        crate::files::write_new(&dir.join(&name), "--out", buf.get_ref())?;
        written.push(out.join(&name));
    }
    Ok([written.remove(0), written.remove(0)])
}
