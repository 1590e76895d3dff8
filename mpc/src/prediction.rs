//! Any model as the controller sees it: a linear prediction model with input dead times, and
//! the settings its `[mpc]` section gives — the paper rig (the open-differential powertrain with
//! the effects a rig file declares or the diagnosis found) and any drive model alike.

use plant::rig::DriveEffects;
use plant::rig::{RigParams, Variant};
use plant::statespace::StateSpace;
use plant::DriveModel;

use crate::error::{MpcError, Result};
use crate::{MpcSection, MpcSettings};

/// What the controller predicts with: the model's linearisation
/// (`plant::DriveModel::control_state_space`, the rig's with its own names:
/// [`rig_control_state_space`]) and the inputs' dead times, the same for the paper rig and any
/// drive model ([`Design::prediction`]). Backlash and friction
/// are left out of the prediction (linear in contact, without friction): [`Prediction::notes`]
/// says so.
#[derive(Debug, Clone)]
pub struct Prediction {
    /// Continuous linear model. The rig's: inputs M_m2, M_drive, M_m3; outputs w_m2, w_drive,
    /// w_m3, T_short_side_shaft, T_long_side_shaft (and w_motor with a drive compliance). A drive
    /// model's: its inputs; its bodies' speeds and its couplings' forces.
    pub model: StateSpace,
    /// Dead time of each input, s.
    pub input_delays_s: Vec<f64>,
    /// What the prediction includes and leaves out, in words.
    pub notes: Vec<String>,
    /// Free motion at unit speed — every body turning together as its gears allow, the first
    /// body at 1 (rad/s or m/s; where several motions twist nothing, as an open differential's,
    /// the one nearest to every body at one speed) — or `None` where the model
    /// cannot move freely (a spring to ground holds it).
    pub motion: Option<Motion>,
}

/// Free motion of a model, x(t) = x₀ + t·`rate`: its speeds `state` (no twist), and the rate at
/// which its positions advance.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    /// The speeds, as a state.
    pub state: nalgebra::DVector<f64>,
    /// ẋ of the motion: the positions' rate.
    pub rate: nalgebra::DVector<f64>,
}

impl Motion {
    /// The motion of a model in physical coordinates [q; q̇; lags] (`n` bodies, `ns` states)
    /// whose bodies move with speeds `shape`.
    fn physical(shape: &[f64], ns: usize) -> Motion {
        let n = shape.len();
        let block = |from: usize| {
            nalgebra::DVector::from_fn(ns, |k, _| if (from..from + n).contains(&k) { shape[k - from] } else { 0.0 })
        };
        Motion { state: block(n), rate: block(0) }
    }
}

/// The paper rig's drive model `m` (`plant::DriveModel::paper_rig`) as its controller sees it:
/// its [`DriveModel::control_state_space`] (in contact, friction and the dead time left out)
/// with the rig's names, which its rig files' `[mpc]` sections and its controller FMU's
/// variables use: inputs M_m2, M_drive, M_m3 (the drive torque acts on the motor when the drive
/// is compliant), outputs w_m2, w_drive (the cage's), w_m3, T_short_side_shaft,
/// T_long_side_shaft and, with a compliance, w_motor; a lag's state M_drive_lagged.
pub fn rig_control_state_space(m: &DriveModel) -> Result<StateSpace> {
    let ss = m.control_state_space()?;
    let mut outputs = vec!["w_m2", "w_drive", "w_m3", "T_short_side_shaft", "T_long_side_shaft"];
    if m.line.bodies.len() == 4 {
        outputs.push("w_motor");
    }
    let rows = outputs
        .iter()
        .map(|o| {
            ss.output_names.iter().position(|n| n == o).ok_or_else(|| {
                MpcError::Numerical(format!(
                    "the rig's model has no output {o} (it has {})",
                    ss.output_names.join(", ")
                ))
            })
        })
        .collect::<Result<Vec<usize>>>()?;
    let lag = 2 * m.line.bodies.len();
    let mut state_names = ss.state_names;
    if let Some(name) = state_names.get_mut(lag) {
        *name = "M_drive_lagged".into();
    }
    Ok(StateSpace {
        c: ss.c.select_rows(&rows),
        d: ss.d.select_rows(&rows),
        a: ss.a,
        b: ss.b,
        state_names,
        input_names: ["M_m2", "M_drive", "M_m3"].map(String::from).into(),
        output_names: outputs.into_iter().map(String::from).collect(),
    })
}

/// The prediction model of a drive model for a controller sampling every `dt_s`: its
/// linearisation and its inputs' dead times. Modes at or beyond the loop's Nyquist frequency (a
/// gear mesh's, a stiff shaft's) are left out — the controller cannot see them, and their aliased
/// discretisation would break its Riccati equations — by projecting the line onto its slower
/// undamped modes (q = Φ_s η, Φ_sᵀ J Φ_s = I; exact for those modes without damping, Galerkin
/// with it); the notes name them.
pub fn drive_prediction(model: &DriveModel, dt_s: f64) -> Result<Prediction> {
    prediction_of(model, model.control_state_space()?, dt_s)
}

/// How the prediction holds each of `model`'s effects, as each effect says
/// ([`plant::Effect::prediction`]), named where it acts with its size.
fn effect_notes(model: &DriveModel) -> Vec<String> {
    model.effects.iter().map(|e| format!("{} is {}", e.summary(model), e.prediction())).collect()
}

/// [`drive_prediction`] from the model's control state space `ss` (the rig's: its own names).
fn prediction_of(model: &DriveModel, ss: StateSpace, dt_s: f64) -> Result<Prediction> {
    let mut notes = effect_notes(model);
    let nyquist_hz = 0.5 / dt_s;
    let (ss, dropped, motion) = without_modes_beyond(ss, model, nyquist_hz)?;
    if !dropped.is_empty() {
        let list: Vec<String> = dropped.iter().map(|f| format!("{f:.1}")).collect();
        notes.push(format!(
            "modes at {} Hz are NOT in the prediction: beyond the {nyquist_hz} Hz a controller sampling every {dt_s} s sees",
            list.join(", ")
        ));
    }
    Ok(Prediction { model: ss, input_delays_s: model.input_delays_s(), notes, motion })
}

/// `ss` (states [q; q̇; lags] of `model`) projected onto the undamped modes below `f_max_hz`,
/// the frequencies of the modes left out (Hz), and the state of free motion at unit speed (see
/// [`Prediction::motion`]).
fn without_modes_beyond(
    ss: StateSpace,
    model: &DriveModel,
    f_max_hz: f64,
) -> Result<(StateSpace, Vec<f64>, Option<Motion>)> {
    let mech = model.line.model()?;
    let n = mech.dofs();
    // J^{-1/2} K J^{-1/2} = V Ω² Vᵀ; Φ = J^{-1/2} V is J-orthonormal (the inertia is diagonal)
    let root: Vec<f64> = (0..n).map(|i| 1.0 / mech.inertia[(i, i)].sqrt()).collect();
    let k = mech.stiffness_matrix();
    let scaled = nalgebra::DMatrix::from_fn(n, n, |i, j| root[i] * k[(i, j)] * root[j]);
    let eig = scaled.symmetric_eigen();
    let omega_max = 2.0 * std::f64::consts::PI * f_max_hz;
    let hz = |w2: f64| w2.max(0.0).sqrt() / (2.0 * std::f64::consts::PI);
    let slow: Vec<usize> = (0..n).filter(|&i| eig.eigenvalues[i] < omega_max * omega_max).collect();
    let mut dropped: Vec<f64> = (0..n).filter(|i| !slow.contains(i)).map(|i| hz(eig.eigenvalues[i])).collect();
    let top = eig.eigenvalues.iter().copied().fold(0.0_f64, f64::max);
    let rigid: Vec<usize> = (0..n).filter(|&i| eig.eigenvalues[i] <= 1e-10 * top).collect();
    let ns = ss.a.nrows();
    let modes: Vec<Vec<f64>> =
        rigid.iter().map(|&i| (0..n).map(|j| root[j] * eig.eigenvectors[(j, i)]).collect()).collect();
    let motion = free_motion(&modes, &mech.inertia, &k).map(|shape| Motion::physical(&shape, ns));
    if dropped.is_empty() {
        return Ok((ss, dropped, motion));
    }
    dropped.sort_by(f64::total_cmp);
    let s = slow.len();
    let lags = ns - 2 * n;
    let phi = nalgebra::DMatrix::from_fn(n, s, |i, j| root[i] * eig.eigenvectors[(i, slow[j])]);
    // x = T ξ with ξ = [η; η̇; lags], ξ = W x with W = Φᵀ J on the mechanical blocks (W T = I)
    let nr = 2 * s + lags;
    let mut t = nalgebra::DMatrix::zeros(ns, nr);
    let mut w = nalgebra::DMatrix::zeros(nr, ns);
    let phi_t_j = phi.transpose() * &mech.inertia;
    for block in 0..2 {
        t.view_mut((block * n, block * s), (n, s)).copy_from(&phi);
        w.view_mut((block * s, block * n), (s, n)).copy_from(&phi_t_j);
    }
    for l in 0..lags {
        t[(2 * n + l, 2 * s + l)] = 1.0;
        w[(2 * s + l, 2 * n + l)] = 1.0;
    }
    let mut state_names: Vec<String> = (0..s).map(|j| format!("eta_{}", j + 1)).collect();
    state_names.extend((0..s).map(|j| format!("der(eta_{})", j + 1)));
    state_names.extend(ss.state_names[2 * n..].iter().cloned());
    let reduced = StateSpace {
        a: &w * &ss.a * &t,
        b: &w * &ss.b,
        c: &ss.c * &t,
        d: ss.d,
        state_names,
        input_names: ss.input_names,
        output_names: ss.output_names,
    };
    Ok((reduced, dropped, motion.map(|m| Motion { state: &w * m.state, rate: &w * m.rate })))
}

/// The free motion "every body turning together as its gears allow", the first body at 1, from
/// the rigid-body modes `modes` (K φ = 0, J-orthonormal) of a line of inertia `j` and stiffness
/// `k`. One mode: that mode (normalised by its largest entry where the first body does not move
/// in it). Several — an open differential, whose outputs may also turn against each other at no
/// twist (eq. (A1): the stiffness is rank one on s = 2φ_drive − φ_m2 − φ_m3) — the one nearest,
/// in kinetic energy, to every body at the same speed: the J-orthogonal projection of the
/// vector of ones onto them, which is that vector itself where it twists nothing (the paper
/// rig, as its controller has always started). `None`: no mode (a spring to ground holds the
/// line), or no free motion carries the bodies together.
fn free_motion(modes: &[Vec<f64>], j: &nalgebra::DMatrix<f64>, k: &nalgebra::DMatrix<f64>) -> Option<Vec<f64>> {
    let n = j.nrows();
    let normalised = |shape: Vec<f64>| -> Option<Vec<f64>> {
        let largest = shape.iter().copied().fold(0.0, |a: f64, v| if v.abs() > a.abs() { v } else { a });
        let first = if shape[0].abs() > 1e-9 * largest.abs() { shape[0] } else { largest };
        (first != 0.0 && first.is_finite()).then(|| shape.iter().map(|v| v / first).collect())
    };
    match modes {
        [] => None,
        [one] => normalised(one.clone()),
        several => {
            if plant::modal::turns_freely_as_one(k) {
                return Some(vec![1.0; n]);
            }
            // Σ φ (φᵀ J 1): the modes are J-orthonormal
            let mut shape = vec![0.0; n];
            for phi in several {
                let weight: f64 = (0..n).map(|i| phi[i] * j[(i, i)]).sum();
                for (s, p) in shape.iter_mut().zip(phi) {
                    *s += weight * p;
                }
            }
            let size = shape.iter().map(|v| v.abs()).fold(0.0, f64::max);
            (size > 1e-9).then_some(shape).and_then(normalised)
        }
    }
}

/// Refuses the rig `rig` in `variant` when its modes lie beyond the Nyquist frequency of a
/// controller sampling every `dt_s`: the rig's three masses put none there unless an inertia or
/// stiffness is far off, and such a rig could not be controlled — left out of the prediction as
/// a drive model's gear meshes are, it would fail later in its estimator, with a message about
/// disturbances instead of the parameters. The message names them.
fn rig_within_nyquist(rig: &RigParams, variant: Variant, dt_s: f64) -> Result<()> {
    let modes = rig.open_differential(variant)?.modes()?;
    let top = modes.frequencies_hz.iter().copied().fold(0.0, f64::max);
    let nyquist = 0.5 / dt_s;
    if top.is_nan() || top >= nyquist {
        return Err(MpcError::Numerical(format!(
            "the rig's fastest mode is at {top:.4e} Hz, beyond the {nyquist} Hz a controller sampling every \
             {dt_s} s can see: check [model] (j_m2 = {}, j_drive = {}, j_m3 = {} kg m^2, c_short = {}, c_long = {} Nm/rad)",
            rig.j_m2,
            rig.j_drive,
            rig.j_m3,
            rig.c_short,
            rig.c_long()
        )));
    }
    Ok(())
}

/// The model a controller is designed on: the paper rig (its signals fixed) or a drive model.
#[derive(Debug, Clone, Copy)]
pub enum Design<'a> {
    /// The paper rig in `variant` with `effects`.
    Rig {
        /// Its reduced three-mass parameters.
        rig: &'a RigParams,
        /// Its variant.
        variant: Variant,
        /// Its drive-path effects.
        effects: &'a DriveEffects,
    },
    /// A drive model.
    Drive(&'a DriveModel),
}

impl Design<'_> {
    /// The prediction model sampled every `dt_s`, by one rule for the rig and any drive model
    /// ([`drive_prediction`]: its modes beyond the loop's Nyquist frequency left out, its free
    /// motion); the rig's with its own signal names ([`rig_control_state_space`]).
    pub fn prediction(&self, dt_s: f64) -> Result<Prediction> {
        match *self {
            Design::Rig { rig, variant, effects } => {
                rig_within_nyquist(rig, variant, dt_s)?;
                let model = DriveModel::paper_rig(rig, variant, effects)?;
                prediction_of(&model, rig_control_state_space(&model)?, dt_s)
            }
            Design::Drive(model) => drive_prediction(model, dt_s),
        }
    }

    /// The prediction model and the settings of `section` at horizon `horizon`: the rig's
    /// ([`MpcSection::rig_settings`], sampled every 1 ms) or a drive model's
    /// ([`MpcSection::drive_settings`] on its prediction's signals).
    pub fn controller(&self, section: &MpcSection, horizon: usize) -> Result<(Prediction, MpcSettings)> {
        match *self {
            Design::Rig { .. } => {
                let settings = section.rig_settings(horizon)?;
                Ok((self.prediction(settings.dt_s)?, settings))
            }
            Design::Drive(model) => {
                let full = model.control_state_space()?;
                let settings = section.drive_settings(&full.input_names, &full.output_names, horizon)?;
                Ok((prediction_of(model, full, settings.dt_s)?, settings))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plant::Output;

    /// The notes name each effect of the rig's preset model where it acts, with its size, and
    /// tell the linear ones (in the prediction) from the nonlinear ones (left out), for the rig
    /// as for any model; a compliance is part of the line (the motor's speed is a state).
    #[test]
    fn the_notes_say_which_effects_the_prediction_holds() {
        let rig = plant::paper::damped_params();
        let effects = DriveEffects {
            actuator_lag_s: 0.004,
            compliance_stiffness_nm_per_rad: 2000.0,
            coulomb_friction_nm: [0.8, 0.0, 0.0],
            ..DriveEffects::default()
        };
        let pred = Design::Rig { rig: &rig, variant: Variant::V1, effects: &effects }.prediction(1e-3).unwrap();
        let held = |what: &str| {
            let note =
                pred.notes.iter().find(|n| n.starts_with(what)).unwrap_or_else(|| panic!("{what}: {:?}", pred.notes));
            !note.contains("NOT")
        };
        assert!(held("actuator_lag at input 2 (time_constant_s = 0.004)"), "{:?}", pred.notes);
        assert!(!held("coulomb_friction at body m2 (friction_Nm = 0.8"), "{:?}", pred.notes);
        // the compliance is in it: the motor's speed is a state of the prediction
        assert!(pred.model.state_names.iter().any(|n| n == "w_motor"), "{:?}", pred.model.state_names);
        assert_eq!(pred.notes.len(), 2, "{:?}", pred.notes);
    }

    /// The open differential behind a gear stage: motor (0.1 kg m²) → gear 2 → cage (0.5) → two
    /// side shafts on s = 2φ_cage − φ_l − φ_r to outputs of `j_out`.
    fn geared_differential(j_out: [f64; 2]) -> DriveModel {
        use plant::line::{Coupling, Domain, Line, LineBody};
        let body = |name: &str, inertia: f64| LineBody { name: name.into(), inertia, drag: 0.01 };
        let shaft = |name: &str, c: f64| Coupling {
            name: Some(name.into()),
            elongation: Some(vec![0.0, 1.0, -0.5, -0.5]),
            ..Coupling::new(c, 0.5, 1.0)
        };
        DriveModel {
            line: Line {
                domain: Domain::Rotational,
                bodies: vec![body("motor", 0.1), body("cage", 0.5), body("out_l", j_out[0]), body("out_r", j_out[1])],
                couplings: vec![Coupling::new(5000.0, 1.0, 2.0), shaft("left", 1500.0), shaft("right", 1100.0)],
            },
            inputs: vec![0],
            effects: Vec::new(),
        }
    }

    /// A line whose stiffness leaves several free motions (an open differential's outputs may
    /// also turn against each other at no twist) still moves together: the motor at 1, the cage
    /// and both outputs at 1/2 through the gear (the analytic free motion: no coupling twists),
    /// so the controller can start at speed. Before, such a model had no free motion and a reset
    /// at speed was refused as if a spring to ground held it.
    #[test]
    fn an_open_differential_behind_a_gear_moves_together() {
        let model = geared_differential([1.0, 1.0]);
        let pred = Design::Drive(&model).prediction(1e-3).unwrap();
        let motion = pred.motion.expect("a free motion");
        let n = 4;
        let expected = [1.0, 0.5, 0.5, 0.5];
        for (i, e) in expected.iter().enumerate() {
            assert!((motion.state[n + i] - e).abs() < 1e-9, "{:?}", motion.state);
            assert!((motion.rate[i] - e).abs() < 1e-9, "{:?}", motion.rate);
        }
        // it twists nothing: every coupling force of the motion is zero
        let forces = model.coupling_forces(pred.model.nstates()) * &motion.rate;
        assert!(forces.abs().max() < 1e-9, "{forces}");
        // and the controller starts at speed
        let section = crate::MpcSection { input_max: Some(vec![50.0]), ..Default::default() };
        let (pred, settings) = Design::Drive(&model).controller(&section, 20).unwrap();
        let mut rt = crate::RealTime::new(&pred, &settings).unwrap();
        rt.reset(10.0).unwrap();
    }

    /// The paper rig's prediction is its drive model's, by the one rule: the same matrices as
    /// the preset's model predicted as any drive model, only the names its own (a guard that the
    /// rig keeps no path of its own; the matrices themselves are checked against the rig's open
    /// differential by `the_rig_control_state_space_is_the_open_differential_with_its_names`),
    /// and the free motion every body at 1 exactly — analytic: the side shafts' elongation
    /// [−1, 2, −1]·share and the compliance's φ_motor − φ_drive each sum to zero, so no coupling
    /// force arises from it.
    #[test]
    fn the_rig_is_predicted_as_any_drive_model() {
        let rig = plant::paper::damped_params();
        let effects =
            DriveEffects { compliance_stiffness_nm_per_rad: 2000.0, time_delay_s: 0.003, ..Default::default() };
        let as_rig = Design::Rig { rig: &rig, variant: Variant::V3, effects: &effects }.prediction(1e-3).unwrap();
        let model = DriveModel::paper_rig(&rig, Variant::V3, &effects).unwrap();
        let as_drive = Design::Drive(&model).prediction(1e-3).unwrap();
        assert_eq!(as_rig.model.a, as_drive.model.a);
        assert_eq!(as_rig.model.b, as_drive.model.b);
        assert_eq!(as_rig.input_delays_s, as_drive.input_delays_s);
        for (row, name) in as_rig.model.output_names.iter().enumerate() {
            let k = as_drive.model.output_names.iter().position(|n| n == name).unwrap();
            assert_eq!(as_rig.model.c.row(row), as_drive.model.c.row(k), "{name}");
        }
        let ones = Motion::physical(&[1.0; 4], as_rig.model.nstates());
        assert_eq!(as_rig.motion, Some(ones.clone()));
        assert_eq!(as_drive.motion, Some(ones.clone()));
        let forces = model.coupling_forces(as_drive.model.nstates()) * &ones.rate;
        assert!(forces.abs().max() < 1e-9, "{forces}");
    }

    /// What the MPC predicts the rig with is the open differential assembled by
    /// `MechanicalModel` from the springs' elongation vectors (another path to the same
    /// equations), its names included.
    #[test]
    fn the_rig_control_state_space_is_the_open_differential_with_its_names() {
        let rig = plant::paper::damped_params();
        let m = DriveModel::paper_rig(&rig, Variant::V2, &DriveEffects::default()).unwrap();
        let ss = rig_control_state_space(&m).unwrap();
        let reference =
            rig.open_differential(Variant::V2).unwrap().state_space(&[Output::Speeds, Output::SpringTorques]).unwrap();
        assert_eq!(ss.state_names, reference.state_names);
        assert_eq!(ss.input_names, reference.input_names);
        assert_eq!(ss.output_names, reference.output_names);
        for (m, r) in [(&ss.a, &reference.a), (&ss.b, &reference.b), (&ss.c, &reference.c)] {
            assert!((m - r).abs().max() < 1e-9 * r.abs().max(), "{m} vs {r}");
        }
    }

    /// With a compliance and a lag the rig keeps its names: the drive torque is still M_drive
    /// (on the motor), w_motor comes last, the lagged torque is M_drive_lagged.
    #[test]
    fn the_compliant_lagged_rig_keeps_its_signal_names() {
        let effects =
            DriveEffects { compliance_stiffness_nm_per_rad: 2000.0, actuator_lag_s: 0.004, ..Default::default() };
        let m = DriveModel::paper_rig(&plant::paper::damped_params(), Variant::V1, &effects).unwrap();
        let ss = rig_control_state_space(&m).unwrap();
        assert_eq!(ss.input_names, ["M_m2", "M_drive", "M_m3"]);
        assert_eq!(ss.output_names, ["w_m2", "w_drive", "w_m3", "T_short_side_shaft", "T_long_side_shaft", "w_motor"]);
        assert_eq!(ss.state_names[8], "M_drive_lagged");
        // w_motor reads the motor's speed state
        assert_eq!(ss.c[(5, 7)], 1.0);
    }
}
