//! # modelfile — reading rigtwin's model files
//!
//! One place reads a model file, once: the paper rig's file (`rigs/paper.toml`, a
//! `torsional_sweep` bundle's TOML), a `kind = "drive_model"` file or a `drive_test` bundle's
//! declared model, and the `[mpc]` section any of them may carry. The C library and the FMUs'
//! tools need nothing else of the `rigtwin` package to read a model: this crate depends on
//! `plant` (the models), `mpc` (the controller's section), serde and toml.
#![warn(missing_docs)]

pub mod drive;
pub mod input;
pub mod rig;

use std::path::{Path, PathBuf};

/// A model file that cannot be used: which file, and what is wrong where.
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", file.display())]
pub struct ModelFileError {
    /// The file.
    pub file: PathBuf,
    /// What is wrong, naming the line (syntax, unknown or missing keys) or the key (values).
    pub message: String,
}

impl From<input::InputError> for ModelFileError {
    fn from(e: input::InputError) -> Self {
        ModelFileError { file: e.path, message: e.message }
    }
}

/// The model a file describes.
#[derive(Debug, Clone)]
pub enum Model {
    /// The paper rig's structure with the file's values, effects, chain and bearing block.
    Rig(Box<plant::Rig>),
    /// A drive model (any line of bodies, couplings, inputs and effects).
    Drive(plant::DriveModel),
}

impl Model {
    /// The model a controller of it is designed on.
    pub fn design(&self) -> mpc::Design<'_> {
        match self {
            Model::Rig(rig) => mpc::Design::Rig { rig: &rig.model, variant: rig.variant, effects: &rig.effects },
            Model::Drive(m) => mpc::Design::Drive(m),
        }
    }
}

/// A model file, read.
#[derive(Debug, Clone)]
pub struct ModelFile {
    /// The model.
    pub model: Model,
    /// Its `[mpc]` section (empty when it has none).
    pub mpc: mpc::MpcSection,
    /// Its `kind` key (`drive_model`, `drive_test`, `torsional_sweep`; none in a plain rig file).
    pub kind: Option<String>,
}

/// Reads the model file `file`: a drive model when its `kind` is `drive_model` or
/// `drive_test`, else a rig file.
pub fn read(file: &Path) -> Result<ModelFile, ModelFileError> {
    let text = input::read_text(file)?;
    parse(&text, file)
}

/// Parses the text of a model file (see [`read`]); `file` names it in errors.
pub fn parse(text: &str, file: &Path) -> Result<ModelFile, ModelFileError> {
    let table = toml::from_str::<toml::Table>(text).ok();
    let kind = table.as_ref().and_then(|t| t.get("kind")).and_then(|k| k.as_str());
    let model = match kind {
        Some("drive_model" | "drive_test") => Model::Drive(drive::parse_drive_model(text, file)?),
        _ => Model::Rig(Box::new(rig::parse_rig(text, file)?)),
    };
    let mpc = match table.as_ref().and_then(|t| t.get("mpc")) {
        None => mpc::MpcSection::default(),
        Some(v) => v
            .clone()
            .try_into()
            .map_err(|e| ModelFileError { file: file.to_path_buf(), message: format!("[mpc]: {e}") })?,
    };
    Ok(ModelFile { model, mpc, kind: kind.map(str::to_string) })
}
