//! Drive models: a `kind = "drive_model"` file or a `drive_test` bundle's declared model
//! (`../shared/DATA.md`): bodies and couplings, inputs, effects.

use serde::Deserialize;
use std::path::Path;

use crate::ModelFileError;

fn error(file: &Path, message: impl Into<String>) -> ModelFileError {
    ModelFileError { file: file.to_path_buf(), message: message.into() }
}

/// A body given by name or by 1-based position.
#[derive(Deserialize)]
#[serde(untagged)]
pub enum BodyRef {
    /// The body's name.
    Name(String),
    /// Its 1-based position in the line.
    Position(i64),
}

/// A drive model's `[model]` section: the line's bodies and couplings.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveModelFile {
    /// The bodies, in line order.
    pub bodies: Vec<plant::LineBody>,
    /// The couplings.
    #[serde(default)]
    pub couplings: Vec<plant::Coupling>,
}

/// An `[[inputs]]` entry: the body it acts on (a bundle's recording keys are not read here).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Input {
    #[allow(dead_code)]
    column: Option<String>,
    body: BodyRef,
    #[allow(dead_code)]
    unit: Option<String>,
    #[allow(dead_code)]
    gain: Option<f64>,
    #[allow(dead_code)]
    offset: Option<f64>,
}

/// The keys of a drive model that make the model (a bundle's other keys are not read here).
#[derive(Deserialize)]
struct ModelFile {
    kind: String,
    domain: plant::Domain,
    model: DriveModelFile,
    #[serde(default)]
    inputs: Vec<Input>,
    #[serde(default)]
    effects: Vec<plant::Effect>,
}

/// Reads a drive model: a `kind = "drive_model"` file (as `rigtwin diagnose --write-model`
/// writes it: `domain`, `[model]` bodies and couplings, `[[inputs]]` with `body` by name or
/// 1-based position, `[[effects]]` with 1-based `body`/`coupling`/`input`) or a `drive_test`
/// bundle's declared model (its data are not read).
pub fn load_drive_model(file: &Path) -> Result<plant::DriveModel, ModelFileError> {
    let text = crate::input::read_text(file).map_err(|e| error(file, e.message))?;
    parse_drive_model(&text, file)
}

/// Parses the text of a drive model file (see [`load_drive_model`]).
pub fn parse_drive_model(text: &str, file: &Path) -> Result<plant::DriveModel, ModelFileError> {
    let raw: ModelFile = toml::from_str(text).map_err(|e| error(file, e.to_string().trim_end().to_string()))?;
    if raw.kind != "drive_model" && raw.kind != "drive_test" {
        return Err(error(file, format!("`kind` = \"{}\": expected \"drive_model\" or \"drive_test\"", raw.kind)));
    }
    if raw.kind == "drive_test" && !raw.effects.is_empty() {
        return Err(error(file, "`effects` belong in a drive_model file, not in a drive_test bundle"));
    }
    let line = plant::Line { domain: raw.domain, bodies: raw.model.bodies, couplings: raw.model.couplings };
    let line = line.resolved().map_err(|e| error(file, e.to_string()))?;
    let n = line.bodies.len();
    let mut inputs = Vec::with_capacity(raw.inputs.len());
    for (k, i) in raw.inputs.iter().enumerate() {
        let at = match &i.body {
            BodyRef::Name(name) => line.body(name),
            BodyRef::Position(p) => usize::try_from(*p).ok().filter(|&p| (1..=n).contains(&p)).map(|p| p - 1),
        };
        inputs.push(at.ok_or_else(|| {
            let names: Vec<&str> = line.bodies.iter().map(|b| b.name.as_str()).collect();
            error(
                file,
                format!(
                    "`inputs[{}].body`: expected a body's name or its position 1..={n} (the bodies are {})",
                    k + 1,
                    names.join(", ")
                ),
            )
        })?);
    }
    let mut effects = Vec::with_capacity(raw.effects.len());
    for (k, e) in raw.effects.iter().enumerate() {
        let (i, what) = e.element_index();
        let i = i
            .checked_sub(1)
            .ok_or_else(|| error(file, format!("`effects[{}].{what}` = 0: positions are 1-based", k + 1)))?;
        effects.push(e.at_index(i));
    }
    let m = plant::DriveModel { line, inputs, effects };
    m.validate().map_err(|e| error(file, e.to_string()))?;
    // a compliance is written into the line as it is read: every consumer sees its two bodies
    let m = m.resolved().map_err(|e| error(file, e.to_string()))?.into_owned();
    Ok(m)
}
