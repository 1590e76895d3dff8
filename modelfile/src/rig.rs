//! The rig description file (TOML): the reduced model under `[model]` — the same keys as a
//! measurement bundle's `[model]` section, so a `torsional_sweep` bundle's TOML is itself a rig
//! file (its `kind` and `data` keys are accepted and the data not read) — and optionally the full chain under `[chain]`, as
//! J/c tables or shaft-segment geometry, with the additional spring and where it goes.
//!
//! ```toml
//! name = "my rig"
//! variant = "V1"                 # default variant for the commands: V1, V2, V3 or V4
//!
//! [model]                        # SI: kg m², Nm/rad, Nm s/rad
//! j_m2 = 0.9148
//! j_drive = 0.529
//! j_m3 = 0.9148
//! c_short = 1479.0
//! # c_long = 1150.33             # default: c_long_ratio · c_short, c_long_ratio = 7/9 (eq. 13)
//! c_delta = 64330.0
//! j_m2_delta = 0.9222            # optional: M2-side inertia with the spring mounted (J1Δ)
//! j_m3_delta = 0.9225            # optional: M3-side inertia with the spring mounted (J17Δ)
//! d_short = 0.0
//! d_long = 0.0
//! load_drag = 0.0
//!
//! [chain]                        # optional: bodies from M2 to M3
//! drive = 8                      # 1-based positions in `bodies`
//! short_shaft = 7
//! long_shaft = 9
//! bodies = [
//!   { name = "rotor M2", j_kgm2 = 0.850, c_Nm_per_rad = 8.72e6 },
//!   # or geometry (eqs. 1–6): outer_diameter_m, inner_diameter_m (0), length_m,
//!   # shear_modulus_Pa (81e9), density_kg_per_m3 (7850)
//!   { name = "shaft", outer_diameter_m = 0.03, length_m = 0.4 },
//!   ...
//! ]
//! [chain.additional_spring]      # optional: needed for variants V2-V4 of the chain
//! left_after = 5                 # inserted between bodies 5 and 6 (M2 side)
//! right_after = 10               # inserted, mirrored, between bodies 10 and 11 (M3 side)
//! bodies = [ ... ]
//!
//! [bearing.element]              # optional: a bearing block the FMU exports (N/m, N s/m, kg)
//! K_N_per_m = [[4.0e5, 0.0], [0.0, 5.0e5]]
//! C_Ns_per_m = [[2600.0, 0.0], [0.0, 2800.0]]
//! M_kg = [[5.4, 0.0], [0.0, 5.9]]
//! [bearing.support]              # k_x, k_y, c_x, c_y, m_x, m_y as in a bearing_shake bundle
//!
//! [effects]                      # optional: drive-path effects (`rigtwin diagnose --write-model`)
//! time_delay_s = 0.0             # dead time of the drive torque
//! actuator_lag_s = 0.0           # first-order lag of the drive torque
//! backlash_rad = 0.0             # total play of each side shaft
//! compliance_stiffness_nm_per_rad = 0.0   # motor-cage compliance inside the drive (0: rigid)
//! compliance_motor_fraction = 0.5         # share of j_drive on the motor side
//! coulomb_friction_nm = [0.0, 0.0, 0.0]   # Coulomb friction of M2, the drive, M3
//! friction_smoothing_radps = 0.05         # T = T_c w/sqrt(w^2 + v_s^2)
//!
//! [bending]                      # optional (section 2.5): the shaft line carrying the spring
//! bearing_a_m = 0.0              # as a beam on two bearings; beyond them it overhangs
//! bearing_b_m = 0.08
//! segments = [ { length_m = 0.08, outer_diameter_m = 0.06 },   # inner_diameter_m (0),
//!              { length_m = 0.25, outer_diameter_m = 0.02 } ]  # density_kg_per_m3, youngs_modulus_Pa
//! ```

use serde::Deserialize;
use std::path::Path;

use crate::ModelFileError;

use plant::segment::{STEEL_DENSITY_KG_PER_M3, STEEL_SHEAR_MODULUS_PA};
use plant::{bodies_from_segments, AdditionalSpring, Body, Rig, RigChain, RigParams, Segment, Variant};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RigFile {
    name: Option<String>,
    /// Present when the file is a measurement bundle (checked before).
    #[allow(dead_code)]
    kind: Option<String>,
    /// A bundle's data file; not read here.
    #[allow(dead_code)]
    data: Option<String>,
    /// A bundle's map of its columns to the recorded channels and its time base; not read here.
    #[allow(dead_code)]
    columns: Option<toml::Value>,
    #[allow(dead_code)]
    time: Option<String>,
    #[allow(dead_code)]
    sample_rate_hz: Option<f64>,
    #[serde(default)]
    variant: Variant,
    model: RigParams,
    chain: Option<ChainFile>,
    bending: Option<BendingFile>,
    bearing: Option<plant::BearingModel>,
    #[serde(default)]
    effects: plant::rig::DriveEffects,
    /// The controller's section, read by [`crate::read`].
    #[allow(dead_code)]
    mpc: Option<toml::Value>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BendingFile {
    bearing_a_m: f64,
    bearing_b_m: f64,
    segments: Vec<BeamSegmentFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BeamSegmentFile {
    length_m: f64,
    outer_diameter_m: f64,
    #[serde(default)]
    inner_diameter_m: f64,
    density_kg_per_m3: Option<f64>,
    #[serde(rename = "youngs_modulus_Pa")]
    youngs_modulus_pa: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ChainFile {
    drive: usize,
    short_shaft: usize,
    long_shaft: usize,
    bodies: Vec<BodyFile>,
    additional_spring: Option<SpringFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SpringFile {
    left_after: usize,
    right_after: usize,
    bodies: Vec<BodyFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BodyFile {
    name: Option<String>,
    j_kgm2: Option<f64>,
    #[serde(rename = "c_Nm_per_rad")]
    c_nm_per_rad: Option<f64>,
    outer_diameter_m: Option<f64>,
    inner_diameter_m: Option<f64>,
    length_m: Option<f64>,
    #[serde(rename = "shear_modulus_Pa")]
    shear_modulus_pa: Option<f64>,
    density_kg_per_m3: Option<f64>,
}

/// Either a tabulated body or a segment's geometry.
enum Entry {
    Table(Body),
    Geometry(String, Segment),
}

impl BodyFile {
    fn entry(self, key: &str) -> Result<Entry, String> {
        let name = self.name.unwrap_or_else(|| key.to_string());
        let geometry = self.outer_diameter_m.is_some()
            || self.length_m.is_some()
            || self.inner_diameter_m.is_some()
            || self.shear_modulus_pa.is_some()
            || self.density_kg_per_m3.is_some();
        match (self.j_kgm2, self.c_nm_per_rad, geometry) {
            (Some(j), Some(c), false) => Ok(Entry::Table(Body { name, inertia_kgm2: j, stiffness_nm_per_rad: c })),
            (None, None, true) => {
                let need = |v: Option<f64>, k: &str| v.ok_or_else(|| format!("`{key}.{k}` is missing: a geometry body needs outer_diameter_m and length_m"));
                Ok(Entry::Geometry(
                    name,
                    Segment {
                        outer_diameter_m: need(self.outer_diameter_m, "outer_diameter_m")?,
                        inner_diameter_m: self.inner_diameter_m.unwrap_or(0.0),
                        length_m: need(self.length_m, "length_m")?,
                        shear_modulus_pa: self.shear_modulus_pa.unwrap_or(STEEL_SHEAR_MODULUS_PA),
                        density_kg_per_m3: self.density_kg_per_m3.unwrap_or(STEEL_DENSITY_KG_PER_M3),
                    },
                ))
            }
            (None, None, false) => Err(format!(
                "`{key}` describes no body: expected `j_kgm2` and `c_Nm_per_rad`, or the geometry `outer_diameter_m` and `length_m`"
            )),
            (Some(_), None, false) => Err(format!("`{key}.c_Nm_per_rad` is missing (the body gives `j_kgm2`)")),
            (None, Some(_), false) => Err(format!("`{key}.j_kgm2` is missing (the body gives `c_Nm_per_rad`)")),
            _ => Err(format!("`{key}` mixes `j_kgm2`/`c_Nm_per_rad` with geometry keys: give one or the other")),
        }
    }
}

/// Tabulated bodies as they are; each run of consecutive geometry bodies is one stepped shaft,
/// with the diameter-step correction (eqs. 4–6) between its segments.
fn bodies(list: Vec<BodyFile>, key: &str) -> Result<Vec<Body>, String> {
    let mut out = Vec::with_capacity(list.len());
    let mut run: Vec<(String, Segment)> = Vec::new();
    let mut run_start = 0;
    let flush = |run: &mut Vec<(String, Segment)>, start: usize, out: &mut Vec<Body>| -> Result<(), String> {
        if run.is_empty() {
            return Ok(());
        }
        let (names, segs): (Vec<String>, Vec<Segment>) = run.drain(..).unzip();
        let mut made = bodies_from_segments(&segs, &names, key, start).map_err(|e| e.to_string())?;
        out.append(&mut made);
        Ok(())
    };
    for (i, b) in list.into_iter().enumerate() {
        let k = format!("{key}[{}]", i + 1);
        match b.entry(&k)? {
            Entry::Table(body) => {
                flush(&mut run, run_start, &mut out)?;
                out.push(body);
            }
            Entry::Geometry(name, seg) => {
                if run.is_empty() {
                    run_start = i + 1;
                }
                run.push((name, seg));
            }
        }
    }
    flush(&mut run, run_start, &mut out)?;
    Ok(out)
}

/// Parses a rig description; `file` only names the source in errors.
pub fn parse_rig(text: &str, file: &Path) -> Result<Rig, ModelFileError> {
    let err = |message: String| ModelFileError { file: file.to_path_buf(), message };
    let toml_err = |e: toml::de::Error| err(e.to_string().trim_end().to_string());
    // A bundle of another kind would fail on its first foreign key; say what it is instead.
    #[derive(Deserialize)]
    struct Kind {
        kind: Option<String>,
    }
    let kind: Kind = toml::from_str(text).map_err(toml_err)?;
    if let Some(kind) = kind.kind.filter(|k| k != "torsional_sweep") {
        return Err(err(format!("`kind` = \"{kind}\": only a `torsional_sweep` bundle describes a torsional rig")));
    }
    let raw: RigFile = toml::from_str(text).map_err(toml_err)?;
    let chain = match raw.chain {
        None => None,
        Some(c) => Some(RigChain {
            bodies: bodies(c.bodies, "chain.bodies").map_err(err)?,
            drive: c.drive,
            short_shaft: c.short_shaft,
            long_shaft: c.long_shaft,
            additional_spring: match c.additional_spring {
                None => None,
                Some(s) => Some(AdditionalSpring {
                    bodies: bodies(s.bodies, "chain.additional_spring.bodies").map_err(err)?,
                    left_after: s.left_after,
                    right_after: s.right_after,
                }),
            },
        }),
    };
    let rig = Rig {
        name: raw.name.unwrap_or_else(|| file.display().to_string()),
        variant: raw.variant,
        model: raw.model,
        chain,
        bearing: raw.bearing,
        effects: raw.effects,
        bending: raw.bending.map(|b| plant::Beam {
            bearing_a_m: b.bearing_a_m,
            bearing_b_m: b.bearing_b_m,
            segments: b
                .segments
                .into_iter()
                .map(|s| plant::BeamSegment {
                    length_m: s.length_m,
                    outer_diameter_m: s.outer_diameter_m,
                    inner_diameter_m: s.inner_diameter_m,
                    density_kg_per_m3: s.density_kg_per_m3.unwrap_or(STEEL_DENSITY_KG_PER_M3),
                    youngs_modulus_pa: s.youngs_modulus_pa.unwrap_or(plant::bending::STEEL_YOUNGS_MODULUS_PA),
                })
                .collect(),
        }),
    };
    rig.validate().map_err(|e| err(e.to_string()))?;
    rig.effects.validate().map_err(|e| err(e.to_string()))?;
    Ok(rig)
}

/// Reads and parses a rig file.
pub fn load_rig(file: &Path) -> Result<Rig, ModelFileError> {
    let text =
        crate::input::read_text(file).map_err(|e| ModelFileError { file: file.to_path_buf(), message: e.message })?;
    parse_rig(&text, file)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Rig, String> {
        parse_rig(text, Path::new("rig.toml")).map_err(|e| e.to_string())
    }

    const MODEL: &str = "[model]\nj_m2 = 0.9\nj_drive = 0.5\nj_m3 = 0.9\nc_short = 1500.0\nc_delta = 6e4\n";

    #[test]
    fn minimal_model_only_rig() {
        let r = parse(MODEL).unwrap();
        assert_eq!(r.variant, Variant::V1);
        assert!((r.model.c_long() - 1500.0 * 7.0 / 9.0).abs() < 1e-9);
        assert!(r.chain.is_none());
    }

    #[test]
    fn geometry_bodies_become_chain_bodies() {
        let text = format!(
            "{MODEL}[chain]\ndrive = 3\nshort_shaft = 2\nlong_shaft = 4\nbodies = [\n\
             {{ j_kgm2 = 1.0, c_Nm_per_rad = 1e7 }},\n\
             {{ outer_diameter_m = 0.03, length_m = 0.4 }},\n\
             {{ j_kgm2 = 1.0, c_Nm_per_rad = 1e7 }},\n\
             {{ outer_diameter_m = 0.03, inner_diameter_m = 0.01, length_m = 0.5, shear_modulus_Pa = 80e9 }},\n\
             {{ j_kgm2 = 1.0, c_Nm_per_rad = 1e7 }}]\n"
        );
        let r = parse(&text).unwrap();
        let b = &r.chain.unwrap().bodies;
        let s = Segment::steel(0.03, 0.0, 0.4);
        assert!((b[1].stiffness_nm_per_rad - s.stiffness_nm_per_rad()).abs() < 1e-6);
        assert!((b[1].inertia_kgm2 - s.inertia_kgm2()).abs() < 1e-15);
    }
}
