//! A drivetrain as one model: a [`Line`] of bodies with couplings and gear stages, the measured
//! forces (torques) acting on some of its bodies, and the effects attached to its elements —
//! Coulomb friction at a body, backlash in a coupling, a dead time and a first-order lag of an
//! input. One nonlinear right-hand side, one linearisation (in contact, friction left out), one
//! exact ZOH for a model without nonlinear effects, one fixed-step RK4 for a model with them
//! ([`crate::integrate::PiecewiseRk4`]: coarse within a smooth piece, fine across a play's edges
//! and a friction's steep band).
//!
//! States x = [q (one per body); q̇; z (one per lagged input)]. Inputs are held constant over a
//! sample (ZOH), as a DAQ's torque command is; a dead time τ = (m + f)·dt shifts the held
//! sequence by m whole samples and splits each sample at the fraction f, so every piece
//! between switching instants is integrated with a constant input (exactly, in the linear case).

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::error::{PlantError, Result};
use crate::integrate::{
    friction_band, AffineStep, ForcedMaps, PieceMaps, PiecewiseRk4, PiecewiseSmooth, AFFINE_MAX_STATES,
    RK4_STEP_TIMES_RATE,
};
use crate::line::{Line, Quantity};
use crate::statespace::zoh;

mod effect;
pub use effect::{
    ActuatorLag, Backlash, Compliance, CoulombFriction, Effect, EffectModel, EffectParameter, Element, Limit, Moves,
    Scale, Search, Shows, SizeContext, TimeDelay, INPUT_TIME_FLOOR_SAMPLES,
};

/// Most RK4 steps per sample within a smooth piece (the fine sub-steps across pieces may be
/// [`FINE_PER_COARSE`] times as many): a model stiffer than this at the record's sample rate is
/// refused instead of being integrated for minutes.
pub const MAX_SUBSTEPS: usize = 2000;

/// What a parameter measures; its unit follows from the line's domain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    /// kg m² or kg.
    Inertia,
    /// Nm/rad or N/m.
    Stiffness,
    /// Nm s/rad or N s/m.
    Damping,
    /// Nm or N.
    Force,
    /// rad or m.
    Coordinate,
    /// rad/s or m/s.
    Speed,
    /// s.
    Time,
    /// Dimensionless.
    Ratio,
}

impl Dimension {
    /// Its unit as a key suffix in reports and JSON, in a rotational (`rotational`) or
    /// translational line: `kg_m2`/`kg`, `Nm_per_rad`/`N_per_m`, `Nm`/`N`, `radps`/`mps`, `s`…
    pub fn key_unit(self, rotational: bool) -> &'static str {
        match (self, rotational) {
            (Dimension::Inertia, true) => "kg_m2",
            (Dimension::Inertia, false) => "kg",
            (Dimension::Stiffness, true) => "Nm_per_rad",
            (Dimension::Stiffness, false) => "N_per_m",
            (Dimension::Damping, true) => "Nms_per_rad",
            (Dimension::Damping, false) => "Ns_per_m",
            (Dimension::Force, true) => "Nm",
            (Dimension::Force, false) => "N",
            (Dimension::Coordinate, true) => "rad",
            (Dimension::Coordinate, false) => "m",
            (Dimension::Speed, true) => "radps",
            (Dimension::Speed, false) => "mps",
            (Dimension::Time, _) => "s",
            (Dimension::Ratio, _) => "1",
        }
    }

    /// Its unit as FMI and the reports write it, in `domain`: `kg.m2`/`kg`, `N.m/rad`/`N/m`,
    /// `N.m.s/rad`/`N.s/m`, `N.m`/`N`, `rad`/`m`, `rad/s`/`m/s`, `s`, `1`.
    pub fn unit(self, domain: crate::line::Domain) -> &'static str {
        let rotational = domain == crate::line::Domain::Rotational;
        match (self, rotational) {
            (Dimension::Inertia, true) => "kg.m2",
            (Dimension::Inertia, false) => "kg",
            (Dimension::Stiffness, true) => "N.m/rad",
            (Dimension::Stiffness, false) => "N/m",
            (Dimension::Damping, true) => "N.m.s/rad",
            (Dimension::Damping, false) => "N.s/m",
            (Dimension::Force, true) => "N.m",
            (Dimension::Force, false) => "N",
            (Dimension::Coordinate, true) => "rad",
            (Dimension::Coordinate, false) => "m",
            (Dimension::Speed, true) => "rad/s",
            (Dimension::Speed, false) => "m/s",
            (Dimension::Time, _) => "s",
            (Dimension::Ratio, _) => "1",
        }
    }
}

/// One parameter of a [`DriveModel`]: what an FMU exposes and a fit moves.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    /// Structured name, e.g. `motor.inertia`, `coupling_1.stiffness`, `M_motor.delay`.
    pub name: String,
    /// What it measures.
    pub dimension: Dimension,
    /// In words.
    pub description: String,
    /// Its value, SI.
    pub value: f64,
    /// Whether 0 is allowed (drags and dampings); else it must be > 0.
    pub zero_allowed: bool,
}

/// A line of bodies, the forces measured on them and the effects: the model of a `drive_test`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DriveModel {
    /// Bodies and couplings.
    pub line: Line,
    /// The body (0-based) each input force acts on.
    pub inputs: Vec<usize>,
    /// Effects, at most one of each kind per element.
    pub effects: Vec<Effect>,
}

/// Most inputs (forces or torques) a drive model may have.
pub const MAX_INPUTS: usize = 8;
/// Most effects a drive model may have (one of each kind on every element is far more than a
/// record can tell apart).
pub const MAX_EFFECTS: usize = 32;

impl DriveModel {
    /// Checks the line, the inputs and every effect (element in range, parameter positive and
    /// finite, no element with the same effect twice).
    pub fn validate(&self) -> Result<()> {
        self.line.validate()?;
        let n = self.line.bodies.len();
        if self.inputs.len() > MAX_INPUTS || self.effects.len() > MAX_EFFECTS {
            return Err(PlantError::Invalid(format!(
                "{} inputs and {} effects: a model takes at most {MAX_INPUTS} inputs and {MAX_EFFECTS} effects",
                self.inputs.len(),
                self.effects.len()
            )));
        }
        if let Some(&b) = self.inputs.iter().find(|&&b| b >= n) {
            return Err(PlantError::Invalid(format!("an input acts on body {} of a line of {n}", b + 1)));
        }
        for (i, e) in self.effects.iter().enumerate() {
            let at = e.at();
            let count = at.count(self);
            if at.index() >= count {
                return Err(PlantError::Invalid(format!(
                    "effects[{}] ({}) acts on element {} of {count}",
                    i + 1,
                    e.name(),
                    at.index() + 1
                )));
            }
            // every effect parameter is bounded to positive, finite values
            for (p, v) in e.parameter_kinds().iter().zip(e.values()) {
                if !(v.is_finite() && v > 0.0) {
                    return Err(PlantError::Invalid(format!(
                        "effects[{}] ({}): {} {v}: expected a positive, finite value",
                        i + 1,
                        e.name(),
                        p.name
                    )));
                }
            }
            let same = |o: &Effect| o.name() == e.name() && o.element(self) == e.element(self);
            if self.effects[..i].iter().any(same) {
                return Err(PlantError::Invalid(format!(
                    "effects[{}]: {} at {} is given twice",
                    i + 1,
                    e.name(),
                    e.element(self)
                )));
            }
        }
        Ok(())
    }

    /// A linear mechanical model with a diagonal inertia matrix (the three-mass strand, a chain
    /// from a rig file, a line) as a rotational drive model without effects: one body per
    /// coordinate (its name, inertia and drag), one coupling per spring with the spring's
    /// elongation, and the torques on the coordinates `inputs`.
    pub fn from_mechanical(m: &crate::mechanical::MechanicalModel, inputs: Vec<usize>) -> Result<DriveModel> {
        let n = m.dofs();
        let off_diagonal =
            (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).any(|(i, j)| i != j && m.inertia[(i, j)] != 0.0);
        if off_diagonal {
            return Err(PlantError::Invalid(
                "the mechanical model couples its coordinates through the inertia matrix: a drive model's bodies \
                 each have their own inertia"
                    .into(),
            ));
        }
        let label = |s: &str| s.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect::<String>();
        let bodies = (0..n)
            .map(|i| crate::line::LineBody {
                name: m.dof_names[i].clone(),
                inertia: m.inertia[(i, i)],
                drag: m.drag[i],
            })
            .collect();
        let couplings = m
            .springs
            .iter()
            .map(|s| crate::line::Coupling {
                name: Some(label(&s.name)),
                elongation: Some(s.elongation.iter().copied().collect()),
                ..crate::line::Coupling::new(s.stiffness, s.damping, 1.0)
            })
            .collect();
        let d = DriveModel {
            line: Line { domain: crate::line::Domain::Rotational, bodies, couplings },
            inputs,
            effects: vec![],
        };
        d.validate()?;
        Ok(d)
    }

    /// True when friction or backlash make the right-hand side nonlinear.
    pub fn is_nonlinear(&self) -> bool {
        self.effects.iter().any(Effect::is_nonlinear)
    }

    /// The model, validated, with every structural effect written into its line
    /// ([`Compliance`]: a body split in two, [`EffectModel::write_into_line`]) and left out of
    /// its effects (the result validated again); borrowed when it has none. What the dynamics,
    /// the FMU, the controller and the modal analysis take: a model file's and the paper rig's
    /// models are resolved as they are read or built.
    pub fn resolved(&self) -> Result<std::borrow::Cow<'_, DriveModel>> {
        use std::borrow::Cow;
        self.validate()?;
        if !self.effects.iter().any(Effect::is_structural) {
            return Ok(Cow::Borrowed(self));
        }
        let effects = self.effects.iter().filter(|e| !e.is_structural()).copied().collect();
        let mut m = DriveModel { effects, ..self.clone() };
        for e in self.effects.iter().filter(|e| e.is_structural()) {
            e.write_into_line(&mut m)?;
        }
        m.validate()?;
        Ok(Cow::Owned(m))
    }

    /// Number of states: angles (positions), speeds and one per lagged input.
    pub fn nstates(&self) -> usize {
        2 * self.line.bodies.len() + self.effects.iter().map(|e| e.state_names(self).len()).sum::<usize>()
    }

    /// Its effects, each with where it acts (`time_delay at input 1`): what a report says a
    /// model leaves out or carries.
    pub fn effects_at(&self) -> Vec<String> {
        self.effects.iter().map(|e| format!("{} at {}", e.name(), e.element(self))).collect()
    }

    /// The bodies' names as identifiers (letters, digits, `_`; not starting with a digit), the
    /// stem of every signal and parameter name; `body_<i>` for all when two would coincide.
    pub fn body_labels(&self) -> Vec<String> {
        let label = |name: &str| {
            let mut s: String = name.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
            if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
                s.insert(0, '_');
            }
            s
        };
        let labels: Vec<String> = self.line.bodies.iter().map(|b| label(&b.name)).collect();
        if (1..labels.len()).any(|i| labels[..i].contains(&labels[i])) {
            return (1..=labels.len()).map(|i| format!("body_{i}")).collect();
        }
        labels
    }

    /// Signal names of one set for the CLI, the FMU, the MPC and the JSON: states
    /// `phi_<body>`/`x_<body>`, `w_<body>`/`v_<body>`, `<input>_lagged` (the force after an actuator lag).
    pub fn state_names(&self) -> Vec<String> {
        let rotational = self.line.domain == crate::line::Domain::Rotational;
        let (q, v) = if rotational { ("phi", "w") } else { ("x", "v") };
        let labels = self.body_labels();
        let mut s: Vec<String> = labels.iter().map(|b| format!("{q}_{b}")).collect();
        s.extend(labels.iter().map(|b| format!("{v}_{b}")));
        for e in &self.effects {
            s.extend(e.state_names(self));
        }
        s
    }

    /// Input names: `M_<body>` (rotational) or `F_<body>`, `_2`, `_3`… for further inputs on
    /// one body.
    pub fn input_names(&self) -> Vec<String> {
        let f = if self.line.domain == crate::line::Domain::Rotational { "M" } else { "F" };
        let labels = self.body_labels();
        let mut out: Vec<String> = Vec::with_capacity(self.inputs.len());
        for (j, &b) in self.inputs.iter().enumerate() {
            let before = self.inputs[..j].iter().filter(|&&o| o == b).count();
            let stem = format!("{f}_{}", labels.get(b).map_or("?", String::as_str));
            out.push(if before == 0 { stem } else { format!("{stem}_{}", before + 1) });
        }
        out
    }

    /// Coupling force names: `T_<name>` (rotational) or `F_<name>`, the name `coupling_<i>`
    /// (1-based) unless the coupling has its own.
    pub fn coupling_force_names(&self) -> Vec<String> {
        let f = if self.line.domain == crate::line::Domain::Rotational { "T" } else { "F" };
        self.coupling_labels().iter().map(|c| format!("{f}_{c}")).collect()
    }

    /// Each coupling's name, `coupling_<i>` (1-based) unless it has its own.
    pub fn coupling_labels(&self) -> Vec<String> {
        let c = &self.line.couplings;
        c.iter().enumerate().map(|(i, c)| c.name.clone().unwrap_or_else(|| format!("coupling_{}", i + 1))).collect()
    }

    /// Every parameter of the model as one list: the bodies' inertias and drags, the
    /// couplings' stiffnesses, dampings and ratios, then each effect's parameters, in the
    /// order of `effects`. [`DriveModel::with_parameter_values`] takes values in this order.
    pub fn parameter_list(&self) -> Vec<Parameter> {
        use Dimension as D;
        let labels = self.body_labels();
        let p = |name: String, dimension, description: String, value, zero_allowed| Parameter {
            name,
            dimension,
            description,
            value,
            zero_allowed,
        };
        let mut out = Vec::new();
        for (b, l) in self.line.bodies.iter().zip(&labels) {
            out.push(p(format!("{l}.inertia"), D::Inertia, format!("inertia (mass) of {}", b.name), b.inertia, false));
            out.push(p(format!("{l}.drag"), D::Damping, format!("viscous drag of {} to ground", b.name), b.drag, true));
        }
        for (i, c) in self.line.couplings.iter().enumerate() {
            let k = i + 1;
            let (a, b) = match (&c.elongation, &c.name) {
                (None, _) => (self.line.bodies[i].name.as_str(), self.line.bodies[i + 1].name.as_str()),
                (Some(_), Some(name)) => (name.as_str(), ""),
                (Some(_), None) => ("", ""),
            };
            let what = if c.elongation.is_some() { format!("of coupling {k} {a}") } else { format!("{a}-{b}") };
            let what = what.trim_end();
            out.push(p(
                format!("coupling_{k}.stiffness"),
                D::Stiffness,
                format!("stiffness {what}"),
                c.stiffness,
                false,
            ));
            out.push(p(format!("coupling_{k}.damping"), D::Damping, format!("damping {what}"), c.damping, true));
            if c.elongation.is_none() {
                out.push(p(
                    format!("coupling_{k}.ratio"),
                    D::Ratio,
                    format!("gear ratio, speed of {a} per speed of {b}"),
                    c.ratio,
                    false,
                ));
            }
        }
        for e in &self.effects {
            let (label, phrase) = (e.at().label(self), e.at().phrase(self));
            for (k, v) in e.parameter_kinds().iter().zip(e.values()) {
                out.push(p(format!("{label}.{}", k.name), k.dimension, format!("{} {phrase}", k.what), v, false));
            }
        }
        out
    }

    /// The model with parameter values `v` in [`DriveModel::parameter_list`] order (same
    /// structure: bodies, couplings, inputs and effects kept), validated.
    pub fn with_parameter_values(&self, v: &[f64]) -> Result<DriveModel> {
        let expected = self.parameter_list().len();
        if v.len() != expected {
            return Err(PlantError::Invalid(format!("{} parameter values for a model of {expected}", v.len())));
        }
        let mut m = self.clone();
        let mut it = v.iter().copied();
        let mut next = || it.next().unwrap_or(f64::NAN);
        for b in &mut m.line.bodies {
            b.inertia = next();
            b.drag = next();
        }
        for c in &mut m.line.couplings {
            c.stiffness = next();
            c.damping = next();
            if c.elongation.is_none() {
                c.ratio = next();
            }
        }
        for e in &mut m.effects {
            let v: Vec<f64> = e.parameter_kinds().iter().map(|_| next()).collect();
            e.set_values(&v);
        }
        m.validate()?;
        Ok(m)
    }

    /// The linearisation in contact with friction left out: ẋ = A x + B u (u: the inputs after
    /// their dead time). Exact for a model without friction and backlash.
    pub fn linearisation(&self) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
        let p = Dynamics::new(self)?;
        Ok(p.linear())
    }

    /// The linearisation as a controller sees it (in contact, friction left out, dead times
    /// left out — [`DriveModel::input_delays_s`]): inputs [`DriveModel::input_names`], outputs
    /// every body's speed (`w_<body>`/`v_<body>`, the speed states' names) and every coupling's
    /// force ([`DriveModel::coupling_force_names`]: c·(q_i/r − q_{i+1}) + d·(q̇_i/r − q̇_{i+1})).
    pub fn control_state_space(&self) -> Result<crate::statespace::StateSpace> {
        let (a, b) = self.linearisation()?;
        let n = self.line.bodies.len();
        let ns = a.nrows();
        let names = self.state_names();
        let nc = self.line.couplings.len();
        let mut c = DMatrix::zeros(n + nc, ns);
        for i in 0..n {
            c[(i, n + i)] = 1.0;
        }
        c.view_mut((n, 0), (nc, ns)).copy_from(&self.coupling_forces(ns));
        let mut output_names: Vec<String> = names[n..2 * n].to_vec();
        output_names.extend(self.coupling_force_names());
        Ok(crate::statespace::StateSpace {
            d: DMatrix::zeros(n + nc, b.ncols()),
            a,
            b,
            c,
            state_names: names,
            input_names: self.input_names(),
            output_names,
        })
    }

    /// The couplings' forces in contact as rows over `nstates` states: c·eᵀq + d·eᵀq̇.
    pub fn coupling_forces(&self, nstates: usize) -> DMatrix<f64> {
        let n = self.line.bodies.len();
        let mut c = DMatrix::zeros(self.line.couplings.len(), nstates);
        for (i, k) in self.line.couplings.iter().enumerate() {
            for (j, e) in k.terms(i) {
                c[(i, j)] = k.stiffness * e;
                c[(i, n + j)] = k.damping * e;
            }
        }
        c
    }

    /// Position in [`DriveModel::parameter_list`] of input `input`'s dead time, if it has one:
    /// after the bodies' (2 each) and the couplings' (3 each, 2 with an elongation) parameters,
    /// the effects' in order.
    pub fn delay_parameter(&self, input: usize) -> Option<usize> {
        let couplings: usize = self.line.couplings.iter().map(|c| if c.elongation.is_some() { 2 } else { 3 }).sum();
        let mut at = 2 * self.line.bodies.len() + couplings;
        for e in &self.effects {
            if let Effect::TimeDelay(TimeDelay { input: j, .. }) = *e {
                if j == input {
                    return Some(at);
                }
            }
            at += e.parameter_kinds().len();
        }
        None
    }

    /// Dead time of each input, s (0: none).
    pub fn input_delays_s(&self) -> Vec<f64> {
        let mut d = vec![0.0; self.inputs.len()];
        for e in &self.effects {
            if let Effect::TimeDelay(TimeDelay { input, delay_s }) = *e {
                d[input] = delay_s;
            }
        }
        d
    }

    /// Fastest rate of the linearisation, max |λ(A)| (1/s): what sets an explicit integrator's
    /// step.
    pub fn fastest_linear_rate(&self) -> Result<f64> {
        Ok(Dynamics::new(self)?.linear_rate())
    }

    /// Simulates the model from rest (every body at `initial_speed` of the first body, through
    /// the gear ratios) under the sampled `inputs` (one vector per model input, sample time
    /// `dt_s`, held over each sample) and returns the `outputs` at the sample instants.
    pub fn simulate(
        &self,
        inputs: &[Vec<f64>],
        dt_s: f64,
        initial_speed: f64,
        outputs: &[(Quantity, usize)],
    ) -> Result<Vec<Vec<f64>>> {
        Ok(split_outputs(self.simulate_flat(inputs, dt_s, initial_speed, outputs)?, outputs.len()))
    }

    /// [`DriveModel::simulate`] with the outputs one after another in one vector, each as long
    /// as the inputs: no per-output buffers beside it (a diagnosis forms its residual in place).
    pub fn simulate_flat(
        &self,
        inputs: &[Vec<f64>],
        dt_s: f64,
        initial_speed: f64,
        outputs: &[(Quantity, usize)],
    ) -> Result<Vec<f64>> {
        let p = Dynamics::new(self)?;
        p.simulate_flat(inputs, dt_s, initial_speed, outputs)
    }
}

/// The `count` outputs of a flat simulation ([`Dynamics::simulate_flat_from`]), one vector
/// each (empty ones for a record without samples).
pub fn split_outputs(flat: Vec<f64>, count: usize) -> Vec<Vec<f64>> {
    let len = flat.len() / count.max(1);
    (0..count).map(|o| flat[o * len..(o + 1) * len].to_vec()).collect()
}

/// The model's right-hand side, outputs, linearisation and RK4 step, in flat arrays: what the
/// record simulation, the FMU and the diagnosis integrate, so all three integrate one model.
#[derive(Debug, Clone)]
pub struct Dynamics {
    n: usize,
    inv_j: Vec<f64>,
    drag: Vec<f64>,
    /// Stiffness, damping, half play (0: none) and twist coefficients of each coupling.
    couplings: Vec<Spring>,
    /// The twists' coefficients (body, coefficient), `Spring::terms` ranges into it.
    terms: Vec<(usize, f64)>,
    /// (friction, smoothing speed) per body (0: none).
    friction: Vec<(f64, f64)>,
    /// Per input: body, dead time, lag time constant (0: none), lag state index.
    inputs: Vec<(usize, f64, f64, usize)>,
    nstates: usize,
    nonlinear: bool,
    /// RK4 steps within a smooth piece and across pieces, s (nonlinear models).
    coarse_s: f64,
    fine_s: f64,
    /// Half-width of each body's steep friction band, m/s or rad/s (0: none).
    friction_band: Vec<f64>,
    /// The model's effects (each linearises its own slot).
    effects: Vec<Effect>,
}

/// Fine sub-steps per coarse step where a step crosses a coupling's play (as
/// `plant::preset::BACKLASH_STEP_S` is an eighth of the rig's millisecond).
pub const FINE_PER_COARSE: f64 = 8.0;

impl Dynamics {
    /// The dynamics of a model, validated and resolved first ([`DriveModel::resolved`]).
    pub fn new(m: &DriveModel) -> Result<Dynamics> {
        let m = &*m.resolved()?;
        let n = m.line.bodies.len();
        let mut terms = Vec::new();
        let couplings: Vec<Spring> = m
            .line
            .couplings
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let start = terms.len();
                terms.extend(c.terms(i));
                let gear = c.elongation.is_none().then(|| 1.0 / c.ratio);
                Spring { c: c.stiffness, d: c.damping, half: 0.0, terms: (start, terms.len()), gear }
            })
            .collect();
        let mut d = Dynamics {
            n,
            inv_j: m.line.bodies.iter().map(|b| 1.0 / b.inertia).collect(),
            drag: m.line.bodies.iter().map(|b| b.drag).collect(),
            couplings,
            terms,
            friction: vec![(0.0, 1.0); n],
            inputs: m.inputs.iter().map(|&b| (b, 0.0, 0.0, 0)).collect(),
            nstates: 2 * n,
            nonlinear: m.is_nonlinear(),
            coarse_s: f64::INFINITY,
            fine_s: f64::INFINITY,
            friction_band: vec![0.0; n],
            effects: m.effects.clone(),
        };
        // each effect fills its element's slot (friction, play, dead time, lag state)
        for e in &m.effects {
            e.enter(&mut d);
        }
        if d.nonlinear {
            d.steps_and_bands();
        }
        Ok(d)
    }

    /// The RK4 steps (within a piece: h·rate ≤ [`RK4_STEP_TIMES_RATE`] of the contact piece's
    /// fastest rate; across pieces: [`FINE_PER_COARSE`] times shorter with backlash, and h·rate
    /// ≤ [`RK4_STEP_TIMES_RATE`] of the friction's slopes F_c/(v_s·J)) and the friction's steep
    /// bands (where F_c v_s²/(J (v² + v_s²)^{3/2}) is faster than the coarse step resolves).
    fn steps_and_bands(&mut self) {
        let slope = |i: usize| {
            let (fc, vs) = self.friction[i];
            fc / vs * self.inv_j[i]
        };
        let bodies = || (0..self.n).filter(|&i| self.friction[i].0 > 0.0);
        let friction_step = bodies().map(|i| RK4_STEP_TIMES_RATE / slope(i)).fold(f64::INFINITY, f64::min);
        // a line without springs (a free mass) has no linear rate: its steps are the friction's
        let mut coarse = RK4_STEP_TIMES_RATE / self.linear_rate();
        if !coarse.is_finite() {
            coarse = friction_step;
        }
        let backlash = self.couplings.iter().any(|c| c.half > 0.0);
        self.fine_s = if backlash { coarse / FINE_PER_COARSE } else { coarse }.min(friction_step);
        for i in bodies() {
            let (fc, vs) = self.friction[i];
            self.friction_band[i] = friction_band(coarse, fc, vs, 1.0 / self.inv_j[i]);
        }
        self.coarse_s = coarse;
    }

    /// The RK4 steps of the nonlinear model (within a smooth piece, across pieces), s; infinite
    /// for a linear model.
    pub fn rk4_steps_s(&self) -> (f64, f64) {
        (self.coarse_s, self.fine_s)
    }

    /// An integrator of this model ([`Dynamics::rk4_steps_s`]).
    pub fn integrator(&self) -> PiecewiseRk4 {
        PiecewiseRk4::new(self.nstates, self.coarse_s, self.fine_s)
    }

    /// The smooth piece of state `x`: each coupling with play in contact on either side or
    /// inside it, each body with friction clear of its steep band on either side or in it.
    pub fn piece(&self, x: &[f64]) -> u64 {
        let n = self.n;
        let mut key: u64 = 0;
        let mut mix = |class: u64| key = mix_piece(key, class);
        for s in &self.couplings {
            if s.half > 0.0 {
                mix(side(self.elastic_twist(s, x), s.half));
            }
        }
        for (i, &band) in self.friction_band.iter().enumerate() {
            if band > 0.0 {
                mix(side(x[n + i], band));
            }
        }
        key
    }

    /// ẋ = f(x, u): `u` the inputs after their dead time.
    #[inline]
    pub fn rhs(&self, x: &[f64], u: &[f64], dx: &mut [f64]) {
        let n = self.n;
        let (q, v) = (&x[..n], &x[n..2 * n]);
        let (dq, rest) = dx.split_at_mut(n);
        let f = &mut rest[..n];
        for i in 0..n {
            dq[i] = v[i];
            let friction = if self.friction[i].0 > 0.0 { self.friction_force(i, v[i]) } else { 0.0 };
            f[i] = -self.drag[i] * v[i] + friction;
        }
        for (&(body, _, tau, z), &u) in self.inputs.iter().zip(u) {
            f[body] += if tau > 0.0 { x[z] } else { u };
        }
        for (i, s) in self.couplings.iter().enumerate() {
            if let Some(inv_r) = s.gear {
                // between neighbours (the hot path of a line): q_i / r − q_{i+1}
                let t = coupling_force(s.c, s.d, s.half, q[i] * inv_r - q[i + 1], v[i] * inv_r - v[i + 1]);
                f[i + 1] += t;
                f[i] -= t * inv_r;
                continue;
            }
            let terms = &self.terms[s.terms.0..s.terms.1];
            let (mut twist, mut rate) = (0.0, 0.0);
            for &(j, e) in terms {
                twist += e * q[j];
                rate += e * v[j];
            }
            let t = coupling_force(s.c, s.d, s.half, twist, rate);
            for &(j, e) in terms {
                f[j] -= e * t;
            }
        }
        for (fi, ij) in f.iter_mut().zip(&self.inv_j) {
            *fi *= ij;
        }
        for (&(_, _, tau, z), &u) in self.inputs.iter().zip(u) {
            if tau > 0.0 {
                rest[z - n] = (u - x[z]) / tau;
            }
        }
    }

    /// A and B of the contact piece without friction.
    pub fn linear(&self) -> (DMatrix<f64>, DMatrix<f64>) {
        self.linear_piece(true)
    }

    /// A and B without friction, every coupling with play in contact (`contact`) or inside
    /// its play, where it carries nothing: each effect's [`EffectModel::linearise`].
    pub fn linear_piece(&self, contact: bool) -> (DMatrix<f64>, DMatrix<f64>) {
        let (ns, m) = (self.nstates, self.inputs.len());
        let mut linear = self.clone();
        for e in &self.effects {
            e.linearise(&mut linear, contact);
        }
        let mut a = DMatrix::zeros(ns, ns);
        let mut b = DMatrix::zeros(ns, m);
        let mut dx = vec![0.0; ns];
        let zero_u = vec![0.0; m];
        for j in 0..ns {
            let mut x = vec![0.0; ns];
            x[j] = 1.0;
            linear.rhs(&x, &zero_u, &mut dx);
            a.set_column(j, &DVector::from_column_slice(&dx));
        }
        let x = vec![0.0; ns];
        for j in 0..m {
            let mut u = vec![0.0; m];
            u[j] = 1.0;
            linear.rhs(&x, &u, &mut dx);
            b.set_column(j, &DVector::from_column_slice(&dx));
        }
        (a, b)
    }

    /// Fastest rate of the linear part, max |λ(A)|, 1/s.
    fn linear_rate(&self) -> f64 {
        self.linear().0.complex_eigenvalues().iter().map(|l| l.norm()).fold(0.0, f64::max)
    }

    /// Number of states.
    pub fn nstates(&self) -> usize {
        self.nstates
    }

    /// Twist of coupling `s` at state `x` (without its rate: what the pieces are told by).
    #[inline]
    fn elastic_twist(&self, s: &Spring, x: &[f64]) -> f64 {
        self.terms[s.terms.0..s.terms.1].iter().map(|&(j, e)| e * x[j]).sum()
    }

    /// Twist of coupling `s` and its rate at state `x`.
    #[inline]
    fn twist(&self, s: &Spring, x: &[f64]) -> (f64, f64) {
        let n = self.n;
        let (mut twist, mut rate) = (0.0, 0.0);
        for &(j, e) in &self.terms[s.terms.0..s.terms.1] {
            twist += e * x[j];
            rate += e * x[n + j];
        }
        (twist, rate)
    }

    /// Twist of coupling `k` at state `x`, and whether it is beyond its play (always, without
    /// play).
    #[inline]
    pub fn coupling_twist(&self, k: usize, x: &[f64]) -> (f64, bool) {
        let s = &self.couplings[k];
        let twist = self.elastic_twist(s, x);
        (twist, s.half <= 0.0 || twist.abs() > s.half)
    }

    /// The state derivative the plays add beyond their positive edges to the contact piece
    /// ([`Dynamics::linear`]): in contact there a coupling's force c (eᵀq − b/2) + d eᵀq̇ is the
    /// engaged one less c b/2, a force e_j c b/2 on body j (below the negative edge its
    /// negative). Exact for plays that all engage at once.
    pub fn play_offset(&self) -> Vec<f64> {
        let n = self.n;
        let mut e = vec![0.0; self.nstates];
        for s in self.couplings.iter().filter(|s| s.half > 0.0) {
            for &(j, c) in &self.terms[s.terms.0..s.terms.1] {
                e[n + j] += c * s.c * s.half * self.inv_j[j];
            }
        }
        e
    }

    /// The exact steps of each of `lengths` (s) of the three pieces of a model whose only
    /// nonlinearity is play that engages at once ([`Dynamics::plays_engage_at_once`]; no
    /// friction, at most [`AFFINE_MAX_STATES`] states): inside the play, beyond it, below it.
    /// `None` for any other model.
    pub fn play_maps(&self, lengths: &[f64]) -> Option<Vec<PieceMaps>> {
        if !self.pieces_are_linear() {
            return None;
        }
        let pieces = self.play_pieces();
        lengths.iter().map(|&h| PieceMaps::new(h, &pieces)).collect()
    }

    /// The three linear pieces of a play that engages at once, in [`PieceMaps`]' order: inside
    /// it (A, B without its couplings), beyond it and below it (A, B in contact), each B with one
    /// more column, the play's offset ([`Dynamics::play_offset`]; 0 inside, its negative below)
    /// as an input held at 1.
    fn play_pieces(&self) -> [(DMatrix<f64>, DMatrix<f64>); 3] {
        let offset = DVector::from_vec(self.play_offset());
        [(false, 0.0), (true, 1.0), (true, -1.0)].map(|(contact, sign)| {
            let (a, b) = self.linear_piece(contact);
            let mut with_offset = DMatrix::zeros(self.nstates, b.ncols() + 1);
            with_offset.columns_mut(0, b.ncols()).copy_from(&b);
            with_offset.set_column(b.ncols(), &(&offset * sign));
            (a, with_offset)
        })
    }

    /// The steps over each of `lengths` (s) that [`HeldInputs`] takes whole where it can: the
    /// pieces of a play ([`Dynamics::play_maps`]), or the linear part exactly with the
    /// frictions as forces while every body with friction slides clear of its band
    /// ([`Dynamics::sliding_steps`]). `None` for any other model.
    pub fn exact_steps(&self, lengths: &[f64]) -> Option<Vec<ExactSteps>> {
        if self.pieces_are_linear() {
            return Some(self.play_maps(lengths)?.into_iter().map(|m| ExactSteps::Play(Box::new(m))).collect());
        }
        if !self.slides_exactly() {
            return None;
        }
        // the frictionless linear part (A, B), with play each of its pieces
        // ([`Dynamics::play_pieces`]), each friction a force on its body (F)
        let (n, ns) = (self.n, self.nstates);
        let pieces: Vec<(DMatrix<f64>, DMatrix<f64>)> =
            if self.couplings.iter().any(|s| s.half > 0.0) { self.play_pieces().into() } else { vec![self.linear()] };
        let bodies: Vec<usize> = (0..n).filter(|&i| self.friction[i].0 > 0.0).collect();
        let mut f = DMatrix::zeros(ns, bodies.len());
        for (j, &i) in bodies.iter().enumerate() {
            f[(n + i, j)] = self.inv_j[i];
        }
        lengths.iter().map(|&h| self.sliding_steps(h, &pieces, &f, &bodies)).collect()
    }

    /// Whether [`Dynamics::exact_steps`] has steps for this model.
    pub fn has_exact_steps(&self) -> bool {
        self.pieces_are_linear() || self.slides_exactly()
    }

    /// Whether the model's nonlinearities are friction and at most play that engages at once
    /// ([`Dynamics::plays_engage_at_once`]), within [`AFFINE_MAX_STATES`] states.
    fn slides_exactly(&self) -> bool {
        self.nonlinear
            && (self.couplings.iter().all(|s| s.half <= 0.0) || self.plays_engage_at_once())
            && self.friction.iter().any(|f| f.0 > 0.0)
            && self.nstates <= AFFINE_MAX_STATES
    }

    /// The class of state `x` in its plays (0 inside, 1 beyond, 2 below: the order of
    /// [`ExactSteps::Sliding`]'s pieces), told by the first play (they engage at once).
    fn play_class(&self, x: &[f64]) -> usize {
        self.couplings.iter().find(|s| s.half > 0.0).map_or(0, |s| side(self.elastic_twist(s, x), s.half) as usize)
    }

    /// The step of `h` while every body with friction (`bodies`) slides: the frictionless
    /// linear part (A, B) stepped exactly, the frictions −F_c v/√(v² + v_s²) as forces on their
    /// bodies (F; ETD2RK, [`ForcedMaps`]); each body's band where the step may not be taken so,
    /// where the friction's slope times `h` exceeds [`SLIDING_SLOPE_TIMES_STEP`] (and never
    /// inside its steep band, [`Dynamics::piece`]).
    fn sliding_steps(
        &self,
        h: f64,
        pieces: &[(DMatrix<f64>, DMatrix<f64>)],
        f: &DMatrix<f64>,
        bodies: &[usize],
    ) -> Option<ExactSteps> {
        let bodies = bodies
            .iter()
            .map(|&i| {
                let (fc, vs) = self.friction[i];
                let wide =
                    friction_band(h * RK4_STEP_TIMES_RATE / SLIDING_SLOPE_TIMES_STEP, fc, vs, 1.0 / self.inv_j[i]);
                (i, wide.max(self.friction_band[i]))
            })
            .collect();
        let maps = pieces.iter().map(|(a, b)| ForcedMaps::new(h, a, b, f)).collect::<Option<Vec<_>>>()?;
        Some(ExactSteps::Sliding { maps: maps.into_boxed_slice(), bodies })
    }

    /// Body `i`'s friction force at speed `v`, against the motion: Coulomb friction smoothed as
    /// F_c v/√(v² + v_s²), the slope F_c/v_s at rest of tanh(v/v_s) without its exponential.
    #[inline]
    fn friction_force(&self, i: usize, v: f64) -> f64 {
        let (fc, vs) = self.friction[i];
        -(fc * v / (v * v + vs * vs).sqrt())
    }

    /// One [`ExactSteps::Sliding`] step of `x` over its length into `out`; false (and `out`
    /// undefined) where a body with friction is inside its band at the start, the predictor or
    /// the end, or reverses.
    fn slide(&self, maps: &ForcedMaps, bodies: &[(usize, f64)], x: &[f64], u: &[f64], out: &mut [f64]) -> bool {
        let (n, m, k) = (self.n, u.len(), bodies.len());
        let clear = |v: f64, band: f64, v0: f64| v.abs() > band && (v > 0.0) == (v0 > 0.0);
        let mut ug = [0.0; MAX_INPUTS + AFFINE_MAX_STATES];
        ug[..m].copy_from_slice(u);
        for (j, &(i, band)) in bodies.iter().enumerate() {
            let v = x[n + i];
            if !clear(v, band, v) {
                return false;
            }
            ug[m + j] = self.friction_force(i, v);
        }
        maps.predict(x, &ug[..m + k], out);
        let mut change = [0.0; AFFINE_MAX_STATES];
        for (j, &(i, band)) in bodies.iter().enumerate() {
            let v = out[n + i];
            if !clear(v, band, x[n + i]) {
                return false;
            }
            change[j] = self.friction_force(i, v) - ug[m + j];
        }
        maps.correct(&change[..k], out);
        bodies.iter().all(|&(i, band)| clear(out[n + i], band, x[n + i]))
    }

    /// Whether [`Dynamics::play_maps`] steps this model's pieces exactly: its only
    /// nonlinearity is play that engages at once, and it has at most [`AFFINE_MAX_STATES`]
    /// states.
    pub fn pieces_are_linear(&self) -> bool {
        self.plays_engage_at_once() && self.friction.iter().all(|f| f.0 <= 0.0) && self.nstates <= AFFINE_MAX_STATES
    }

    /// Whether the model has play and every play enters and leaves contact together: one
    /// coupling's, or several whose twists are one twist scaled, their plays scaled alike (the
    /// paper rig's two side shafts on the differential's twist, eq. (A1)). Its pieces are then
    /// three, each linear where nothing else is nonlinear.
    pub fn plays_engage_at_once(&self) -> bool {
        let mut plays = self.couplings.iter().filter(|s| s.half > 0.0);
        let Some(first) = plays.next() else { return false };
        // each play's twist per half play, as a dense row
        let row = |s: &Spring| {
            let mut r = vec![0.0; self.n];
            for &(j, e) in &self.terms[s.terms.0..s.terms.1] {
                r[j] += e / s.half;
            }
            r
        };
        let r0 = row(first);
        let size = r0.iter().map(|v| v.abs()).fold(0.0, f64::max);
        plays.all(|s| row(s).iter().zip(&r0).all(|(a, b)| (a - b).abs() <= 1e-12 * size))
    }

    /// The piece key of a model whose plays engage at once, all in `class` (0 inside, 1
    /// beyond, 2 below: [`Dynamics::piece`]'s).
    fn play_piece_key(&self, class: u64) -> u64 {
        self.couplings.iter().filter(|s| s.half > 0.0).fold(0, |key, _| mix_piece(key, class))
    }

    /// The friction's contribution to ∂v̇_i/∂v_i at state `x`: (speed's state index, slope
    /// −F_c v_s²/((v² + v_s²)^{3/2} J_i)) for each body with friction.
    pub fn friction_slopes(&self, x: &[f64]) -> Vec<(usize, f64)> {
        let n = self.n;
        let mut out = Vec::new();
        for (i, &(fc, vs)) in self.friction.iter().enumerate() {
            if fc > 0.0 {
                let v = x[n + i];
                out.push((n + i, -fc * vs * vs / (v * v + vs * vs).powf(1.5) * self.inv_j[i]));
            }
        }
        out
    }

    /// Half-width of body `i`'s steep friction band, m/s or rad/s (0: none).
    #[inline]
    pub fn friction_band(&self, i: usize) -> f64 {
        self.friction_band[i]
    }

    /// Integrates with the RK4 steps `coarse_s` within a smooth piece and `fine_s` across pieces
    /// instead of [`Dynamics::rk4_steps_s`]'s rule (a rig that steps as its record is sampled);
    /// the friction's steep bands follow the coarse step.
    pub fn with_steps(mut self, coarse_s: f64, fine_s: f64) -> Dynamics {
        self.coarse_s = coarse_s;
        self.fine_s = fine_s;
        for i in 0..self.n {
            let (fc, vs) = self.friction[i];
            if fc > 0.0 {
                self.friction_band[i] = friction_band(coarse_s, fc, vs, 1.0 / self.inv_j[i]);
            }
        }
        self
    }

    /// Fastest rate of the linear part, max |λ(A)|, 1/s.
    pub fn fastest_rate(&self) -> f64 {
        self.linear_rate()
    }

    /// Number of inputs.
    pub fn ninputs(&self) -> usize {
        self.inputs.len()
    }

    /// Dead time of input `j`, s (0: none).
    pub fn delay_s(&self, j: usize) -> f64 {
        self.inputs.get(j).map_or(0.0, |i| i.1)
    }

    /// The same dynamics with every input acting at once: for inputs already delayed.
    pub fn without_delays(&self) -> Dynamics {
        let mut d = self.clone();
        for input in &mut d.inputs {
            input.1 = 0.0;
        }
        d
    }

    /// True when friction or backlash make the right-hand side nonlinear.
    pub fn is_nonlinear(&self) -> bool {
        self.nonlinear
    }

    /// The state a record starts in: the line in rigid motion, the first body at `speed` and
    /// the others at it through the gear ratios, each lagged input at `inputs[j]` (its steady
    /// value), and the couplings twisted as far as the forces at that state take them
    /// ([`Dynamics::quasi_static_positions`]): a record that starts under load starts with its
    /// shafts wound up, not ringing from untwisted.
    pub fn initial_state(&self, speed: f64, inputs: &[f64]) -> Vec<f64> {
        let mut x = self.rigid_state(speed, inputs);
        if let Some(q) = self.quasi_static_positions(&x, inputs) {
            x[..self.n].copy_from_slice(&q);
        }
        x
    }

    /// The positions at which the couplings carry the forces of state `x` (its speeds; inputs
    /// `u`; drag and friction at those speeds) while the line accelerates as a rigid body:
    /// K q = f − M R α with Rᵀ(f − M R α) = 0 (R the rigid-body modes, the null space of the
    /// stiffness matrix K), q = K⁺(f − M R α); a coupling with play then twisted further by half
    /// its play on the side it carries (one that carries nothing in the middle of its play). `None` for a line without springs or where the forces
    /// are not finite.
    pub fn quasi_static_positions(&self, x: &[f64], u: &[f64]) -> Option<Vec<f64>> {
        let n = self.n;
        if self.couplings.iter().all(|s| s.c <= 0.0) {
            return None;
        }
        // the forces at rigid motion (no twist, no twist rate: the couplings carry nothing)
        let mut rigid = x.to_vec();
        rigid[..n].fill(0.0);
        let mut dx = vec![0.0; self.nstates];
        self.rhs(&rigid, u, &mut dx);
        let f = DVector::from_fn(n, |i, _| dx[n + i] / self.inv_j[i]);
        let mut k = DMatrix::zeros(n, n);
        let mut e = DMatrix::zeros(self.couplings.len(), n);
        for (row, s) in self.couplings.iter().enumerate() {
            for &(i, a) in &self.terms[s.terms.0..s.terms.1] {
                e[(row, i)] += a;
            }
            let ek = e.row(row).transpose();
            k += s.c * &ek * ek.transpose();
        }
        let svd = k.clone().svd(true, true);
        let tol = 1e-9 * svd.singular_values.max();
        let v = svd.v_t.as_ref()?.transpose();
        let rigid_modes: Vec<usize> = (0..n).filter(|&i| svd.singular_values[i] <= tol).collect();
        let mut g = f.clone();
        if !rigid_modes.is_empty() {
            let r = DMatrix::from_fn(n, rigid_modes.len(), |i, j| v[(i, rigid_modes[j])]);
            let m = DMatrix::from_diagonal(&DVector::from_fn(n, |i, _| 1.0 / self.inv_j[i]));
            let alpha = (r.transpose() * &m * &r).try_inverse()? * r.transpose() * &f;
            g -= m * r * alpha;
        }
        let mut q = svd.pseudo_inverse(tol).ok()? * g;
        let widen = DVector::from_fn(self.couplings.len(), |row, _| {
            let s = &self.couplings[row];
            let twist = (e.row(row) * &q)[0];
            // an unloaded coupling (no twist) sits in the middle of its play
            if s.half > 0.0 && twist != 0.0 {
                s.half * twist.signum()
            } else {
                0.0
            }
        });
        if widen.iter().any(|&w| w != 0.0) {
            q += e.pseudo_inverse(1e-12).ok()? * widen;
        }
        q.iter().all(|v| v.is_finite()).then(|| q.as_slice().to_vec())
    }

    /// The line in rigid motion at `speed` (see [`Dynamics::initial_state`]), untwisted.
    fn rigid_state(&self, speed: f64, inputs: &[f64]) -> Vec<f64> {
        let n = self.n;
        let mut x = vec![0.0; self.nstates];
        x[n..2 * n].fill(speed);
        // outwards from the first body through every coupling that joins two bodies (a gear
        // stage between neighbours, a gear mesh or shaft given by the bodies it joins, a
        // compliance): the second body turns so that the twist does not change, e_a v_a + e_b v_b
        // = 0. A body that no such coupling reaches (an open differential's) keeps the speed.
        let mut known = vec![false; n];
        known[0] = true;
        let mut changed = true;
        while changed {
            changed = false;
            for s in &self.couplings {
                let &[(a, ea), (b, eb)] = &self.terms[s.terms.0..s.terms.1] else { continue };
                let (from, to, ratio) = match (known[a], known[b]) {
                    (true, false) => (a, b, -ea / eb),
                    (false, true) => (b, a, -eb / ea),
                    _ => continue,
                };
                x[n + to] = x[n + from] * ratio;
                known[to] = true;
                changed = true;
            }
        }
        for (k, &(_, _, tau, z)) in self.inputs.iter().enumerate() {
            if tau > 0.0 {
                x[z] = inputs.get(k).copied().unwrap_or(0.0);
            }
        }
        x
    }

    /// An output at state `x`: a body's position or speed, a coupling's force.
    pub fn output(&self, x: &[f64], what: (Quantity, usize)) -> f64 {
        let n = self.n;
        match what {
            (Quantity::Position, i) => x[i],
            (Quantity::Speed, i) => x[n + i],
            (Quantity::CouplingForce, i) => {
                let s = &self.couplings[i];
                let (twist, rate) = self.twist(s, x);
                coupling_force(s.c, s.d, s.half, twist, rate)
            }
        }
    }

    fn simulate_flat(
        &self,
        inputs: &[Vec<f64>],
        dt: f64,
        initial_speed: f64,
        outputs: &[(Quantity, usize)],
    ) -> Result<Vec<f64>> {
        let signals: Vec<&[f64]> = inputs.iter().map(Vec::as_slice).collect();
        self.simulate_flat_from(self.record_start(inputs, initial_speed), &signals, dt, outputs)
    }

    /// The state a record starts from: rigid motion at `initial_speed` of the first body,
    /// lagged inputs at their first value.
    pub(crate) fn record_start(&self, inputs: &[Vec<f64>], initial_speed: f64) -> Vec<f64> {
        let first: Vec<f64> = inputs.iter().map(|u| u.first().copied().unwrap_or(0.0)).collect();
        self.initial_state(initial_speed, &first)
    }

    /// Simulates the model from state `x0` under the sampled `inputs` and returns the
    /// `outputs` at the sample instants, one vector each ([`Dynamics::simulate_flat_from`]).
    pub fn simulate_from(
        &self,
        x0: Vec<f64>,
        inputs: &[&[f64]],
        dt: f64,
        outputs: &[(Quantity, usize)],
    ) -> Result<Vec<Vec<f64>>> {
        Ok(split_outputs(self.simulate_flat_from(x0, inputs, dt, outputs)?, outputs.len()))
    }

    /// Simulates the model from state `x0` under the sampled `inputs` (one signal per input,
    /// sample time `dt`, each held over a sample and shifted by its input's dead time, the
    /// first value held before the start) and returns the `outputs` at the sample instants, one
    /// after another in one vector (output o's sample k at o·len + k, len the inputs' length).
    /// A linear model is stepped exactly (ZOH of each piece of a sample between the dead
    /// times' fractions); a nonlinear one by [`PiecewiseRk4`] with [`Dynamics::rk4_steps_s`],
    /// the pieces of a play that is its only nonlinearity exactly, a friction that is while
    /// it slides whole ([`Dynamics::exact_steps`]).
    pub fn simulate_flat_from(
        &self,
        x0: Vec<f64>,
        inputs: &[&[f64]],
        dt: f64,
        outputs: &[(Quantity, usize)],
    ) -> Result<Vec<f64>> {
        self.run(x0, inputs, dt, outputs, None)
    }

    /// The one-step-ahead prediction of the `outputs` (the `predictor` module): as
    /// [`Dynamics::simulate_flat_from`], the state corrected after each sample k by `gain`
    /// (states × outputs, a `Predictor`'s) times the `measured` outputs' (one signal per output,
    /// as long as the inputs) departure from sample k's prediction, which is what is returned.
    pub fn predict_flat_from(
        &self,
        x0: Vec<f64>,
        inputs: &[&[f64]],
        dt: f64,
        outputs: &[(Quantity, usize)],
        measured: &[&[f64]],
        gain: &DMatrix<f64>,
    ) -> Result<Vec<f64>> {
        let len = inputs.first().map_or(0, |u| u.len());
        if measured.len() != outputs.len() || measured.iter().any(|y| y.len() != len) {
            return Err(PlantError::Invalid("one measured signal per output, as long as the inputs".into()));
        }
        if gain.shape() != (self.nstates, outputs.len()) {
            return Err(PlantError::Invalid(format!(
                "a predictor of {:?} gains for a model of {} states and {} outputs",
                gain.shape(),
                self.nstates,
                outputs.len()
            )));
        }
        self.run(x0, inputs, dt, outputs, Some((measured, gain)))
    }

    /// The simulation of [`Dynamics::simulate_flat_from`], corrected after each sample where
    /// `correction` gives the measured outputs and the gain ([`Dynamics::predict_flat_from`]).
    fn run(
        &self,
        x0: Vec<f64>,
        inputs: &[&[f64]],
        dt: f64,
        outputs: &[(Quantity, usize)],
        correction: Option<(&[&[f64]], &DMatrix<f64>)>,
    ) -> Result<Vec<f64>> {
        let (n, ns, m) = (self.n, self.nstates, self.inputs.len());
        if x0.len() != ns {
            return Err(PlantError::Invalid(format!(
                "a start state of {} values for a model of {ns} states",
                x0.len()
            )));
        }
        if inputs.len() != m {
            return Err(PlantError::Invalid(format!("{} input signals for a model of {m} inputs", inputs.len())));
        }
        let len = inputs.first().map_or(0, |u| u.len());
        if inputs.iter().any(|u| u.len() != len) || !(dt.is_finite() && dt > 0.0) {
            return Err(PlantError::Invalid("inputs of different lengths or a bad sample time".into()));
        }
        for &(q, i) in outputs {
            let count = if q == Quantity::CouplingForce { self.couplings.len() } else { n };
            if i >= count {
                return Err(PlantError::Invalid(format!("output {q:?} of element {} is outside the line", i + 1)));
            }
        }
        // dead times in whole samples and a fraction; the pieces of a sample start at the
        // distinct fractions
        let shifts: Vec<(usize, f64)> = self
            .inputs
            .iter()
            .map(|&(_, delay, _, _)| {
                let s = delay / dt;
                let mut whole = s.floor();
                let mut frac = s - whole;
                if frac > 1.0 - 1e-9 {
                    whole += 1.0;
                    frac = 0.0;
                }
                if frac < 1e-9 {
                    frac = 0.0;
                }
                (whole.min(len as f64) as usize, frac)
            })
            .collect();
        let mut starts: Vec<f64> =
            std::iter::once(0.0).chain(shifts.iter().map(|s| s.1).filter(|&f| f > 0.0)).collect();
        starts.sort_by(|a, b| a.total_cmp(b));
        starts.dedup();
        let pieces: Vec<(f64, f64)> =
            starts.iter().enumerate().map(|(p, &s)| (s, starts.get(p + 1).copied().unwrap_or(1.0) - s)).collect();

        let mut x = x0;
        let mut y = vec![0.0; outputs.len() * len];
        let mut u = vec![0.0; m];
        // per piece, how many samples back each input's value lies
        let backs: Vec<Vec<usize>> = pieces
            .iter()
            .map(|&(phase, _)| shifts.iter().map(|&(whole, frac)| whole + usize::from(phase < frac)).collect())
            .collect();
        let input_at = |u: &mut [f64], k: usize, p: usize| {
            for ((uj, sig), &back) in u.iter_mut().zip(inputs).zip(&backs[p]) {
                *uj = sig[k.saturating_sub(back)];
            }
        };
        // an output that is a state is read off it, a coupling's force computed
        let sources: Vec<Option<usize>> = outputs
            .iter()
            .map(|&(q, i)| match q {
                Quantity::Position => Some(i),
                Quantity::Speed => Some(n + i),
                Quantity::CouplingForce => None,
            })
            .collect();
        let record = |y: &mut [f64], x: &[f64], k: usize| {
            for (j, (&o, source)) in outputs.iter().zip(&sources).enumerate() {
                y[j * len + k] = match *source {
                    Some(i) => x[i],
                    None => self.output(x, o),
                };
            }
        };
        // the state moved toward sample k's measurement, x += L (y_k − ŷ_k)
        let correct = |x: &mut [f64], y: &[f64], k: usize| {
            if let Some((measured, gain)) = correction {
                for (o, signal) in measured.iter().enumerate() {
                    let innovation = signal[k] - y[o * len + k];
                    for (i, xi) in x.iter_mut().enumerate() {
                        *xi += gain[(i, o)] * innovation;
                    }
                }
            }
        };
        // the state checked for divergence every this many samples and at the last
        const CHECK_EVERY: usize = 64;
        let diverged =
            |x: &[f64], k: usize| (k.is_multiple_of(CHECK_EVERY) || k + 1 == len) && !x.iter().all(|v| v.is_finite());
        let divergence = |k: usize| {
            PlantError::Numerical(format!("the simulation diverged by sample {k} (within the last {CHECK_EVERY})"))
        };

        if !self.nonlinear {
            // exact ZOH of each piece length, one pass over [Φ Γ]'s columns per piece
            // (`AffineStep`) where the state fits it, else a row at a time
            let (a, b) = self.linear();
            let mut maps = Vec::with_capacity(pieces.len());
            for &(_, frac) in &pieces {
                let (phi, gamma) = zoh(&a, &b, frac * dt)?;
                maps.push(Zoh::new(phi, gamma));
            }
            let mut next = vec![0.0; ns];
            for k in 0..len {
                record(&mut y, &x, k);
                correct(&mut x, &y, k);
                for (p, map) in maps.iter().enumerate() {
                    input_at(&mut u, k, p);
                    map.apply(&x, &u, &mut next);
                    std::mem::swap(&mut x, &mut next);
                }
                if diverged(&x, k) {
                    return Err(divergence(k));
                }
            }
            return Ok(y);
        }

        let (coarse, fine) = self.rk4_steps_s();
        let mut rk = self.integrator();
        let worst = rk.counts(dt).map(|(c, f)| c as f64 * f as f64);
        if !(coarse > 0.0 && fine > 0.0 && coarse.is_finite() && fine.is_finite())
            || worst.is_none_or(|w| w > FINE_PER_COARSE * MAX_SUBSTEPS as f64)
        {
            return Err(PlantError::Invalid(format!(
                "the model needs up to {:.0} integration steps per sample (steps of {coarse:.3e} s, {fine:.3e} s where \
                 contact or friction switches, at a {dt} s sample): too stiff for this sample rate (a friction \
                 smoothing speed or an element far stiffer than the data can show)",
                worst.unwrap_or(f64::INFINITY)
            )));
        }
        // each step starts in the piece the last one ended in (pieces do not depend on inputs);
        // with play that engages at once and nothing else nonlinear, a step that stays in its
        // piece is exact
        let lengths: Vec<f64> = pieces.iter().map(|&(_, frac)| frac * dt).collect();
        let exact = self.exact_steps(&lengths);
        let mut piece = None;
        for k in 0..len {
            record(&mut y, &x, k);
            if correction.is_some() {
                correct(&mut x, &y, k);
                // the correction may have moved the state into another piece
                piece = None;
            }
            for (p, &(_, frac)) in pieces.iter().enumerate() {
                input_at(&mut u, k, p);
                let maps = exact.as_ref().and_then(|maps| maps.get(p));
                piece = rk.advance_from(&mut HeldInputs { d: self, u: &u, maps }, &mut x, frac * dt, piece).1;
            }
            if diverged(&x, k) {
                return Err(divergence(k));
            }
        }
        Ok(y)
    }
}

/// An exact step x⁺ = Φ x + Γ u of a linear model.
enum Zoh {
    /// Summed over columns (small models).
    Columns(AffineStep),
    /// Row by row: Φ and Γ row-major.
    Rows { phi: Vec<f64>, gamma: Vec<f64>, ns: usize, m: usize },
}

impl Zoh {
    fn new(phi: DMatrix<f64>, gamma: DMatrix<f64>) -> Zoh {
        let (ns, m) = (phi.nrows(), gamma.ncols());
        match AffineStep::new(phi.as_slice(), gamma.as_slice(), &vec![0.0; ns]) {
            Some(step) => Zoh::Columns(step),
            // row-major: the transpose's column-major storage
            None => Zoh::Rows {
                phi: phi.transpose().as_slice().to_vec(),
                gamma: gamma.transpose().as_slice().to_vec(),
                ns,
                m,
            },
        }
    }

    fn apply(&self, x: &[f64], u: &[f64], out: &mut [f64]) {
        match self {
            Zoh::Columns(step) => step.apply(x, u, out),
            Zoh::Rows { phi, gamma, ns, m } => {
                for (r, o) in out.iter_mut().enumerate().take(*ns) {
                    let pr = &phi[r * ns..(r + 1) * ns];
                    let gr = &gamma[r * m..(r + 1) * m];
                    *o = pr.iter().zip(x).map(|(a, b)| a * b).sum::<f64>()
                        + gr.iter().zip(u).map(|(a, b)| a * b).sum::<f64>();
                }
            }
        }
    }
}

/// Where `v` lies about a band ±`half`: 0 inside, 1 above, 2 below (a play's pieces, a
/// friction's steep band; [`Dynamics::piece`]).
fn side(v: f64, half: f64) -> u64 {
    u64::from(v > half) + 2 * u64::from(v < -half)
}

/// One element's class folded into a piece key ([`Dynamics::piece`]).
fn mix_piece(key: u64, class: u64) -> u64 {
    (key ^ class).wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(1)
}

/// Friction's slope F_c v_s²/(J (v² + v_s²)^{3/2}) times the step, at most, where
/// [`ExactSteps::Sliding`] steps a sample whole: the second-order treatment of the friction
/// force then errs by about this cubed over six per step, below RK4's at its own step bound
/// ([`RK4_STEP_TIMES_RATE`], (0.5)⁵/120 per step).
pub const SLIDING_SLOPE_TIMES_STEP: f64 = 0.01;

/// The whole-step maps of a model over one step length ([`Dynamics::exact_steps`]).
#[derive(Debug, Clone)]
pub enum ExactSteps {
    /// Play that engages at once, nothing else nonlinear: each of its three pieces is linear.
    Play(Box<PieceMaps>),
    /// Friction, nothing else nonlinear but play that engages at once: the linear part (of the
    /// play's piece) exact and the frictions as forces, while each (body, band) slides clear
    /// of its band.
    Sliding {
        /// The step: one, or with play one per piece (inside, beyond, below; the play's offset
        /// an input held at 1 beyond the model's).
        maps: Box<[ForcedMaps]>,
        /// Each body with friction and the half-width of speeds where the step is not taken.
        bodies: Vec<(usize, f64)>,
    },
}

impl ExactSteps {
    /// The step length, s.
    pub fn h(&self) -> f64 {
        match self {
            ExactSteps::Play(maps) => maps.h(),
            ExactSteps::Sliding { maps, .. } => maps[0].h(),
        }
    }
}

/// The dynamics with the inputs held over a step.
pub struct HeldInputs<'a> {
    /// The model.
    pub d: &'a Dynamics,
    /// The inputs after their dead times.
    pub u: &'a [f64],
    /// The whole steps it may take ([`Dynamics::exact_steps`]).
    pub maps: Option<&'a ExactSteps>,
}

impl PiecewiseSmooth for HeldInputs<'_> {
    #[inline]
    fn rhs(&mut self, x: &[f64], dx: &mut [f64]) {
        self.d.rhs(x, self.u, dx);
    }
    #[inline]
    fn piece(&mut self, x: &[f64]) -> u64 {
        self.d.piece(x)
    }
    /// With play that engages at once and nothing else nonlinear, the piece's key is the plays'
    /// one class: inside (0), beyond (1), below (2), the order of [`PieceMaps`].
    /// With friction and nothing else nonlinear but such play, a step where every body with
    /// friction slides (within the play's piece: the end's piece is checked by the integrator).
    fn exact(&mut self, piece: u64, x: &[f64], h: f64, out: &mut [f64]) -> bool {
        match self.maps {
            Some(ExactSteps::Play(maps)) => {
                let Some(index) = (0..3).find(|&class| self.d.play_piece_key(class) == piece) else { return false };
                maps.step(index, x, self.u, h, out)
            }
            Some(ExactSteps::Sliding { maps, bodies }) => {
                if maps[0].h() != h {
                    return false;
                }
                if let [map] = &maps[..] {
                    return self.d.slide(map, bodies, x, self.u, out);
                }
                // with play: the piece's map, its offset an input held at 1
                let m = self.u.len();
                let mut u = [0.0; MAX_INPUTS + 1];
                u[..m].copy_from_slice(self.u);
                u[m] = 1.0;
                self.d.slide(&maps[self.d.play_class(x)], bodies, x, &u[..=m], out)
            }
            None => false,
        }
    }
}

/// A coupling as the right-hand side steps it.
#[derive(Debug, Clone, Copy)]
struct Spring {
    c: f64,
    d: f64,
    half: f64,
    /// Range of its coefficients in `Dynamics::terms`.
    terms: (usize, usize),
    /// 1/ratio of a coupling between neighbours (None: an elongation of its own).
    gear: Option<f64>,
}

/// Force of a coupling with play: the spring acts on the twist beyond ± half the play, the
/// damper only in contact.
fn coupling_force(c: f64, d: f64, half: f64, twist: f64, rate: f64) -> f64 {
    if half <= 0.0 {
        c * twist + d * rate
    } else if twist > half {
        c * (twist - half) + d * rate
    } else if twist < -half {
        c * (twist + half) + d * rate
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::line::{Coupling, Domain, LineBody};
    use approx::assert_relative_eq;

    fn mass(m: f64, drag: f64) -> DriveModel {
        DriveModel {
            line: Line {
                domain: Domain::Translational,
                bodies: vec![LineBody { name: "carriage".into(), inertia: m, drag }],
                couplings: vec![],
            },
            inputs: vec![0],
            effects: vec![],
        }
    }

    /// Two bodies driven at the first, joined by `coupling`.
    fn two_bodies(inertia: [f64; 2], drag: [f64; 2], coupling: Coupling, effects: Vec<Effect>) -> DriveModel {
        DriveModel {
            line: Line {
                domain: Domain::Rotational,
                bodies: vec![
                    LineBody { name: "a".into(), inertia: inertia[0], drag: drag[0] },
                    LineBody { name: "b".into(), inertia: inertia[1], drag: drag[1] },
                ],
                couplings: vec![coupling],
            },
            inputs: vec![0],
            effects,
        }
    }

    fn gear_line() -> Line {
        Line {
            domain: Domain::Rotational,
            bodies: vec![
                LineBody { name: "motor".into(), inertia: 0.002, drag: 1e-4 },
                LineBody { name: "hub".into(), inertia: 0.0004, drag: 0.0 },
                LineBody { name: "load".into(), inertia: 0.05, drag: 0.004 },
            ],
            couplings: vec![Coupling::new(800.0, 0.02, 1.0), Coupling::new(20000.0, 0.5, 4.0)],
        }
    }

    /// The three-mass strand (eqs. (14), (18)) and the paper's full chain (Table A1, 22 bodies)
    /// as drive models: their linearisation — the one right-hand side's, probed state by state —
    /// equals the mechanical models' J⁻¹C and J⁻¹D, and the chain's frequencies the chain's
    /// modes (to 1e-9: round-off of two assemblies of the same matrices).
    #[test]
    fn the_strand_and_a_chain_are_drive_models() {
        let rig = crate::paper::damped_params();
        let strand = rig.three_mass(crate::rig::Variant::V1).unwrap();
        let chain = crate::chain::Chain::from_bodies(&crate::paper::table_a1()).unwrap().mechanical();
        for (m, inputs) in [(strand, vec![0, 1, 2]), (chain, vec![0])] {
            let d = DriveModel::from_mechanical(&m, inputs.clone()).unwrap();
            let (a, b) = d.linearisation().unwrap();
            let ss = m.state_space(&[crate::mechanical::Output::Speeds]).unwrap();
            let scale = ss.a.abs().max();
            assert!((&a - &ss.a).abs().max() <= 1e-9 * scale, "A differs");
            assert!((&b - ss.b.select_columns(&inputs)).abs().max() <= 1e-9 * ss.b.abs().max(), "B differs");
            let f = d.line.model().unwrap().modes().unwrap().frequencies_hz;
            let g = m.modes().unwrap().frequencies_hz;
            for (x, y) in f.iter().zip(&g) {
                assert!((x - y).abs() <= 1e-9 * g.last().unwrap(), "{f:?} vs {g:?}");
            }
        }
        let side_gears = rig.open_differential_with_side_gears(crate::rig::Variant::V1, 0.002).unwrap();
        assert!(DriveModel::from_mechanical(&side_gears, vec![1]).unwrap_err().to_string().contains("inertia matrix"));
    }

    /// The controller's state space equals the mechanical model's (`Line::state_space`, built
    /// from J, C, D matrices), speeds and coupling forces; a dead time is reported beside it.
    /// A record without samples gives one empty signal per output, as many as were asked for.
    #[test]
    fn a_flat_simulation_splits_into_one_signal_per_output() {
        assert_eq!(split_outputs(Vec::new(), 3), vec![Vec::<f64>::new(); 3]);
        assert_eq!(split_outputs(vec![1.0, 2.0, 3.0, 4.0], 2), vec![vec![1.0, 2.0], vec![3.0, 4.0]]);
        assert!(split_outputs(Vec::new(), 0).is_empty());
    }

    #[test]
    fn control_state_space_is_the_mechanical_one() {
        let line = gear_line();
        let model = DriveModel {
            line: line.clone(),
            inputs: vec![0],
            effects: vec![Effect::TimeDelay(TimeDelay { input: 0, delay_s: 0.003 })],
        };
        let ss = model.control_state_space().unwrap();
        let outputs = [
            (Quantity::Speed, 0),
            (Quantity::Speed, 1),
            (Quantity::Speed, 2),
            (Quantity::CouplingForce, 0),
            (Quantity::CouplingForce, 1),
        ];
        let reference = line.state_space(&[0], &outputs).unwrap();
        for (m, r) in [(&ss.a, &reference.a), (&ss.b, &reference.b), (&ss.c, &reference.c)] {
            assert!((m - r).abs().max() <= 1e-12 * r.abs().max(), "{m} vs {r}");
        }
        assert_eq!(ss.output_names, ["w_motor", "w_hub", "w_load", "T_coupling_1", "T_coupling_2"]);
        assert_eq!(ss.input_names, ["M_motor"]);
        assert_eq!(model.input_delays_s(), [0.003]);
    }

    /// The dead time's position in the parameter list, behind friction (two parameters) and a
    /// lag, is the parameter of that name and value.
    #[test]
    fn delay_parameter_points_at_the_dead_time() {
        let model = DriveModel {
            line: gear_line(),
            inputs: vec![0, 2],
            effects: vec![
                Effect::CoulombFriction(CoulombFriction { body: 2, friction: 0.2, smoothing_speed: 0.05 }),
                Effect::ActuatorLag(ActuatorLag { input: 0, time_constant_s: 0.004 }),
                Effect::TimeDelay(TimeDelay { input: 1, delay_s: 0.007 }),
            ],
        };
        let list = model.parameter_list();
        let i = model.delay_parameter(1).unwrap();
        assert_eq!((list[i].name.as_str(), list[i].value), ("M_load.delay", 0.007));
        assert_eq!(model.delay_parameter(0), None);
    }

    /// Without effects the exact ZOH equals the mechanical model's own state space
    /// (`Line::state_space`, built from J, C, D matrices) simulated by `lsim`.
    #[test]
    fn the_linear_path_equals_the_mechanical_state_space() {
        let line = gear_line();
        let model = DriveModel { line: line.clone(), inputs: vec![0], effects: vec![] };
        let u: Vec<f64> = (0..2000).map(|k| (k as f64 * 0.013).sin() + 0.3 * (k as f64 * 0.11).sin()).collect();
        let outputs =
            [(Quantity::Speed, 0), (Quantity::Speed, 2), (Quantity::CouplingForce, 1), (Quantity::Position, 2)];
        let y = model.simulate(std::slice::from_ref(&u), 1e-3, 0.0, &outputs).unwrap();
        let ss = line.state_space(&[0], &outputs).unwrap();
        let reference = ss.lsim(&DMatrix::from_column_slice(u.len(), 1, &u), 1e-3, &DVector::zeros(6)).unwrap();
        for (o, yo) in y.iter().enumerate() {
            let scale = reference.column(o).amax();
            for k in 0..u.len() {
                assert!((yo[k] - reference[(k, o)]).abs() <= 1e-9 * scale, "output {o} sample {k}");
            }
        }
    }

    /// A free mass m under a unit force step recorded at t = 0 and a dead time of 2.4 samples:
    /// v(t) = (t − τ)/m after the dead time, exactly, also at the fractional switching instant.
    #[test]
    fn a_fractional_dead_time_shifts_the_response_exactly() {
        let (m, dt, tau) = (2.0, 1e-3, 2.4e-3);
        let mut model = mass(m, 0.0);
        model.effects.push(Effect::TimeDelay(TimeDelay { input: 0, delay_s: tau }));
        let mut u = vec![1.0; 50];
        u[0] = 0.0; // held before the start: the step is at t = dt
        let y = model.simulate(&[u], dt, 0.0, &[(Quantity::Speed, 0)]).unwrap();
        for (k, v) in y[0].iter().enumerate() {
            let t = k as f64 * dt;
            assert_relative_eq!(*v, ((t - dt - tau).max(0.0)) / m, epsilon = 1e-12);
        }
    }

    /// A first-order lag τ on a force step of 1 at t = dt: v = ((t−dt) − τ(1 − e^(−(t−dt)/τ)))/m.
    #[test]
    fn an_actuator_lag_is_the_first_order_law() {
        let (m, dt, tau) = (3.0, 1e-3, 0.02);
        let mut model = mass(m, 0.0);
        model.effects.push(Effect::ActuatorLag(ActuatorLag { input: 0, time_constant_s: tau }));
        let mut u = vec![1.0; 200];
        u[0] = 0.0;
        let y = model.simulate(&[u], dt, 0.0, &[(Quantity::Speed, 0)]).unwrap();
        for (k, v) in y[0].iter().enumerate().skip(1) {
            let s = (k - 1) as f64 * dt;
            assert_relative_eq!(*v, (s - tau * (1.0 - (-s / tau).exp())) / m, epsilon = 1e-12);
        }
    }

    /// Coulomb friction F_c under a constant force F > F_c: once the speed is well above the
    /// smoothing speed the mass accelerates at (F − F_c)/m; the smoothing only leaves the mass
    /// ahead of the sharp law by less than the smoothing speed.
    #[test]
    fn coulomb_friction_takes_its_force_off_the_drive() {
        let (m, f, fc, vs, dt) = (5.0, 10.0, 4.0, 1e-3, 1e-3);
        let mut model = mass(m, 0.0);
        model.effects.push(Effect::CoulombFriction(CoulombFriction { body: 0, friction: fc, smoothing_speed: vs }));
        let y = model.simulate(&[vec![f; 1001]], dt, 0.0, &[(Quantity::Speed, 0)]).unwrap();
        let v_end = y[0][1000];
        let exact = (f - fc) / m * 1.0;
        assert!((v_end - exact).abs() < vs, "{v_end} vs {exact}");
        // and a force below the friction leaves the body (almost) at rest: v ≤ v_s (F/F_c)/√(1 − (F/F_c)²)
        let y = model.simulate(&[vec![0.5 * fc; 1001]], dt, 0.0, &[(Quantity::Speed, 0)]).unwrap();
        assert!(y[0][1000].abs() <= vs * 0.5 / 0.75f64.sqrt() * 1.001, "{}", y[0][1000]);
    }

    /// Two masses joined by a spring with play b, the first pushed by a constant force, no
    /// damping: the second stays at rest until the twist reaches b/2, at t_c = √(b m₁ / F).
    #[test]
    fn backlash_holds_the_load_until_contact() {
        let (m1, m2, f, b, dt) = (1.0, 1.0, 2.0, 0.01, 1e-4);
        let backlash = Effect::Backlash(Backlash { coupling: 0, backlash: b });
        let model = two_bodies([m1, m2], [0.0; 2], Coupling::new(1e4, 0.0, 1.0), vec![backlash]);
        // at rest without load at the first sample (a record starts where its first input has
        // held the line: `Dynamics::initial_state`), the force stepped on after it
        let mut u = vec![f; 2000];
        u[0] = 0.0;
        let y = model.simulate(&[u], dt, 0.0, &[(Quantity::Position, 0), (Quantity::Position, 1)]).unwrap();
        let tc = (b * m1 / f).sqrt();
        for (k, (q1, q2)) in y[0].iter().zip(&y[1]).enumerate() {
            let t = (k as f64 - 1.0).max(0.0) * dt;
            if t < tc - dt {
                assert_eq!(*q2, 0.0, "t = {t}");
                assert_relative_eq!(*q1, f * t * t / (2.0 * m1), max_relative = 1e-9, epsilon = 1e-15);
            }
        }
        assert!(y[1][1999] > 0.0);
    }

    /// A record that starts under load starts wound up: two bodies through a 3:1 gear stage,
    /// no drag, a constant torque F on the first. The line accelerates as one body,
    /// a₁ = F/(J₁ + J₂/r²), and the coupling carries T = J₂ a₁/r from the first sample on — no
    /// ringing from an untwisted start (analytic; the tolerance is the RK4-free exact step's
    /// rounding over 1000 samples).
    #[test]
    fn a_record_under_load_starts_wound_up() {
        let (j1, j2, r, k, f) = (0.002, 0.05, 3.0, 800.0, 1.5);
        let model = two_bodies([j1, j2], [0.0; 2], Coupling::new(k, 0.3, r), vec![]);
        let y = model.simulate(&[vec![f; 1000]], 1e-3, 2.0, &[(Quantity::CouplingForce, 0)]).unwrap();
        let torque = j2 * f / (j1 + j2 / (r * r)) / r;
        assert_eq!(y[0].len(), 1000);
        for t in &y[0] {
            assert_relative_eq!(*t, torque, max_relative = 1e-9);
        }
    }

    /// `steps` classical RK4 steps of `h` of ẋ = f(x, u) for two bodies (x = [q1, q2, w1, w2]),
    /// written out here as the tests' reference, independent of `integrate`.
    fn rk4_written_out(
        f: &dyn Fn([f64; 4], f64) -> [f64; 4],
        mut x: [f64; 4],
        u: f64,
        h: f64,
        steps: usize,
    ) -> [f64; 4] {
        let add = |a: [f64; 4], k: [f64; 4], s: f64| std::array::from_fn::<f64, 4, _>(|i| a[i] + s * k[i]);
        for _ in 0..steps {
            let k1 = f(x, u);
            let k2 = f(add(x, k1, h / 2.0), u);
            let k3 = f(add(x, k2, h / 2.0), u);
            let k4 = f(add(x, k3, h), u);
            x = std::array::from_fn(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        }
        x
    }

    /// The torque that drives the play tests' twist through the play and back many times a
    /// second (3 Hz and 17 Hz), `n` samples of `dt`.
    fn rattling_torque(n: usize, dt: f64) -> Vec<f64> {
        (0..n)
            .map(|k| {
                let t = k as f64 * dt;
                0.5 * (std::f64::consts::TAU * 3.0 * t).sin() + 0.2 * (std::f64::consts::TAU * 17.0 * t).sin()
            })
            .collect()
    }

    /// A shaft's torque with total play `b` written out as the dead zone's own branches: stiffness
    /// `c` on the twist `s` beyond ±b/2, damping `d` on its rate `r` only in contact.
    fn shaft_with_play(c: f64, d: f64, b: f64, s: f64, r: f64) -> f64 {
        if s > b / 2.0 {
            c * (s - b / 2.0) + d * r
        } else if s < -b / 2.0 {
            c * (s + b / 2.0) + d * r
        } else {
            0.0
        }
    }

    /// A rattling play stepped exactly within its pieces ([`Dynamics::play_maps`])
    /// against RK4 written out here over 10 µs steps, the dead zone as its own branches: two
    /// bodies, a spring with 20 mrad of play damped to 35 % of critical (lighter damping makes
    /// the impacts' timing, and so any two integrations, drift apart), a two-tone torque that
    /// drives the twist through the play and back many times a second.
    #[test]
    fn a_rattling_play_stepped_exactly_matches_a_fine_rk4() {
        let (j1, j2, c, d, b, dt) = (0.01, 0.05, 1000.0, 2.0, 0.02, 1e-3);
        let backlash = Effect::Backlash(Backlash { coupling: 0, backlash: b });
        let model = two_bodies([j1, j2], [0.01, 0.02], Coupling::new(c, d, 1.0), vec![backlash]);
        assert!(Dynamics::new(&model).unwrap().play_maps(&[dt]).is_some(), "the exact path is taken");
        let u = rattling_torque(2000, dt);
        let y =
            model.simulate(std::slice::from_ref(&u), dt, 0.0, &[(Quantity::Speed, 0), (Quantity::Speed, 1)]).unwrap();
        // x = [q1, q2, w1, w2]; force in the shaft on the twist q1 − q2 beyond ±b/2
        let f = |x: [f64; 4], torque: f64| -> [f64; 4] {
            let t = shaft_with_play(c, d, b, x[0] - x[1], x[2] - x[3]);
            [x[2], x[3], (torque - t - 0.01 * x[2]) / j1, (t - 0.02 * x[3]) / j2]
        };
        let (mut x, sub) = ([0.0; 4], 100);
        let h = dt / sub as f64;
        let peak = y[0].iter().chain(&y[1]).fold(0.0f64, |m, v| m.max(v.abs()));
        let mut contacts = 0;
        let mut inside = true;
        let mut worst = 0.0f64;
        for (k, &uk) in u.iter().enumerate() {
            worst = worst.max((y[0][k] - x[2]).abs().max((y[1][k] - x[3]).abs()));
            x = rk4_written_out(&f, x, uk, h, sub);
            let now_inside = (x[0] - x[1]).abs() < b / 2.0;
            contacts += usize::from(inside && !now_inside);
            inside = now_inside;
        }
        assert!(contacts > 20, "the play was crossed {contacts} times: the test must rattle");
        // Within a piece the step is exact; each crossing is taken in fine RK4 sub-steps, whose
        // error at the kink both paths share: measured 2.7 % of the peak speed with the exact
        // pieces, 2.65 % with RK4 throughout (the same sub-steps), so 3.5 %.
        assert!(worst < 0.035 * peak, "worst difference {worst:.3e} of a peak speed {peak:.3}");
    }

    /// A friction stepped whole while its body slides ([`ExactSteps::Sliding`]) against RK4
    /// written out here over 10 µs steps: a motor driving a load through a stiff, lightly
    /// damped shaft (78 Hz), the load's friction 0.3 N·m smoothed over 0.01 rad/s, a torque
    /// that swings the speeds through zero twice a second (sticking, stepped by RK4 there) with
    /// a 17 Hz tone that keeps the shaft ringing while they slide.
    #[test]
    fn a_sliding_friction_stepped_whole_matches_a_fine_rk4() {
        let (j1, j2, c, d, fc, vs, dt) = (0.01, 0.05, 2000.0, 0.5, 0.3, 0.01, 1e-3);
        let friction = Effect::CoulombFriction(CoulombFriction { body: 1, friction: fc, smoothing_speed: vs });
        let model = two_bodies([j1, j2], [0.01, 0.02], Coupling::new(c, d, 1.0), vec![friction]);
        let dynamics = Dynamics::new(&model).unwrap();
        let steps = dynamics.exact_steps(&[dt]).expect("friction alone has whole steps");
        let u: Vec<f64> = (0..3000)
            .map(|k| {
                let t = k as f64 * dt;
                (std::f64::consts::TAU * t).sin() + 0.2 * (std::f64::consts::TAU * 17.0 * t).sin()
            })
            .collect();
        let y =
            model.simulate(std::slice::from_ref(&u), dt, 0.0, &[(Quantity::Speed, 0), (Quantity::Speed, 1)]).unwrap();
        // x = [q1, q2, w1, w2]
        let f = |x: [f64; 4], torque: f64| -> [f64; 4] {
            let t = c * (x[0] - x[1]) + d * (x[2] - x[3]);
            let friction = fc * x[3] / (x[3] * x[3] + vs * vs).sqrt();
            [x[2], x[3], (torque - t - 0.01 * x[2]) / j1, (t - 0.02 * x[3] - friction) / j2]
        };
        let (mut x, sub) = ([0.0; 4], 100);
        let h = dt / sub as f64;
        let peak = y[0].iter().chain(&y[1]).fold(0.0f64, |m, v| m.max(v.abs()));
        let (mut worst, mut whole, mut reversals) = (0.0f64, 0, 0);
        let mut out = [0.0; 4];
        for (k, &uk) in u.iter().enumerate() {
            worst = worst.max((y[0][k] - x[2]).abs().max((y[1][k] - x[3]).abs()));
            let mut held = HeldInputs { d: &dynamics, u: &[uk], maps: Some(&steps[0]) };
            whole += usize::from(held.exact(0, &x, dt, &mut out));
            let before = x[3];
            x = rk4_written_out(&f, x, uk, h, sub);
            reversals += usize::from((before > 0.0) != (x[3] > 0.0));
        }
        assert!(reversals >= 5, "the load reversed {reversals} times: the test must stick and slip");
        assert!(whole > u.len() / 2, "{whole} of {} samples stepped whole", u.len());
        // measured: 8.8e-6 of the peak speed with the whole steps (2892 of 3000 samples), and
        // 1.9e-5 with `Dynamics`'s RK4 at its own steps throughout (the band made infinite), so
        // the bound is 3e-5: the whole steps may not err more than the RK4 they replace
        assert!(worst < 3e-5 * peak, "worst difference {worst:.3e} of a peak speed {peak:.3}");
    }

    /// Play and a friction stepped whole together ([`ExactSteps::Sliding`] with one map per piece
    /// of the play) against RK4 written out here over 10 µs steps: the rattling play of the test
    /// above with the load's friction 0.05 N·m smoothed over 0.01 rad/s, the torque swinging the
    /// load's speed through zero three times a second.
    #[test]
    fn play_and_friction_stepped_whole_match_a_fine_rk4() {
        let (j1, j2, c, d, b, fc, vs, dt) = (0.01, 0.05, 1000.0, 2.0, 0.02, 0.05, 0.01, 1e-3);
        let effects = vec![
            Effect::Backlash(Backlash { coupling: 0, backlash: b }),
            Effect::CoulombFriction(CoulombFriction { body: 1, friction: fc, smoothing_speed: vs }),
        ];
        let model = two_bodies([j1, j2], [0.01, 0.02], Coupling::new(c, d, 1.0), effects);
        let dynamics = Dynamics::new(&model).unwrap();
        let steps = dynamics.exact_steps(&[dt]).expect("play and friction have whole steps");
        let u = rattling_torque(2000, dt);
        let y =
            model.simulate(std::slice::from_ref(&u), dt, 0.0, &[(Quantity::Speed, 0), (Quantity::Speed, 1)]).unwrap();
        let f = |x: [f64; 4], torque: f64| -> [f64; 4] {
            let t = shaft_with_play(c, d, b, x[0] - x[1], x[2] - x[3]);
            let friction = fc * x[3] / (x[3] * x[3] + vs * vs).sqrt();
            [x[2], x[3], (torque - t - 0.01 * x[2]) / j1, (t - 0.02 * x[3] - friction) / j2]
        };
        let (mut x, sub) = ([0.0; 4], 100);
        let h = dt / sub as f64;
        let peak = y[0].iter().chain(&y[1]).fold(0.0f64, |m, v| m.max(v.abs()));
        let (mut worst, mut whole, mut contacts, mut reversals, mut inside) = (0.0f64, 0, 0, 0, true);
        let mut out = [0.0; 4];
        for (k, &uk) in u.iter().enumerate() {
            worst = worst.max((y[0][k] - x[2]).abs().max((y[1][k] - x[3]).abs()));
            let mut held = HeldInputs { d: &dynamics, u: &[uk], maps: Some(&steps[0]) };
            let piece = dynamics.piece(&x);
            whole += usize::from(held.exact(piece, &x, dt, &mut out) && dynamics.piece(&out) == piece);
            let before = x[3];
            x = rk4_written_out(&f, x, uk, h, sub);
            reversals += usize::from((before > 0.0) != (x[3] > 0.0));
            let now_inside = (x[0] - x[1]).abs() < b / 2.0;
            contacts += usize::from(inside && !now_inside);
            inside = now_inside;
        }
        assert!(
            contacts > 20 && reversals >= 5,
            "{contacts} contacts, {reversals} reversals: the test must rattle and stick"
        );
        assert!(whole > u.len() / 2, "{whole} of {} samples stepped whole", u.len());
        // measured: 2.84 % of the peak speed with the whole steps (1857 of 2000 samples), 2.81 %
        // with RK4 throughout (as the build before stepped this model): the crossings of the
        // play, taken in fine RK4 sub-steps by both, dominate, so the play test's 3.5 %
        assert!(worst < 0.035 * peak, "worst difference {worst:.3e} of a peak speed {peak:.3}");
    }

    #[test]
    fn bad_effects_are_named() {
        let mut model = mass(1.0, 0.0);
        model.effects.push(Effect::Backlash(Backlash { coupling: 0, backlash: 0.1 }));
        assert!(model.validate().unwrap_err().to_string().contains("effects[1] (backlash)"));
        model.effects[0] = Effect::TimeDelay(TimeDelay { input: 0, delay_s: -1.0 });
        assert!(model.validate().unwrap_err().to_string().contains("positive"));
        model.effects[0] = Effect::TimeDelay(TimeDelay { input: 0, delay_s: 1e-3 });
        model.effects.push(Effect::TimeDelay(TimeDelay { input: 0, delay_s: 2e-3 }));
        assert!(model.validate().unwrap_err().to_string().contains("twice"));
        // friction smoothed far below what the sample rate can resolve: refused, not ground out
        let mut model = mass(1.0, 0.0);
        model.effects.push(Effect::CoulombFriction(CoulombFriction { body: 0, friction: 1e3, smoothing_speed: 1e-12 }));
        let e = model.simulate(&[vec![1.0; 10]], 1e-3, 0.0, &[(Quantity::Speed, 0)]).unwrap_err();
        assert!(e.to_string().contains("too stiff"), "{e}");
    }
}
