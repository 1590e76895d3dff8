//! What the commands report: serialisable views of `plant` results (JSON keys carry units) and
//! their human-readable form.

use serde::Serialize;
use std::fmt::Write as _;

use plant::{reduce, MechanicalModel, ModeKind, Rig, Variant};

/// Which torsional model a command works on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ModelKind {
    /// The full chain of bodies (Table A1, with Table A2 for V2–V4).
    Chain,
    /// The reduced three-mass smooth strand (eqs. 14, 18, 44, 45).
    Reduced,
    /// The three-mass model with the open differential (section 2.4).
    Differential,
}

/// A pole as `damp` reports it.
#[derive(Debug, Clone, Serialize)]
pub struct PoleReport {
    /// Real part of the eigenvalue, 1/s.
    pub re_per_s: f64,
    /// Imaginary part of the eigenvalue, rad/s.
    pub im_rad_per_s: f64,
    /// |λ|/2π, Hz.
    pub natural_hz: f64,
    /// |Im λ|/2π, Hz.
    pub damped_hz: f64,
    /// −Re λ/|λ| (null at the origin).
    pub damping_ratio: Option<f64>,
}

/// `rigtwin modal`.
#[derive(Debug, Clone, Serialize)]
pub struct ModalReport {
    /// Rig name.
    pub rig: String,
    /// Model analysed.
    pub model: ModelKind,
    /// Variant analysed.
    pub variant: Variant,
    /// Coordinate names, the order of every mode shape.
    pub dof_names: Vec<String>,
    /// Undamped natural frequencies, Hz, ascending.
    pub frequencies_hz: Vec<f64>,
    /// 0-based index of the shuffle mode in `frequencies_hz`, or null.
    pub shuffle_mode: Option<usize>,
    /// Character of each mode.
    pub mode_kinds: Vec<ModeKind>,
    /// Mode shapes (largest component +1), one per frequency.
    pub modes: Vec<Vec<f64>>,
    /// Poles of the damped system, when the model has damping.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub poles: Option<Vec<PoleReport>>,
}

/// `rigtwin reduce`.
#[derive(Debug, Clone, Serialize)]
pub struct ReduceReport {
    /// Rig name.
    pub rig: String,
    /// Variant reduced.
    pub variant: Variant,
    /// Masses before reduction.
    pub masses_before: usize,
    /// Names of the bodies the reduced masses stand for.
    pub names: Vec<String>,
    /// Reduced inertias, kg m².
    pub inertias_kgm2: Vec<f64>,
    /// Reduced coupling stiffnesses, Nm/rad.
    #[serde(rename = "stiffnesses_Nm_per_rad")]
    pub stiffnesses_nm_per_rad: Vec<f64>,
    /// Natural frequencies of the reduced chain, Hz.
    pub frequencies_hz: Vec<f64>,
    /// Natural frequencies of the full chain, Hz (the first as many as the reduced chain has).
    pub full_chain_frequencies_hz: Vec<f64>,
    /// Sum of inertias before = after, kg m².
    pub total_inertia_kgm2: f64,
    /// 0-based index of the shuffle mode of the reduced chain, or null.
    pub shuffle_mode: Option<usize>,
}

/// The model `kind` of `rig` in `variant`.
pub fn model(rig: &Rig, kind: ModelKind, variant: Variant) -> anyhow::Result<MechanicalModel> {
    Ok(match kind {
        ModelKind::Reduced => rig.model.three_mass(variant)?,
        ModelKind::Differential => rig.model.open_differential(variant)?,
        ModelKind::Chain => {
            let chain = rig.chain.as_ref().ok_or_else(|| {
                anyhow::anyhow!("rig `{}` has no [chain] section: the chain model needs the full chain", rig.name)
            })?;
            let (c, layout) = chain.chain(variant)?;
            MechanicalModel { layout: Some(layout), ..c.mechanical() }
        }
    })
}

/// Modal analysis of one model of the rig.
pub fn modal(rig: &Rig, kind: ModelKind, variant: Variant) -> anyhow::Result<ModalReport> {
    let m = model(rig, kind, variant)?;
    let modes = m.modes()?;
    let kinds = m.layout.map(|l| modes.kinds(&l)).unwrap_or_else(|| vec![ModeKind::Other; modes.frequencies_hz.len()]);
    let poles = if m.is_damped() { Some(pole_reports(&m)?) } else { None };
    Ok(ModalReport {
        rig: rig.name.clone(),
        model: kind,
        variant,
        dof_names: m.dof_names.clone(),
        shuffle_mode: kinds.iter().position(|&k| k == ModeKind::Shuffle),
        mode_kinds: kinds,
        frequencies_hz: modes.frequencies_hz,
        modes: modes.shapes.iter().map(|s| s.iter().copied().collect()).collect(),
        poles,
    })
}

/// The poles of a mechanical model's state space, one per conjugate pair.
fn pole_reports(m: &MechanicalModel) -> anyhow::Result<Vec<PoleReport>> {
    Ok(m.state_space(&[])?
        .damp()?
        .into_iter()
        .map(|p| PoleReport {
            re_per_s: p.eigenvalue.re,
            im_rad_per_s: p.eigenvalue.im,
            natural_hz: p.natural_hz,
            damped_hz: p.damped_hz,
            damping_ratio: p.damping_ratio,
        })
        .collect())
}

/// The elastic modes' shapes over the coordinates `names`, as one SVG panel (at most 8 modes).
fn plot_mode_shapes(
    target: &crate::files::Target,
    title: &str,
    names: &[String],
    frequencies_hz: &[f64],
    modes: &[Vec<f64>],
) -> anyhow::Result<()> {
    let series = frequencies_hz
        .iter()
        .zip(modes)
        .filter(|(f, _)| **f > 0.0)
        .take(8)
        .map(|(f, shape)| (format!("{f:.2} Hz"), shape.iter().enumerate().map(|(i, &v)| ((i + 1) as f64, v)).collect()))
        .collect();
    let panel = crate::plot::Panel {
        title: format!("mode shapes ({})", names.join(", ")),
        x_desc: "coordinate [position in the line]".into(),
        y_desc: "mode shape [largest component = 1]".into(),
        log_y: false,
        series,
    };
    crate::plot::lines(target, title, &[panel])
}

/// `rigtwin modal --params` of a drive model (`drive_model` file or `drive_test` bundle).
#[derive(Debug, Clone, Serialize)]
pub struct LineModalReport {
    /// The file.
    pub model: String,
    /// `rotational` or `translational`.
    pub domain: plant::Domain,
    /// Body names, the order of every mode shape.
    pub dof_names: Vec<String>,
    /// Undamped natural frequencies, Hz, ascending (rigid-body modes exactly 0).
    pub frequencies_hz: Vec<f64>,
    /// Each mode in words: `rigid body`, or which bodies swing against which.
    pub mode_kinds: Vec<String>,
    /// Mode shapes (largest component +1), one per frequency.
    pub modes: Vec<Vec<f64>>,
    /// Poles of the damped line (drag and coupling damping), one per conjugate pair.
    pub poles: Vec<PoleReport>,
    /// Effects of the model left out of the modal analysis (it is of the linear line: play
    /// closed, friction off, dead times and lags are no mechanics).
    pub left_out: Vec<String>,
}

/// Natural frequencies, damping ratios and mode shapes of any drive model's line.
pub fn modal_of_line(name: &str, m: &plant::DriveModel) -> anyhow::Result<LineModalReport> {
    let mech = m.line.model()?;
    let modes = mech.modes()?;
    let names: Vec<String> = m.line.bodies.iter().map(|b| b.name.clone()).collect();
    let poles = pole_reports(&mech)?;
    Ok(LineModalReport {
        model: name.to_string(),
        domain: m.line.domain,
        mode_kinds: modes
            .frequencies_hz
            .iter()
            .zip(&modes.shapes)
            .enumerate()
            .map(|(k, (&f, s))| mode_in_words(f, k > 0 && modes.frequencies_hz[k - 1] == 0.0, s, &names))
            .collect(),
        dof_names: names,
        frequencies_hz: modes.frequencies_hz,
        modes: modes.shapes.iter().map(|s| s.iter().copied().collect()).collect(),
        poles,
        left_out: m.effects_at(),
    })
}

/// A mode in words: `rigid body` at 0 Hz (the first: `plant::modal::modes` puts the motion of
/// every body together first), else the bodies that swing with the largest component against
/// those that swing against it (components beyond a third of the largest count) — at 0 Hz after
/// another (`after_free`), a free motion that twists nothing, as an open differential's outputs
/// turning against each other (the rig's "outputs in antiphase").
fn mode_in_words(f_hz: f64, after_free: bool, shape: &nalgebra::DVector<f64>, names: &[String]) -> String {
    if f_hz == 0.0 && !after_free {
        return "rigid body".into();
    }
    let with: Vec<&str> = shape.iter().zip(names).filter(|(v, _)| **v >= 1.0 / 3.0).map(|(_, n)| n.as_str()).collect();
    let against: Vec<&str> =
        shape.iter().zip(names).filter(|(v, _)| **v <= -1.0 / 3.0).map(|(_, n)| n.as_str()).collect();
    let swing = if against.is_empty() {
        format!("{} against the rest", with.join(", "))
    } else {
        format!("{} against {}", with.join(", "), against.join(", "))
    };
    if f_hz == 0.0 {
        format!("free: {swing}, no twist")
    } else {
        swing
    }
}

impl LineModalReport {
    /// Human-readable form.
    pub fn human(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "{} — {} line of {} bodies", self.model, words(&self.domain), self.dof_names.len());
        let _ = writeln!(s, "  mode   f [Hz]      shape [{}]", self.dof_names.join(", "));
        for (k, (f, shape)) in self.frequencies_hz.iter().zip(&self.modes).enumerate() {
            let v: Vec<String> = shape.iter().map(|x| format!("{x:+.3}")).collect();
            let _ = writeln!(s, "  f{:<4} {f:>8.3}   [{}]  {}", k + 1, v.join(", "), self.mode_kinds[k]);
        }
        let _ = writeln!(s, "  poles (damped):   natural [Hz]   damped [Hz]   damping ratio");
        for p in &self.poles {
            let z = p.damping_ratio.map_or("-".to_string(), |z| format!("{z:.4}"));
            let _ = writeln!(s, "                    {:>10.3}   {:>10.3}   {z:>12}", p.natural_hz, p.damped_hz);
        }
        for e in &self.left_out {
            let _ = writeln!(s, "  left out (not linear mechanics): {e}");
        }
        s
    }

    /// The mode shapes as a plot: each elastic mode's components over the bodies.
    pub fn plot(&self, target: &crate::files::Target) -> anyhow::Result<()> {
        let title = format!("rigtwin modal {}", self.model);
        plot_mode_shapes(target, &title, &self.dof_names, &self.frequencies_hz, &self.modes)
    }
}

impl ModalReport {
    /// The mode shapes as a plot: each elastic mode's components over the coordinates.
    pub fn plot(&self, target: &crate::files::Target) -> anyhow::Result<()> {
        let title = format!("rigtwin modal {}", self.rig);
        plot_mode_shapes(target, &title, &self.dof_names, &self.frequencies_hz, &self.modes)
    }
}

/// Rivin/Di reduction of the rig's chain.
pub fn reduction(rig: &Rig, variant: Variant, masses: usize) -> anyhow::Result<ReduceReport> {
    let rc = rig
        .chain
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("rig `{}` has no [chain] section: reduce needs the full chain", rig.name))?;
    let (full, layout) = rc.chain(variant)?;
    let r = reduce(&full, masses)?;
    let modes = r.chain.mechanical().modes()?;
    let full_f = full.mechanical().modes()?.frequencies_hz;
    let shuffle_mode = rc.reduced_layout(&layout, &r.chain).and_then(|l| modes.shuffle_mode(&l));
    Ok(ReduceReport {
        rig: rig.name.clone(),
        variant,
        masses_before: full.len(),
        names: r.chain.names.clone(),
        total_inertia_kgm2: r.chain.total_inertia_kgm2(),
        inertias_kgm2: r.chain.inertias_kgm2,
        stiffnesses_nm_per_rad: r.chain.stiffnesses_nm_per_rad,
        frequencies_hz: modes.frequencies_hz,
        full_chain_frequencies_hz: full_f.into_iter().take(masses).collect(),
        shuffle_mode,
    })
}

fn kind_word(k: ModeKind) -> &'static str {
    match k {
        ModeKind::RigidBody => "rigid body",
        ModeKind::OutputsAntiphase => "outputs in antiphase",
        ModeKind::Shuffle => "SHUFFLE: drive against both outputs, side shafts as nodes",
        ModeKind::Other => "",
    }
}

impl ModalReport {
    /// Human-readable form; `max_modes` limits the table (long chains have modes in the kHz).
    pub fn human(&self, max_modes: usize) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "{} — {} model, variant {}", self.rig, words(&self.model), self.variant);
        let shown = self.frequencies_hz.len().min(max_modes);
        let dofs = self.dof_names.len();
        let show_shape = dofs <= 6;
        if show_shape {
            let _ = writeln!(s, "  mode   f [Hz]      shape [{}]", self.dof_names.join(", "));
        } else {
            let _ = writeln!(s, "  mode   f [Hz]");
        }
        for i in 0..shown {
            let shape = if show_shape {
                format!("[{}]", self.modes[i].iter().map(|v| format!("{v:+.3}")).collect::<Vec<_>>().join(", "))
            } else {
                String::new()
            };
            let _ = writeln!(
                s,
                "  f{:<4} {:>9.3}   {shape}  {}",
                i + 1,
                self.frequencies_hz[i],
                kind_word(self.mode_kinds[i])
            );
        }
        if shown < self.frequencies_hz.len() {
            let _ = writeln!(
                s,
                "  ... {} more modes up to {:.1} Hz",
                self.frequencies_hz.len() - shown,
                self.frequencies_hz.last().unwrap()
            );
        }
        match self.shuffle_mode {
            Some(i) => {
                let _ = writeln!(s, "  shuffle mode: f{} = {:.3} Hz", i + 1, self.frequencies_hz[i]);
            }
            None => {
                let _ = writeln!(s, "  shuffle mode: none found");
            }
        }
        if let Some(poles) = &self.poles {
            let _ = writeln!(s, "  poles (damped):   natural [Hz]   damped [Hz]   damping ratio");
            for p in poles {
                let z = p.damping_ratio.map(|z| format!("{z:.4}")).unwrap_or_else(|| "-".into());
                let _ = writeln!(
                    s,
                    "    {:>+10.3}{:>+10.3}i {:>12.3} {:>13.3} {:>15}",
                    p.re_per_s, p.im_rad_per_s, p.natural_hz, p.damped_hz, z
                );
            }
        }
        s
    }
}

impl ReduceReport {
    /// Human-readable form.
    pub fn human(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{} — variant {}: {} masses reduced to {} (Rivin/Di)",
            self.rig,
            self.variant,
            self.masses_before,
            self.inertias_kgm2.len()
        );
        let _ = writeln!(s, "  mass  J [kg m^2]   stands for");
        for (i, (j, n)) in self.inertias_kgm2.iter().zip(&self.names).enumerate() {
            let _ = writeln!(s, "  {:<4}  {:>10.4}   {n}", i + 1, j);
        }
        let _ = writeln!(s, "  spring  c [Nm/rad]");
        for (i, c) in self.stiffnesses_nm_per_rad.iter().enumerate() {
            let _ = writeln!(s, "  {:<6}  {:>10.0}", i + 1, c);
        }
        let _ = writeln!(s, "  total inertia {:.4} kg m^2 (kept)", self.total_inertia_kgm2);
        let _ = writeln!(s, "  mode   reduced f [Hz]   full chain f [Hz]");
        for (i, (a, b)) in self.frequencies_hz.iter().zip(&self.full_chain_frequencies_hz).enumerate() {
            let tag = if Some(i) == self.shuffle_mode { "  shuffle" } else { "" };
            let _ = writeln!(s, "  f{:<4} {:>14.3} {:>19.3}{tag}", i + 1, a, b);
        }
        s
    }
}

/// `rigtwin run`: everything the rig's model says about its modes.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Rig name.
    pub rig: String,
    /// Variant of the chain, reduction and differential model.
    pub variant: Variant,
    /// Modal analysis of the full chain, when the rig has one.
    pub chain: Option<ModalReport>,
    /// The chain reduced to three masses, when the rig has one.
    pub reduction: Option<ReduceReport>,
    /// The three-mass smooth strand in every variant the rig can build.
    pub reduced_variants: Vec<ModalReport>,
    /// The open-differential model, the one FMU and MPC use.
    pub differential: ModalReport,
}

/// The main job's modal summary.
pub fn summary(rig: &Rig, variant: Variant) -> anyhow::Result<Summary> {
    let chain = match rig.chain {
        Some(_) => Some(modal(rig, ModelKind::Chain, variant)?),
        None => None,
    };
    let reduction = match rig.chain {
        Some(_) => Some(reduction(rig, variant, 3)?),
        None => None,
    };
    let variants: Vec<Variant> = if rig.model.c_delta > 0.0 { Variant::ALL.to_vec() } else { vec![Variant::V1] };
    let reduced_variants =
        variants.into_iter().map(|v| modal(rig, ModelKind::Reduced, v)).collect::<anyhow::Result<_>>()?;
    Ok(Summary {
        rig: rig.name.clone(),
        variant,
        chain,
        reduction,
        reduced_variants,
        differential: modal(rig, ModelKind::Differential, variant)?,
    })
}

impl Summary {
    /// Human-readable form.
    pub fn human(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "rigtwin modal summary — {}\n", self.rig);
        if let Some(c) = &self.chain {
            let _ = writeln!(s, "1. Full chain ({} masses, variant {})", c.dof_names.len(), c.variant);
            s += &c.human(4).lines().skip(1).map(|l| format!("{l}\n")).collect::<String>();
            s.push('\n');
        }
        if let Some(r) = &self.reduction {
            let _ = writeln!(s, "2. Reduction after Rivin/Di");
            s += &r.human().lines().skip(1).map(|l| format!("{l}\n")).collect::<String>();
            s.push('\n');
        }
        let _ = writeln!(s, "3. Three-mass smooth strand (eq. 14), shuffle frequency by variant");
        let _ = writeln!(s, "  variant   f2 [Hz]   f3 [Hz]   shuffle");
        for m in &self.reduced_variants {
            let f = &m.frequencies_hz;
            let sh = m.shuffle_mode.map(|i| format!("f{} = {:.3} Hz", i + 1, f[i])).unwrap_or_else(|| "none".into());
            let _ = writeln!(s, "  {:<8} {:>8.3}  {:>8.3}   {sh}", m.variant.to_string(), f[1], f[2]);
        }
        s.push('\n');
        let _ = writeln!(s, "4. Open differential (section 2.4), variant {}", self.differential.variant);
        s += &self.differential.human(3).lines().skip(1).map(|l| format!("{l}\n")).collect::<String>();
        s
    }
}

/// The version of rigtwin's JSON reports: `schema_version` in every document a command writes
/// (`docs/json.md` lists the documents); raised when a key is renamed or removed.
pub const JSON_SCHEMA_VERSION: u32 = 1;

/// A report as the JSON document a command writes: an object with `schema_version`, pretty
/// printed, ending in a line break.
pub fn json_document<T: serde::Serialize>(report: &T) -> anyhow::Result<String> {
    let mut v = serde_json::to_value(report)?;
    match v.as_object_mut() {
        Some(o) => {
            o.insert("schema_version".into(), JSON_SCHEMA_VERSION.into());
        }
        None => v = serde_json::json!({ "schema_version": JSON_SCHEMA_VERSION, "report": v }),
    }
    Ok(serde_json::to_string_pretty(&v)? + "\n")
}

/// A setting's or a kind's name as the JSON spells it, for text (`ModalFit` → `modal fit`,
/// `SideGears` → `side gears`): never Rust's debug form.
pub fn words<T: serde::Serialize>(value: &T) -> String {
    match serde_json::to_value(value) {
        Ok(serde_json::Value::String(s)) => s.replace('_', " "),
        Ok(other) => other.to_string(),
        Err(_) => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper rig written as any drive model (its preset, V3: the outputs' inertias differ)
    /// names its modes as the rig's own modal analysis classifies them: the motion of every body
    /// together, then the outputs turning against each other at no twist (the rig's "outputs in
    /// antiphase", `plant::ModeKind`), then the drive swinging against the outputs.
    #[test]
    fn the_rig_as_a_drive_model_names_its_free_motions_as_the_rig_does() {
        let rig = plant::paper::damped_params();
        let m = plant::DriveModel::paper_rig(&rig, Variant::V3, &plant::rig::DriveEffects::default()).unwrap();
        let line = modal_of_line("rig", &m).unwrap();
        let own = rig.open_differential(Variant::V3).unwrap();
        let layout = own.layout.expect("the differential's layout");
        let kinds = own.modes().unwrap().kinds(&layout);
        assert_eq!(kinds[..2], [ModeKind::RigidBody, ModeKind::OutputsAntiphase]);
        assert_eq!(line.mode_kinds[0], "rigid body");
        assert_eq!(line.mode_kinds[1], "free: m2 against m3, no twist");
        assert_eq!(line.mode_kinds[2], "drive against the rest");
        assert_eq!(kinds[2], ModeKind::Shuffle);
    }
}
