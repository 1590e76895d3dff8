//! The parameter set an FMU is built from: its plant — the one drive model, given by the paper
//! rig's preset (its reduced parameters, variant, effects and bearing block, under the rig's
//! fixed names and value references) or as a drive model of its own (`plant::DriveModel`) — and,
//! for the controller FMU, the controller of that plant.

use serde::{Deserialize, Serialize};

use mpc::MpcSection;
use plant::rig::DriveEffects;
use plant::{paper, BearingModel, Coefficients, DriveModel, RigParams, Support, Variant};

/// Everything that sets the FMU's start values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FmuParams {
    /// The plant: what the plant FMU simulates, and what the controller FMU controls.
    pub plant: Plant,
    /// The controller FMU: when given, the FMU is rigtwin's MPC of the plant above instead of
    /// the plant itself (`crate::controller`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub controller: Option<ControllerSpec>,
}

/// The plant of an FMU: one drive model, as the paper rig's preset builds it or written as a
/// drive model. The two differ only in how the model is named and parameterised: the rig keeps
/// its fixed variable names and value references (users' SSP files point at them) and its
/// reduced parameters; a drive model's table is generated from its bodies, couplings, inputs
/// and effects.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
// one per FMU instance, built once: the rig's inline size costs nothing
#[allow(clippy::large_enum_variant)]
pub enum Plant {
    /// The paper rig (`plant::DriveModel::paper_rig`) with its bearing block.
    PaperRig(RigPlant),
    /// A drivetrain model (a `drive_test` bundle's model, or one written by `rigtwin diagnose
    /// --write-model`).
    Drive(DriveModel),
}

/// The paper rig's preset as an FMU's plant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigPlant {
    /// Reduced three-mass parameters of the open-differential powertrain.
    pub powertrain: RigParams,
    /// Rig variant (where the additional spring is mounted).
    pub variant: Variant,
    /// The bearing block on its support, where the rig has one: its forces are inputs, its
    /// displacements and velocities states and outputs. Without it the FMU has none of them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bearing: Option<BearingModel>,
    /// Drive-path effects (dead time, actuator lag, backlash, drive compliance, friction), all
    /// off by default; the ones on add parameters and states to the FMU.
    #[serde(default)]
    pub effects: DriveEffects,
}

impl Default for RigPlant {
    /// The embedded default rig (`plant::paper::rig`: the paper's V1/V2 parameter set, Table 4,
    /// with the shaft damping and load drag declared in the example bundles), without a bearing
    /// block (the paper's rig has none).
    fn default() -> Self {
        let rig = paper::rig();
        RigPlant { powertrain: rig.model, variant: rig.variant, bearing: None, effects: DriveEffects::default() }
    }
}

impl RigPlant {
    /// The rig's drive model (its preset, `plant::DriveModel::paper_rig`).
    pub fn drive_model(&self) -> Result<DriveModel, String> {
        DriveModel::paper_rig(&self.powertrain, self.variant, &self.effects).map_err(|e| e.to_string())
    }
}

impl Plant {
    /// The model a controller of this plant is designed on.
    pub fn design(&self) -> mpc::Design<'_> {
        match self {
            Plant::PaperRig(r) => mpc::Design::Rig { rig: &r.powertrain, variant: r.variant, effects: &r.effects },
            Plant::Drive(m) => mpc::Design::Drive(m),
        }
    }

    /// The paper rig's preset, if the plant is the rig.
    pub fn rig(&self) -> Option<&RigPlant> {
        match self {
            Plant::PaperRig(r) => Some(r),
            Plant::Drive(_) => None,
        }
    }

    /// The drive model, if the plant is written as one.
    pub fn drive(&self) -> Option<&DriveModel> {
        match self {
            Plant::PaperRig(_) => None,
            Plant::Drive(m) => Some(m),
        }
    }
}

/// The controller an FMU carries: horizon and move blocks (fixed at export), the tunable
/// settings (start values of its parameters) and, for a drive model, its `[mpc]` section
/// (the signals tracked, penalised and measured; the tunables override its weights and bounds).
/// The rig's defaults are `mpc::MpcSettings::powertrain`'s.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerSpec {
    /// Prediction horizon, steps of 1 ms.
    pub horizon: usize,
    /// Number of move blocks (0: every step free).
    pub move_blocks: usize,
    /// The tunable settings, in the order of `ControllerSpec::ports` (`crate::controller`)' parameters.
    pub values: Vec<f64>,
    /// A drive model's `[mpc]` section (`None` for the paper rig).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub section: Option<MpcSection>,
}

impl Default for FmuParams {
    /// The embedded default rig ([`RigPlant::default`]).
    fn default() -> Self {
        FmuParams::of_rig(RigPlant::default())
    }
}

impl FmuParams {
    /// The plant FMU of the paper rig `rig`.
    pub fn of_rig(rig: RigPlant) -> Self {
        FmuParams { plant: Plant::PaperRig(rig), controller: None }
    }

    /// The plant FMU of the drive model `m`.
    pub fn of_drive(m: DriveModel) -> Self {
        FmuParams { plant: Plant::Drive(m), controller: None }
    }

    /// The default rig with the squeeze-film damper identified from `sfd_shake` (KCM, full
    /// coupling, IVFM; `tests/bearing.rs` re-identifies it and compares) as its bearing block.
    pub fn with_sfd_bearing() -> Self {
        FmuParams::of_rig(RigPlant { bearing: Some(sfd_bearing()), ..RigPlant::default() })
    }
}

/// The squeeze-film damper identified from `sfd_shake` on its support (see
/// [`FmuParams::with_sfd_bearing`]).
pub fn sfd_bearing() -> BearingModel {
    BearingModel {
        element: Coefficients {
            k_n_per_m: [
                [399_494.641_414_391_9, 1_662.949_771_836_502_4],
                [501.096_480_048_138_5, 499_519.175_816_695_4],
            ],
            c_ns_per_m: [
                [2_627.271_959_527_591_7, 0.099_358_503_747_976_04],
                [-1.079_536_341_524_340_4, 2_802.539_190_846_918],
            ],
            m_kg: [
                [5.443_161_690_440_772, 0.011_049_102_197_932_373],
                [0.000_121_998_052_471_661_81, 5.891_483_860_386_054],
            ],
        },
        support: Support {
            k_x: 3_677_663.527_559_055_5,
            k_y: 3_852_790.362_204_725,
            c_x: 1_225.887_842_519_685_1,
            c_y: 1_313.451_259_842_52,
            m_x: 18.143_694_800_000_002,
            m_y: 18.143_694_800_000_002,
        },
        table: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_round_trip_keeps_the_token() {
        let p = FmuParams::with_sfd_bearing();
        let back: FmuParams = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
        assert_eq!(back, p);
        assert_eq!(crate::token(&back), crate::token(&p));
    }
}
