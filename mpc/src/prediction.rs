//! Any model as the controller sees it: a linear prediction model with input dead times, and
//! the settings its `[mpc]` section gives — the paper rig (the open-differential powertrain with
//! the effects a rig file declares or the diagnosis found) and any drive model alike.

use plant::effects::{DriveEffects, Powertrain};
use plant::rig::{RigParams, Variant};
use plant::statespace::StateSpace;
use plant::DriveModel;

use crate::error::{MpcError, Result};
use crate::{MpcSection, MpcSettings};

/// What the controller predicts with: the model's linearisation (the rig's
/// `plant::effects::Powertrain::control_state_space`, a drive model's
/// `plant::DriveModel::control_state_space`) and the inputs' dead times. Backlash and friction
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
}

/// The prediction model of the rig `rig` in `variant` with `effects`, for a controller sampling
/// every `dt_s`. Refused when the rig's modes lie beyond that loop's Nyquist frequency (an
/// inertia or stiffness far off): it could not be controlled, and its Riccati equations would
/// fail with a message about residuals instead of the parameters.
pub fn prediction(rig: &RigParams, variant: Variant, effects: &DriveEffects, dt_s: f64) -> Result<Prediction> {
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
    let pt = Powertrain::new(rig, variant, effects)?;
    let e = effects;
    let mut notes = Vec::new();
    if e.time_delay_s > 0.0 {
        notes.push(format!("drive-torque dead time {:.4} ms as input-delay states", e.time_delay_s * 1e3));
    }
    if e.actuator_lag_s > 0.0 {
        notes.push(format!("actuator lag {:.4} ms as a state", e.actuator_lag_s * 1e3));
    }
    if e.compliance_stiffness_nm_per_rad > 0.0 {
        notes.push(format!(
            "drive compliance {:.1} Nm/rad (motor share {:.2}) as two states",
            e.compliance_stiffness_nm_per_rad, e.compliance_motor_fraction
        ));
    }
    if e.backlash_rad > 0.0 {
        notes.push(format!(
            "side-shaft backlash {:.4} mrad is NOT in the prediction: it stays linear with the shafts in contact",
            e.backlash_rad * 1e3
        ));
    }
    for (k, name) in ["M2", "the drive", "M3"].iter().enumerate() {
        if e.coulomb_friction_nm[k] > 0.0 {
            notes.push(format!(
                "Coulomb friction {:.3} Nm at {name} is NOT in the prediction: the filter's input disturbance absorbs it",
                e.coulomb_friction_nm[k]
            ));
        }
    }
    Ok(Prediction { model: pt.control_state_space(), input_delays_s: pt.delay_s().to_vec(), notes })
}

/// The prediction model of a drive model: its linearisation and its inputs' dead times.
pub fn drive_prediction(model: &DriveModel) -> Result<Prediction> {
    let mut notes = Vec::new();
    for e in &model.effects {
        notes.push(match e {
            plant::Effect::TimeDelay(_) => format!("{} at {}: input-delay states", e.name(), e.element(model)),
            plant::Effect::ActuatorLag(_) => format!("{} at {}: a state", e.name(), e.element(model)),
            _ => format!(
                "{} at {} is NOT in the prediction: it stays linear (in contact, without friction)",
                e.name(),
                e.element(model)
            ),
        });
    }
    Ok(Prediction { model: model.control_state_space()?, input_delays_s: model.input_delays_s(), notes })
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
    /// The prediction model and the settings of `section` at horizon `horizon`: the rig's
    /// ([`MpcSection::rig_settings`], sampled every 1 ms) or a drive model's
    /// ([`MpcSection::drive_settings`] on its prediction's signals).
    pub fn controller(&self, section: &MpcSection, horizon: usize) -> Result<(Prediction, MpcSettings)> {
        match *self {
            Design::Rig { rig, variant, effects } => {
                let settings = section.rig_settings(horizon)?;
                Ok((prediction(rig, variant, effects, settings.dt_s)?, settings))
            }
            Design::Drive(model) => {
                let p = drive_prediction(model)?;
                let settings = section.drive_settings(&p.model.input_names, &p.model.output_names, horizon)?;
                Ok((p, settings))
            }
        }
    }
}
