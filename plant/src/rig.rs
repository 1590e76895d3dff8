//! The rig: the three-mass model with its variants V1–V4 (eqs. (13)–(19), (44), (45)), the open
//! differential with its side gears (section 2.4, eqs. (27)–(34); the massless one, eq. (A1),
//! is the preset's: `RigParams::open_differential` in [`crate::preset`]), and the full chain
//! with the additional spring inserted (Table A2); the rig's drive-path effects
//! ([`DriveEffects`], as a rig file names them), from which [`crate::preset`] builds the rig's
//! drive model.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

use crate::chain::{Body, Chain};
use crate::error::{in_range, non_negative, positive, PlantError, Result};
use crate::mechanical::{Layout, MechanicalModel, Spring};

/// Rig variant (section 3, Figure 10): where the additional spring c_delta is mounted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub enum Variant {
    /// Original rig.
    #[default]
    V1,
    /// Additional spring on both side shafts.
    V2,
    /// Additional spring on the right (M3, long side shaft).
    V3,
    /// Additional spring on the left (M2, short side shaft).
    V4,
}

impl Variant {
    /// All four, in order.
    pub const ALL: [Variant; 4] = [Variant::V1, Variant::V2, Variant::V3, Variant::V4];

    /// The spring sits in series with the short (M2) side shaft.
    pub fn left_spring(self) -> bool {
        matches!(self, Variant::V2 | Variant::V4)
    }

    /// The spring sits in series with the long (M3) side shaft.
    pub fn right_spring(self) -> bool {
        matches!(self, Variant::V2 | Variant::V3)
    }
}

impl fmt::Display for Variant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{self:?}")
    }
}

impl FromStr for Variant {
    type Err = PlantError;
    fn from_str(s: &str) -> Result<Self> {
        match s.trim() {
            "V1" | "v1" => Ok(Variant::V1),
            "V2" | "v2" => Ok(Variant::V2),
            "V3" | "v3" => Ok(Variant::V3),
            "V4" | "v4" => Ok(Variant::V4),
            other => Err(PlantError::Invalid(format!("unknown variant `{other}`: expected V1, V2, V3 or V4"))),
        }
    }
}

fn default_long_ratio() -> f64 {
    7.0 / 9.0
}

/// Parameters of the reduced three-mass rig. The keys are those of a measurement bundle's
/// `[model]` section (`../shared/DATA.md`), all SI.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigParams {
    /// Load machine M2 with adapters (left, short side shaft), kg m².
    pub j_m2: f64,
    /// Drive unit reduced to the output (differential cage), kg m².
    pub j_drive: f64,
    /// Load machine M3 with adapters (right, long side shaft), kg m².
    pub j_m3: f64,
    /// Short side shaft stiffness c_Ts, Nm/rad.
    pub c_short: f64,
    /// Long side shaft stiffness, Nm/rad; when absent, `c_long_ratio · c_short` (eq. (13)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c_long: Option<f64>,
    /// c_long / c_short when `c_long` is absent; 7/9 for the paper's shafts (eq. (13)).
    #[serde(default = "default_long_ratio")]
    pub c_long_ratio: f64,
    /// The additional spring c_TΔ, Nm/rad.
    #[serde(default)]
    pub c_delta: f64,
    /// M2-side inertia when the additional spring is mounted there (J1Δ), kg m²; default `j_m2`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub j_m2_delta: Option<f64>,
    /// M3-side inertia when the additional spring is mounted there (J17Δ), kg m²; default `j_m3`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub j_m3_delta: Option<f64>,
    /// Damping of the short side shaft, Nm s/rad.
    #[serde(default)]
    pub d_short: f64,
    /// Damping of the long side shaft, Nm s/rad.
    #[serde(default)]
    pub d_long: f64,
    /// Speed-proportional drag of each load machine, Nm s/rad.
    #[serde(default)]
    pub load_drag: f64,
}

/// The three-mass parameters a variant puts in effect.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Effective {
    /// M2-side inertia, kg m².
    pub j_m2: f64,
    /// Drive inertia, kg m².
    pub j_drive: f64,
    /// M3-side inertia, kg m².
    pub j_m3: f64,
    /// Left (M2) branch stiffness, Nm/rad: c_short, or eq. (16) with the spring.
    pub c_left: f64,
    /// Right (M3) branch stiffness, Nm/rad: c_long, or eq. (17) with the spring.
    pub c_right: f64,
    /// Left branch damping, Nm s/rad.
    pub d_left: f64,
    /// Right branch damping, Nm s/rad.
    pub d_right: f64,
    /// Drag of each load machine, Nm s/rad.
    pub load_drag: f64,
}

fn series(a: f64, b: f64) -> f64 {
    a * b / (a + b)
}

impl RigParams {
    /// The paper's smooth-strand parameters with the given unknowns, undamped, c_long = 7/9 c_short.
    pub fn new(j_m2: f64, j_drive: f64, j_m3: f64, c_short: f64, c_delta: f64) -> Self {
        RigParams {
            j_m2,
            j_drive,
            j_m3,
            c_short,
            c_long: None,
            c_long_ratio: default_long_ratio(),
            c_delta,
            j_m2_delta: None,
            j_m3_delta: None,
            d_short: 0.0,
            d_long: 0.0,
            load_drag: 0.0,
        }
    }

    /// Long side shaft stiffness, Nm/rad (eq. (13) unless given).
    pub fn c_long(&self) -> f64 {
        self.c_long.unwrap_or(self.c_long_ratio * self.c_short)
    }

    /// Checks every parameter; errors name the key (prefixed by `section`, e.g. "model").
    pub fn validate(&self, section: &str) -> Result<()> {
        let k = |name: &str| if section.is_empty() { name.to_string() } else { format!("{section}.{name}") };
        positive(|| k("j_m2"), self.j_m2, "kg m^2")?;
        positive(|| k("j_drive"), self.j_drive, "kg m^2")?;
        positive(|| k("j_m3"), self.j_m3, "kg m^2")?;
        positive(|| k("c_short"), self.c_short, "Nm/rad")?;
        if let Some(c) = self.c_long {
            positive(|| k("c_long"), c, "Nm/rad")?;
        }
        positive(|| k("c_long_ratio"), self.c_long_ratio, "(ratio)")?;
        non_negative(|| k("c_delta"), self.c_delta, "Nm/rad")?;
        if let Some(j) = self.j_m2_delta {
            positive(|| k("j_m2_delta"), j, "kg m^2")?;
        }
        if let Some(j) = self.j_m3_delta {
            positive(|| k("j_m3_delta"), j, "kg m^2")?;
        }
        non_negative(|| k("d_short"), self.d_short, "Nm s/rad")?;
        non_negative(|| k("d_long"), self.d_long, "Nm s/rad")?;
        non_negative(|| k("load_drag"), self.load_drag, "Nm s/rad")?;
        Ok(())
    }

    /// The branch parameters of a variant: the spring in series on its side (eqs. (16), (17)),
    /// and J1Δ / J17Δ on that side. The shaft damping is kept as it is (the additional spring
    /// is taken as undamped and much stiffer than the shaft).
    pub fn effective(&self, variant: Variant) -> Result<Effective> {
        self.validate("model")?;
        if (variant.left_spring() || variant.right_spring()) && self.c_delta <= 0.0 {
            return Err(PlantError::Invalid(format!(
                "`model.c_delta` must be positive for variant {variant}, which mounts the additional spring; got {} Nm/rad",
                self.c_delta
            )));
        }
        let (l, r) = (variant.left_spring(), variant.right_spring());
        Ok(Effective {
            j_m2: if l { self.j_m2_delta.unwrap_or(self.j_m2) } else { self.j_m2 },
            j_drive: self.j_drive,
            j_m3: if r { self.j_m3_delta.unwrap_or(self.j_m3) } else { self.j_m3 },
            c_left: if l { series(self.c_short, self.c_delta) } else { self.c_short },
            c_right: if r { series(self.c_long(), self.c_delta) } else { self.c_long() },
            d_left: self.d_short,
            d_right: self.d_long,
            load_drag: self.load_drag,
        })
    }

    /// The smooth strand (eqs. (14), (18), (44), (45)): q = [φ_m2, φ_drive, φ_m3], each side
    /// shaft a spring between its load machine and the drive. The side shafts' torques are
    /// positive when the drive drives the loads.
    pub fn three_mass(&self, variant: Variant) -> Result<MechanicalModel> {
        let e = self.effective(variant)?;
        let springs = vec![
            spring("short side shaft", [-1.0, 1.0, 0.0], e.c_left, e.d_left),
            spring("long side shaft", [0.0, 1.0, -1.0], e.c_right, e.d_right),
        ];
        Ok(three_dof(&e, springs))
    }

    /// The open differential with its side gears' inertia `j_side` each: eq. (28) with
    /// J_d2 = J_d3 = `j_side`, before section 2.4 drops them. Coordinates q = [φ_m2, φ_drive,
    /// φ_d3, φ_m3] with φ_d2 = 2φ_drive − φ_d3 (eq. (27)), so J = [[J_m2, 0, 0, 0], [0,
    /// J_drive + 4J_s, −2J_s, 0], [0, −2J_s, 2J_s, 0], [0, 0, 0, J_m3]], the short shaft on
    /// 2φ_drive − φ_d3 − φ_m2, the long one on φ_d3 − φ_m3; `j_side` → 0 is
    /// [`RigParams::open_differential`].
    pub fn open_differential_with_side_gears(&self, variant: Variant, j_side: f64) -> Result<MechanicalModel> {
        let e = self.effective(variant)?;
        positive(|| "j_side_gear", j_side, "kg m^2")?;
        let j_c = e.j_drive;
        let mut inertia = DMatrix::zeros(4, 4);
        inertia[(0, 0)] = e.j_m2;
        inertia[(1, 1)] = j_c + 4.0 * j_side;
        inertia[(1, 2)] = -2.0 * j_side;
        inertia[(2, 1)] = -2.0 * j_side;
        inertia[(2, 2)] = 2.0 * j_side;
        inertia[(3, 3)] = e.j_m3;
        let spring4 = |name: &str, el: [f64; 4], c: f64, d: f64| Spring {
            name: name.into(),
            elongation: DVector::from_row_slice(&el),
            stiffness: c,
            damping: d,
        };
        Ok(MechanicalModel {
            dof_names: vec!["m2".into(), "drive".into(), "side_gear_m3".into(), "m3".into()],
            inertia,
            springs: vec![
                spring4("short side shaft", [-1.0, 2.0, -1.0, 0.0], e.c_left, e.d_left),
                spring4("long side shaft", [0.0, 0.0, 1.0, -1.0], e.c_right, e.d_right),
            ],
            drag: DVector::from_vec(vec![e.load_drag, 0.0, 0.0, e.load_drag]),
            layout: Some(Layout { m2: 0, drive: Some(1), m3: 3, short_shaft: (0, 1), long_shaft: (2, 3) }),
        })
    }

    /// A copy whose side-shaft dampings give the open differential's shuffle mode of `variant`
    /// the damping ratio `zeta` (the "slight generic damping" of section 4.3). The dampings are
    /// stiffness-proportional, d = β c with β = 2ζ/ω_shuffle, so the shuffle mode stays a
    /// classical normal mode with exactly that ratio.
    pub fn with_shaft_damping_ratio(&self, zeta: f64, variant: Variant) -> Result<RigParams> {
        non_negative(|| "damping_ratio", zeta, "(ratio)")?;
        let e = self.effective(variant)?;
        let cs = series(e.c_left, e.c_right);
        let w = (cs * (1.0 / e.j_m2 + 4.0 / e.j_drive + 1.0 / e.j_m3)).sqrt();
        let beta = 2.0 * zeta / w;
        Ok(RigParams { d_short: beta * e.c_left, d_long: beta * e.c_right, ..self.clone() })
    }
}

fn spring(name: &str, e: [f64; 3], stiffness: f64, damping: f64) -> Spring {
    Spring { name: name.into(), elongation: DVector::from_row_slice(&e), stiffness, damping }
}

fn three_dof(e: &Effective, springs: Vec<Spring>) -> MechanicalModel {
    MechanicalModel {
        dof_names: vec!["m2".into(), "drive".into(), "m3".into()],
        inertia: DMatrix::from_diagonal(&DVector::from_vec(vec![e.j_m2, e.j_drive, e.j_m3])),
        springs,
        drag: DVector::from_vec(vec![e.load_drag, 0.0, e.load_drag]),
        layout: Some(Layout { m2: 0, drive: Some(1), m3: 2, short_shaft: (0, 1), long_shaft: (1, 2) }),
    }
}

/// The additional spring's bodies (Table A2) and where they go in the chain.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdditionalSpring {
    /// Bodies from the M2 end of the spring to its drive end, as mounted on the left; the right
    /// side mounts it mirrored.
    pub bodies: Vec<Body>,
    /// 1-based chain position after which the spring goes on the left (M2) side.
    pub left_after: usize,
    /// 1-based chain position after which the spring goes (mirrored) on the right (M3) side.
    pub right_after: usize,
}

/// The full chain of the rig from M2 to M3 (Table A1), with the roles of its bodies.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigChain {
    /// Bodies from load machine M2 to load machine M3.
    pub bodies: Vec<Body>,
    /// 1-based position of the drive (differential cage).
    pub drive: usize,
    /// 1-based position of the short side shaft (M2 side).
    pub short_shaft: usize,
    /// 1-based position of the long side shaft (M3 side).
    pub long_shaft: usize,
    /// The additional spring of variants V2–V4, if the rig has one.
    pub additional_spring: Option<AdditionalSpring>,
}

/// 0-based positions of the roles in a chain.
#[derive(Debug, Clone, Copy)]
struct Roles {
    drive: usize,
    short_shaft: usize,
    long_shaft: usize,
}

impl RigChain {
    /// Checks positions and bodies; errors name the key under `chain`.
    pub fn validate(&self) -> Result<()> {
        let n = self.bodies.len();
        if n < 3 {
            return Err(PlantError::Invalid(format!("`chain.bodies` needs at least 3 bodies, got {n}")));
        }
        for (i, b) in self.bodies.iter().enumerate() {
            positive(|| format!("chain.bodies[{}].j_kgm2", i + 1), b.inertia_kgm2, "kg m^2")?;
            positive(|| format!("chain.bodies[{}].c_Nm_per_rad", i + 1), b.stiffness_nm_per_rad, "Nm/rad")?;
        }
        in_range(|| "chain.drive", self.drive, 3, n - 2)?;
        in_range(|| "chain.short_shaft", self.short_shaft, 2, self.drive - 1)?;
        in_range(|| "chain.long_shaft", self.long_shaft, self.drive + 1, n - 1)?;
        if let Some(s) = &self.additional_spring {
            if s.bodies.is_empty() {
                return Err(PlantError::Invalid("`chain.additional_spring.bodies` is empty".into()));
            }
            for (i, b) in s.bodies.iter().enumerate() {
                positive(|| format!("chain.additional_spring.bodies[{}].j_kgm2", i + 1), b.inertia_kgm2, "kg m^2")?;
                positive(
                    || format!("chain.additional_spring.bodies[{}].c_Nm_per_rad", i + 1),
                    b.stiffness_nm_per_rad,
                    "Nm/rad",
                )?;
            }
            in_range(|| "chain.additional_spring.left_after", s.left_after, 1, self.drive - 1)?;
            in_range(|| "chain.additional_spring.right_after", s.right_after, self.drive, n - 1)?;
        }
        Ok(())
    }

    /// The bodies of a variant: the additional spring inserted after `left_after` (V2, V4) and,
    /// mirrored, after `right_after` (V2, V3), as the paper does for Table 2.
    pub fn bodies(&self, variant: Variant) -> Result<(Vec<Body>, Layout)> {
        self.validate()?;
        let (left, right) = (variant.left_spring(), variant.right_spring());
        let spring = match (&self.additional_spring, left || right) {
            (_, false) => None,
            (Some(s), true) => Some(s),
            (None, true) => {
                return Err(PlantError::Invalid(format!(
                    "variant {variant} needs `chain.additional_spring`, which the rig does not describe"
                )))
            }
        };
        let mut out = Vec::with_capacity(self.bodies.len() + 14);
        let (mut drive, mut short, mut long) = (0, 0, 0);
        for (i, b) in self.bodies.iter().enumerate() {
            let pos = i + 1;
            if let Some(s) = spring {
                if right && pos == s.right_after + 1 {
                    out.extend(s.bodies.iter().rev().cloned().map(|mut b| {
                        b.name = format!("{} (right)", b.name);
                        b
                    }));
                }
            }
            if pos == self.drive {
                drive = out.len();
            } else if pos == self.short_shaft {
                short = out.len();
            } else if pos == self.long_shaft {
                long = out.len();
            }
            out.push(b.clone());
            if let Some(s) = spring {
                if left && pos == s.left_after {
                    out.extend(s.bodies.iter().cloned().map(|mut b| {
                        b.name = format!("{} (left)", b.name);
                        b
                    }));
                }
            }
        }
        let roles = Roles { drive, short_shaft: short, long_shaft: long };
        let identity: Vec<usize> = (0..out.len()).collect();
        let layout = locate(&identity, roles).expect("positions validated above");
        Ok((out, layout))
    }

    /// The chain of a variant, coupled by eq. (3).
    pub fn chain(&self, variant: Variant) -> Result<(Chain, Layout)> {
        let (bodies, layout) = self.bodies(variant)?;
        Ok((Chain::from_bodies(&bodies)?, layout))
    }

    /// The layout of a chain reduced from [`RigChain::chain`] of the same variant, found through
    /// the reduced masses' origins; `None` when the reduction merged the drive away or left no
    /// mass on one side of a side shaft.
    pub fn reduced_layout(&self, full: &Layout, reduced: &Chain) -> Option<Layout> {
        // short shaft body sits between the bracket's ends: recover it as bracket.0 + 1
        let roles =
            Roles { drive: full.drive?, short_shaft: full.short_shaft.0 + 1, long_shaft: full.long_shaft.0 + 1 };
        locate(&reduced.origins, roles)
    }
}

/// Where roles fall among masses whose origins (positions in the full chain) are `origins`.
fn locate(origins: &[usize], roles: Roles) -> Option<Layout> {
    let n = origins.len();
    if n < 3 {
        return None;
    }
    let last_below = |p: usize| origins.iter().rposition(|&o| o < p);
    let first_above = |p: usize| origins.iter().position(|&o| o > p);
    Some(Layout {
        m2: 0,
        drive: origins.iter().position(|&o| o == roles.drive),
        m3: n - 1,
        short_shaft: (last_below(roles.short_shaft)?, first_above(roles.short_shaft)?),
        long_shaft: (last_below(roles.long_shaft)?, first_above(roles.long_shaft)?),
    })
}

/// The effects, each off at zero.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveEffects {
    /// Dead time of the drive torque, s.
    #[serde(default)]
    pub time_delay_s: f64,
    /// Time constant of a first-order lag of the drive torque, s.
    #[serde(default)]
    pub actuator_lag_s: f64,
    /// Total play of each side shaft (output side), rad.
    #[serde(default)]
    pub backlash_rad: f64,
    /// Stiffness between the drive's motor and its cage, Nm/rad (0: rigid drive).
    #[serde(default)]
    pub compliance_stiffness_nm_per_rad: f64,
    /// Share of j_drive on the motor side of that compliance (the rest is the cage).
    #[serde(default = "half")]
    pub compliance_motor_fraction: f64,
    /// Coulomb friction of each machine [M2, drive, M3] (bearings, seals, brushes), Nm; the
    /// drive's acts on its motor when the drive is compliant.
    #[serde(default)]
    pub coulomb_friction_nm: [f64; 3],
    /// Smoothing speed v_s of the friction, rad/s: T = T_c w/√(w² + v_s²) (71 % of T_c at v_s,
    /// 97 % at 4 v_s), so the right-hand side stays Lipschitz through a speed reversal.
    #[serde(default = "default_smoothing")]
    pub friction_smoothing_radps: f64,
}

/// Default friction smoothing speed, rad/s (0.5 rpm: well below the speeds at which a rig's
/// machines reverse under a sweep, well above what the 0.125 ms integration step resolves for
/// frictions of a few Nm on inertias of 0.1 kg m²).
pub const FRICTION_SMOOTHING_RADPS: f64 = 0.05;

fn default_smoothing() -> f64 {
    FRICTION_SMOOTHING_RADPS
}

fn half() -> f64 {
    0.5
}

impl Default for DriveEffects {
    fn default() -> Self {
        DriveEffects {
            time_delay_s: 0.0,
            actuator_lag_s: 0.0,
            backlash_rad: 0.0,
            compliance_stiffness_nm_per_rad: 0.0,
            compliance_motor_fraction: 0.5,
            coulomb_friction_nm: [0.0; 3],
            friction_smoothing_radps: FRICTION_SMOOTHING_RADPS,
        }
    }
}

impl DriveEffects {
    /// Checks ranges; names the key.
    pub fn validate(&self) -> Result<()> {
        non_negative(|| "effects.time_delay_s", self.time_delay_s, "s")?;
        non_negative(|| "effects.actuator_lag_s", self.actuator_lag_s, "s")?;
        non_negative(|| "effects.backlash_rad", self.backlash_rad, "rad")?;
        non_negative(|| "effects.compliance_stiffness_nm_per_rad", self.compliance_stiffness_nm_per_rad, "Nm/rad")?;
        for (k, name) in ["M2", "drive", "M3"].iter().enumerate() {
            non_negative(|| format!("effects.coulomb_friction_nm[{k}] ({name})"), self.coulomb_friction_nm[k], "Nm")?;
        }
        if !(self.friction_smoothing_radps > 0.0 && self.friction_smoothing_radps.is_finite()) {
            return Err(PlantError::Invalid(format!(
                "`effects.friction_smoothing_radps` must be a positive speed, got {}",
                self.friction_smoothing_radps
            )));
        }
        if !(self.compliance_motor_fraction > 0.0 && self.compliance_motor_fraction < 1.0) {
            return Err(PlantError::Invalid(format!(
                "`effects.compliance_motor_fraction` must lie strictly between 0 and 1, got {}",
                self.compliance_motor_fraction
            )));
        }
        Ok(())
    }

    /// True when no effect is on.
    pub fn is_empty(&self) -> bool {
        self.time_delay_s == 0.0
            && self.actuator_lag_s == 0.0
            && self.backlash_rad == 0.0
            && self.compliance_stiffness_nm_per_rad == 0.0
            && self.coulomb_friction_nm == [0.0; 3]
    }

    /// The effects in words, with their sizes ("none" without): what a report says a model
    /// or a plant carries.
    pub fn in_words(&self) -> String {
        let mut v = Vec::new();
        if self.time_delay_s > 0.0 {
            v.push(format!("time_delay {:.4} ms", self.time_delay_s * 1e3));
        }
        if self.actuator_lag_s > 0.0 {
            v.push(format!("actuator_lag {:.4} ms", self.actuator_lag_s * 1e3));
        }
        if self.backlash_rad > 0.0 {
            v.push(format!("backlash {:.4} mrad", self.backlash_rad * 1e3));
        }
        if self.compliance_stiffness_nm_per_rad > 0.0 {
            v.push(format!("drive_compliance {:.1} Nm/rad", self.compliance_stiffness_nm_per_rad));
        }
        for (k, name) in ["m2", "drive", "m3"].iter().enumerate() {
            if self.coulomb_friction_nm[k] > 0.0 {
                v.push(format!("coulomb_friction at {name} {:.3} Nm", self.coulomb_friction_nm[k]));
            }
        }
        if v.is_empty() {
            "none".into()
        } else {
            v.join(", ")
        }
    }

    /// True when the right-hand side is nonlinear (backlash or friction): integrated by RK4
    /// ([`crate::Dynamics::paper_rig`]), in the diagnosis and in the FMU alike.
    pub fn is_nonlinear(&self) -> bool {
        self.backlash_rad > 0.0 || self.coulomb_friction_nm.iter().any(|&f| f > 0.0)
    }
}

/// A rig: its reduced parameters, optionally its full chain, and the variant to study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Rig {
    /// Free-text name.
    pub name: String,
    /// Variant the commands use unless told otherwise.
    pub variant: Variant,
    /// Reduced three-mass parameters.
    pub model: RigParams,
    /// The full chain, where known.
    pub chain: Option<RigChain>,
    /// The shaft line with the additional spring as a beam on its bearings (section 2.5).
    pub bending: Option<crate::bending::Beam>,
    /// A bearing test element on its support, exported beside the powertrain by the FMU.
    pub bearing: Option<crate::bearing::BearingModel>,
    /// Drive-path effects the reduced model leaves out (found by `rigtwin diagnose`).
    pub effects: DriveEffects,
}

impl Rig {
    /// Checks the whole rig.
    pub fn validate(&self) -> Result<()> {
        self.model.validate("model")?;
        if let Some(c) = &self.chain {
            c.validate()?;
        }
        if let Some(b) = &self.bending {
            b.validate("bending")?;
        }
        if let Some(b) = &self.bearing {
            b.validate()?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Side gears of vanishing inertia give the reduced open differential's frequencies (the
    /// fourth mode, the side gears against each other, goes to infinity); the rigid motion's
    /// inertia is the cage's and both side gears'.
    #[test]
    fn side_gears_vanish_into_the_open_differential() {
        let rig = crate::paper::damped_params();
        for variant in Variant::ALL {
            let reduced = rig.open_differential(variant).unwrap().modes().unwrap().frequencies_hz;
            let with = rig.open_differential_with_side_gears(variant, 1e-9).unwrap().modes().unwrap().frequencies_hz;
            for k in 0..3 {
                assert!((reduced[k] - with[k]).abs() <= 1e-6 * reduced[2], "{variant}: {reduced:?} vs {with:?}");
            }
            assert!(with[3] > 100.0 * reduced[2]);
            // the rigid motion carries both side gears beside the cage
            let m = rig.open_differential_with_side_gears(variant, 0.01).unwrap();
            let ones = DVector::from_element(4, 1.0);
            let e = rig.effective(variant).unwrap();
            let total = (ones.transpose() * &m.inertia * &ones)[(0, 0)];
            assert!((total - (e.j_m2 + e.j_drive + 0.02 + e.j_m3)).abs() < 1e-12);
        }
        assert!(rig.open_differential_with_side_gears(Variant::V1, 0.0).is_err());
    }
    use approx::assert_relative_eq;
    use std::f64::consts::PI;

    fn params() -> RigParams {
        RigParams::new(0.9, 0.5, 1.1, 1500.0, 60000.0)
    }

    #[test]
    fn differential_stiffness_is_eq_a1() {
        let p = params();
        let k = p.open_differential(Variant::V1).unwrap().stiffness_matrix();
        let (c2, c3) = (p.c_short, p.c_long());
        let s = c2 + c3;
        // Diagonal of eq. (A1), typed from the paper (sums of squares: no sign lost in print).
        assert_relative_eq!(k[(0, 0)], c2 * (c2 / s - 1.0).powi(2) + c2 * c2 * c3 / (s * s), max_relative = 1e-12);
        assert_relative_eq!(
            k[(1, 1)],
            c2 * (2.0 * c2 / s - 2.0).powi(2) + 4.0 * c2 * c2 * c3 / (s * s),
            max_relative = 1e-12
        );
        assert_relative_eq!(k[(2, 2)], c3 * (c3 / s - 1.0).powi(2) + c2 * c3 * c3 / (s * s), max_relative = 1e-12);
        // Whole matrix: static condensation of eq. (29) (q = [φm2, φdrive, φd3, φm3]) on the
        // massless φd3, the step eq. (30) takes; independent of the spring-vector assembly.
        let v = DMatrix::from_row_slice(
            4,
            4,
            &[
                c2,
                -2.0 * c2,
                c2,
                0.0,
                -2.0 * c2,
                4.0 * c2,
                -2.0 * c2,
                0.0,
                c2,
                -2.0 * c2,
                c2 + c3,
                -c3,
                0.0,
                0.0,
                -c3,
                c3,
            ],
        );
        let keep = [0, 1, 3];
        let schur =
            DMatrix::from_fn(3, 3, |i, j| v[(keep[i], keep[j])] - v[(keep[i], 2)] * v[(2, keep[j])] / v[(2, 2)]);
        assert_relative_eq!(k, schur, max_relative = 1e-12, epsilon = 1e-9);
    }

    #[test]
    fn differential_has_two_zero_modes_and_the_analytic_shuffle() {
        let p = params();
        let m = p.open_differential(Variant::V1).unwrap().modes().unwrap();
        assert_eq!(&m.frequencies_hz[..2], &[0.0, 0.0]);
        let cs = p.c_short * p.c_long() / (p.c_short + p.c_long());
        let w = (cs * (1.0 / 0.9 + 4.0 / 0.5 + 1.0 / 1.1)).sqrt();
        assert_relative_eq!(m.frequencies_hz[2], w / (2.0 * PI), max_relative = 1e-12);
    }

    #[test]
    fn shaft_damping_ratio_is_met_exactly() {
        let p = params().with_shaft_damping_ratio(0.05, Variant::V2).unwrap();
        let ss = p.open_differential(Variant::V2).unwrap().state_space(&[]).unwrap();
        let poles = ss.damp().unwrap();
        let shuffle = poles.iter().find(|p| p.natural_hz > 1.0).unwrap();
        assert_relative_eq!(shuffle.damping_ratio.unwrap(), 0.05, max_relative = 1e-9);
    }

    #[test]
    fn spring_variant_without_c_delta_is_an_error() {
        let mut p = params();
        p.c_delta = 0.0;
        assert!(p.three_mass(Variant::V1).is_ok());
        let e = p.three_mass(Variant::V3).unwrap_err().to_string();
        assert!(e.contains("model.c_delta"), "{e}");
    }

    #[test]
    fn variants_parse() {
        assert_eq!("V3".parse::<Variant>().unwrap(), Variant::V3);
        assert!("V5".parse::<Variant>().is_err());
        assert!(Variant::V4.left_spring() && !Variant::V4.right_spring());
    }
}
