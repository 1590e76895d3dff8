//! One settings struct for the controller: horizon, signals and their weights and bounds, the
//! estimator's noise model and the QP solver's options.

use serde::{Deserialize, Serialize};

use crate::error::{setting, Result};

/// How the QP is posed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Formulation {
    /// Decision variables are the (blocked) inputs only; states are eliminated by the
    /// prediction x = Φx₀ + Γu. Small and dense.
    Condensed,
    /// States and inputs are both decision variables, tied by the dynamics as equality
    /// constraints. Large and sparse (banded KKT system).
    Sparse,
}

/// One manipulated input (a machine torque).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InputSettings {
    /// The plant input's name, e.g. `M_drive`.
    pub name: String,
    /// Hard lower bound, Nm.
    pub min_nm: f64,
    /// Hard upper bound, Nm.
    pub max_nm: f64,
    /// Hard bound on |u[k] − u[k−1]| / dt, Nm/s.
    pub max_rate_nm_per_s: f64,
    /// Weight on (u − u_target)², 1/Nm².
    pub weight_per_nm2: f64,
    /// Weight on (u[k] − u[k−1])², 1/Nm².
    pub rate_weight_per_nm2: f64,
    /// The input has a reference (its target is the reference, e.g. the drive torque that
    /// the engine model asks for).
    pub tracked: bool,
    /// Standard deviation of the input disturbance's random walk per step, Nm (the
    /// estimator's model of unmeasured torques: drag, friction, a mis-set inertia); 0: this
    /// input carries no disturbance.
    pub disturbance_std_nm: f64,
}

/// One plant output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OutputSettings {
    /// The plant output's name, e.g. `w_m2` or `T_short_side_shaft`.
    pub name: String,
    /// Measured, with this noise standard deviation (in the output's unit); `None`: not
    /// measured.
    pub noise_std: Option<f64>,
    /// The output has a reference (tracked at steady state).
    pub tracked: bool,
    /// Weight on (y − y_target)² over the horizon, 1/unit². For the side-shaft torques this
    /// is the penalty on the shuffle oscillation.
    pub weight: f64,
    /// Soft lower bound (slack-penalised), unit.
    pub soft_min: Option<f64>,
    /// Soft upper bound (slack-penalised), unit.
    pub soft_max: Option<f64>,
}

/// The QP solver's (Clarabel's) options that matter for a real-time loop.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolverSettings {
    /// Absolute and relative duality-gap tolerance.
    pub tol_gap: f64,
    /// Primal/dual feasibility tolerance.
    pub tol_feas: f64,
    /// Iteration limit.
    pub max_iter: u32,
    /// Wall-clock limit of one solve, s (the fallback plan is used when it is exceeded).
    pub time_limit_s: f64,
    /// Ruiz equilibration of the QP data.
    pub equilibrate: bool,
    /// Iterative refinement of each KKT solve.
    pub iterative_refinement: bool,
    /// Before the interior-point solve, try the optimum with every inequality inactive (one
    /// triangular solve with the factor of P kept from the set-up, one check of the rows): when
    /// no bound and no soft bound is active — most steps of a settled loop — it is the exact
    /// optimum, and the interior-point method is not run (condensed formulation only).
    #[serde(default = "yes")]
    pub unconstrained_check: bool,
}

fn yes() -> bool {
    true
}

/// Everything that defines the controller.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MpcSettings {
    /// Sample time, s.
    pub dt_s: f64,
    /// Prediction horizon, steps.
    pub horizon: usize,
    /// Move blocking: lengths of the blocks over which the inputs are held (they sum to the
    /// horizon); empty = every step free.
    pub move_blocks: Vec<usize>,
    /// How the QP is posed.
    pub formulation: Formulation,
    /// Inputs are solved for in units of this torque (100 Nm conditions the QP far better
    /// than raw Nm).
    pub input_scale_nm: f64,
    /// Terminal cost from the discrete Riccati equation (else the stage cost).
    pub terminal_cost: bool,
    /// Soft output bounds at every step of the horizon (else at the end of every move block).
    pub soft_bounds_every_step: bool,
    /// Linear penalty on the soft-bound slack, per unit.
    pub slack_linear: f64,
    /// Quadratic penalty on the soft-bound slack, per unit².
    pub slack_quadratic: f64,
    /// Process noise of the (reduced) states in the estimator, relative to the measurement
    /// noise.
    pub state_noise_ratio: f64,
    /// The manipulated inputs (every plant input must be listed).
    pub inputs: Vec<InputSettings>,
    /// The outputs used (measured, tracked, penalised or bounded).
    pub outputs: Vec<OutputSettings>,
    /// The QP solver's options.
    pub solver: SolverSettings,
}

/// A model file's `[mpc]` section: what the controller tracks and penalises and the inputs'
/// bounds. Every key is optional; [`MpcSection::rig_settings`] and
/// [`MpcSection::drive_settings`] give the defaults.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MpcSection {
    /// Outputs with a reference (speeds). Drive: default the last body's speed. The rig's are
    /// fixed (w_m2, w_m3).
    pub tracked: Option<Vec<String>>,
    /// Inputs that follow a reference. Drive: default none. The rig's is fixed (M_drive).
    pub tracked_inputs: Option<Vec<String>>,
    /// Coupling forces (torques) whose oscillation is penalised. Drive: default every
    /// coupling. The rig's are fixed (both side shafts).
    pub penalised: Option<Vec<String>>,
    /// Measured outputs. Drive: default every body's speed. The rig's are fixed (the three speeds).
    pub measured: Option<Vec<String>>,
    /// |u| bound of each input, in the model's input order, N·m or N. Rig: default 300, 200,
    /// 300 N·m; drive: required (the actuators' limits).
    pub input_max: Option<Vec<f64>>,
    /// Rate bound of each input, N·m/s or N/s. Rig: default 1e5, 4e4, 1e5; drive: default
    /// input_max per 10 ms.
    pub input_rate_max: Option<Vec<f64>>,
    /// Weight on a tracked speed's error, per (rad/s)² or (m/s)². Default 100.
    pub speed_weight: Option<f64>,
    /// Weight on a penalised force's oscillation, per (N·m)² or N². Rig: default 1; drive:
    /// (30 / U)² with U the largest input bound (a force of U costs as much as a 3 rad/s speed
    /// error at the default speed weight; (300 / U)² — the rig's ratio — held a geared drive's
    /// step back to a creep: its couplings must carry several times U while it accelerates).
    pub force_weight: Option<f64>,
    /// Soft bound on |penalised force|, N·m or N. Rig: default 60; drive: none.
    pub force_soft_max: Option<f64>,
}

impl MpcSection {
    fn lengths(&self, m: usize) -> Result<()> {
        for (key, v) in [("input_max", &self.input_max), ("input_rate_max", &self.input_rate_max)] {
            if let Some(v) = v {
                if v.len() != m {
                    return Err(setting(
                        format!("[mpc] {key}"),
                        format!("{} values for the model's {m} inputs", v.len()),
                    ));
                }
                if let Some(x) = v.iter().find(|x| !(x.is_finite() && **x > 0.0)) {
                    return Err(setting(format!("[mpc] {key}"), format!("{x}: expected positive, finite values")));
                }
            }
        }
        for (key, v) in [
            ("speed_weight", self.speed_weight),
            ("force_weight", self.force_weight),
            ("force_soft_max", self.force_soft_max),
        ] {
            if let Some(x) = v.filter(|x| !(x.is_finite() && *x > 0.0)) {
                return Err(setting(format!("[mpc] {key}"), format!("{x}: expected a positive, finite value")));
            }
        }
        Ok(())
    }

    /// The paper rig's settings ([`MpcSettings::powertrain`]) with the section's weights and
    /// bounds (inputs M_m2, M_drive, M_m3). Its tracked, penalised and measured signals are
    /// fixed: naming them is an error.
    pub fn rig_settings(&self, horizon: usize) -> Result<MpcSettings> {
        for (key, given) in [
            ("tracked", self.tracked.is_some()),
            ("tracked_inputs", self.tracked_inputs.is_some()),
            ("penalised", self.penalised.is_some()),
            ("measured", self.measured.is_some()),
        ] {
            if given {
                return Err(setting(
                    format!("[mpc] {key}"),
                    "the paper rig's signals are fixed (tracked w_m2, w_m3 and M_drive; penalised both side shafts; measured the three speeds): give only weights and bounds",
                ));
            }
        }
        self.lengths(3)?;
        let mut s = MpcSettings::powertrain(horizon);
        for (j, u) in s.inputs.iter_mut().enumerate() {
            if let Some(v) = &self.input_max {
                u.min_nm = -v[j];
                u.max_nm = v[j];
            }
            if let Some(v) = &self.input_rate_max {
                u.max_rate_nm_per_s = v[j];
            }
        }
        for y in s.outputs.iter_mut() {
            if y.tracked {
                y.weight = self.speed_weight.unwrap_or(y.weight);
            }
            if y.name.starts_with("T_") {
                y.weight = self.force_weight.unwrap_or(y.weight);
                if let Some(b) = self.force_soft_max {
                    y.soft_min = Some(-b);
                    y.soft_max = Some(b);
                }
            }
        }
        s.validate()?;
        Ok(s)
    }

    /// Without `input_max`, the bounds a record shows: each input's peak |value| in `inputs`
    /// (one series per input) — what the actuators reached in that test, not their limits.
    /// Returns whether the bounds were taken from the record.
    pub fn bound_by_record(&mut self, inputs: &[Vec<f64>]) -> bool {
        if self.input_max.is_some() {
            return false;
        }
        self.input_max = Some(inputs.iter().map(|u| u.iter().fold(0.0_f64, |a, v| a.max(v.abs()))).collect());
        true
    }

    /// A drive model's weights on its tracked speeds and its penalised forces: the section's, or
    /// 100 and (30/U)² for the largest input bound U (the rig's proportions to its 300 N·m).
    pub fn drive_weights(&self, largest_input_max: f64) -> (f64, f64) {
        (self.speed_weight.unwrap_or(100.0), self.force_weight.unwrap_or((30.0 / largest_input_max).powi(2)))
    }

    /// Settings for a drive model whose controller state space has `inputs` and `outputs`
    /// (speeds `w_*`/`v_*`, forces): the section's signals (defaults above) and bounds, the
    /// weights scaled to the largest input bound U as the rig's are to its 300 N·m (input
    /// 0.09/U², move 9/U², a tracked input 1600/U²), an input disturbance on every input that
    /// does not follow a reference (std U/300), speeds measured with 0.01 noise.
    pub fn drive_settings(&self, inputs: &[String], outputs: &[String], horizon: usize) -> Result<MpcSettings> {
        let m = inputs.len();
        self.lengths(m)?;
        let max = self.input_max.clone().ok_or_else(|| {
            setting(
                "[mpc] input_max",
                format!(
                    "required for a drive model: the bounds of its inputs {}; add to the model file\n\n[mpc]\ninput_max = [{}]  # |input| limit of each, N·m (N on a linear axis)\n",
                    inputs.join(", "),
                    vec!["LIMIT"; inputs.len()].join(", ")
                ),
            )
        })?;
        let rate = self.input_rate_max.clone().unwrap_or_else(|| max.iter().map(|v| v / 0.01).collect());
        let big = max.iter().copied().fold(0.0, f64::max);
        let is_speed = |n: &String| n.starts_with("w_") || n.starts_with("v_");
        let speeds: Vec<String> = outputs.iter().filter(|n| is_speed(n)).cloned().collect();
        let forces: Vec<String> = outputs.iter().filter(|n| !is_speed(n)).cloned().collect();
        let tracked = self.tracked.clone().unwrap_or_else(|| speeds.last().cloned().into_iter().collect());
        let tracked_inputs = self.tracked_inputs.clone().unwrap_or_default();
        let penalised = self.penalised.clone().unwrap_or(forces);
        let measured = self.measured.clone().unwrap_or(speeds);
        let known = |key: &str, list: &[String], names: &[String]| -> Result<()> {
            match list.iter().find(|n| !names.contains(n)) {
                Some(n) => Err(setting(
                    format!("[mpc] {key}"),
                    format!("no signal `{n}` (the model has {})", names.join(", ")),
                )),
                None => Ok(()),
            }
        };
        known("tracked", &tracked, outputs)?;
        known("penalised", &penalised, outputs)?;
        known("measured", &measured, outputs)?;
        known("tracked_inputs", &tracked_inputs, inputs)?;
        let (speed_weight, force_weight) = self.drive_weights(big);
        let mut names: Vec<&String> = tracked.iter().chain(&penalised).chain(&measured).collect();
        names.sort();
        names.dedup();
        let outputs = names
            .into_iter()
            .map(|n| {
                let force = penalised.contains(n);
                OutputSettings {
                    name: n.clone(),
                    noise_std: measured.contains(n).then_some(0.01),
                    tracked: tracked.contains(n),
                    weight: if tracked.contains(n) {
                        speed_weight
                    } else if force {
                        force_weight
                    } else {
                        1.0
                    },
                    soft_min: if force { self.force_soft_max.map(|b| -b) } else { None },
                    soft_max: if force { self.force_soft_max } else { None },
                }
            })
            .collect();
        let inputs = inputs
            .iter()
            .enumerate()
            .map(|(j, name)| {
                let follows = tracked_inputs.contains(name);
                let u2 = max[j] * max[j];
                InputSettings {
                    name: name.clone(),
                    min_nm: -max[j],
                    max_nm: max[j],
                    max_rate_nm_per_s: rate[j],
                    weight_per_nm2: if follows { 1600.0 / u2 } else { 0.09 / u2 },
                    rate_weight_per_nm2: 9.0 / u2,
                    tracked: follows,
                    disturbance_std_nm: if follows { 0.0 } else { max[j] / 300.0 },
                }
            })
            .collect();
        let base = MpcSettings::powertrain(horizon);
        let s = MpcSettings { input_scale_nm: big / 3.0, inputs, outputs, ..base };
        s.validate()?;
        Ok(s)
    }
}

/// Longest prediction horizon, steps: twice the real-time regime's longest (10–100 steps at
/// 1 ms). The QP's size grows with it (the sparse formulation's KKT system by the horizon times
/// the states, the condensed one's dense Hessian by its square), and a longer horizon cannot be
/// solved within a 1 kHz loop's step on this class of machine.
pub const MAX_HORIZON: usize = 200;

/// Move blocks 1, 2, 4, … doubling, at most `count` of them, the last one taking the rest of
/// `horizon`: fine near the present where the first input is decided, coarse far out.
pub fn exponential_blocks(horizon: usize, count: usize) -> Vec<usize> {
    let mut blocks = Vec::new();
    let (mut sum, mut len) = (0, 1);
    while sum < horizon {
        let l = if blocks.len() + 1 >= count.max(1) { horizon - sum } else { len.min(horizon - sum) };
        blocks.push(l);
        sum += l;
        len *= 2;
    }
    blocks
}

impl Default for SolverSettings {
    /// Duality-gap tolerance 1e-8: at N = 50 the first input is within 1e-4 Nm of the exact
    /// optimum (1e-3 Nm at 1e-7, same iteration count); the time limit is 60 % of a 1 kHz
    /// period. Iterative refinement is off:
    /// on this QP it doubled the solve time (measured with `rigtwin mpc`) without changing the first
    /// input by more than 1e-5 Nm.
    fn default() -> Self {
        SolverSettings {
            tol_gap: 1e-8,
            tol_feas: 1e-7,
            max_iter: 50,
            time_limit_s: 6e-4,
            equilibrate: true,
            iterative_refinement: false,
            unconstrained_check: true,
        }
    }
}

impl MpcSettings {
    /// Road-load emulation on the open-differential rig (inputs `M_m2`, `M_drive`, `M_m3`;
    /// outputs `w_*` and `T_*_side_shaft`): the load machines hold their speed references,
    /// the drive follows its torque reference, the side-shaft torques' oscillation about
    /// their steady state is penalised and soft-bounded. Horizon `horizon` at 1 ms.
    pub fn powertrain(horizon: usize) -> Self {
        let load = |name: &str| InputSettings {
            name: name.into(),
            min_nm: -300.0,
            max_nm: 300.0,
            max_rate_nm_per_s: 1e5,
            weight_per_nm2: 1e-6,
            rate_weight_per_nm2: 1e-4,
            tracked: false,
            disturbance_std_nm: 1.0,
        };
        let speed = |name: &str, tracked: bool| OutputSettings {
            name: name.into(),
            noise_std: Some(0.01),
            tracked,
            weight: if tracked { 100.0 } else { 1.0 },
            soft_min: None,
            soft_max: None,
        };
        let shaft = |name: &str| OutputSettings {
            name: name.into(),
            noise_std: None,
            tracked: false,
            weight: 1.0,
            soft_min: Some(-60.0),
            soft_max: Some(60.0),
        };
        MpcSettings {
            dt_s: 1e-3,
            horizon,
            move_blocks: exponential_blocks(horizon, 4),
            formulation: Formulation::Condensed,
            input_scale_nm: 100.0,
            terminal_cost: true,
            soft_bounds_every_step: false,
            slack_linear: 1e3,
            slack_quadratic: 1e2,
            state_noise_ratio: 1e-3,
            inputs: vec![
                load("M_m2"),
                InputSettings {
                    name: "M_drive".into(),
                    min_nm: -200.0,
                    max_nm: 200.0,
                    max_rate_nm_per_s: 4e4,
                    weight_per_nm2: 0.04,
                    rate_weight_per_nm2: 1e-4,
                    tracked: true,
                    disturbance_std_nm: 0.0,
                },
                load("M_m3"),
            ],
            outputs: vec![
                speed("w_m2", true),
                speed("w_drive", false),
                speed("w_m3", true),
                shaft("T_short_side_shaft"),
                shaft("T_long_side_shaft"),
            ],
            solver: SolverSettings::default(),
        }
    }

    /// Names of the references a controller of these settings takes, in order: the tracked
    /// outputs, then the tracked inputs (as [`crate::Controller::reference_names`] for inputs
    /// listed in the plant's order).
    pub fn reference_names(&self) -> Vec<String> {
        let outputs = self.outputs.iter().filter(|o| o.tracked).map(|o| o.name.clone());
        outputs.chain(self.inputs.iter().filter(|u| u.tracked).map(|u| u.name.clone())).collect()
    }

    /// Checks ranges and consistency; names the offending setting.
    pub fn validate(&self) -> Result<()> {
        let pos = |key: &str, v: f64| {
            if v > 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(setting(key, format!("must be a positive, finite number, got {v}")))
            }
        };
        let nonneg = |key: &str, v: f64| {
            if v >= 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(setting(key, format!("must be a non-negative, finite number, got {v}")))
            }
        };
        pos("dt_s", self.dt_s)?;
        if self.horizon == 0 || self.horizon > MAX_HORIZON {
            return Err(setting("horizon", format!("must be 1..={MAX_HORIZON} steps, got {}", self.horizon)));
        }
        if !self.move_blocks.is_empty() {
            let sum: usize = self.move_blocks.iter().sum();
            if sum != self.horizon || self.move_blocks.contains(&0) {
                return Err(setting(
                    "move_blocks",
                    format!(
                        "block lengths must be ≥ 1 and sum to the horizon {}, got {:?}",
                        self.horizon, self.move_blocks
                    ),
                ));
            }
        }
        pos("input_scale_nm", self.input_scale_nm)?;
        nonneg("slack_linear", self.slack_linear)?;
        pos("slack_quadratic", self.slack_quadratic)?;
        pos("state_noise_ratio", self.state_noise_ratio)?;
        for (i, u) in self.inputs.iter().enumerate() {
            let key = |f: &str| format!("inputs[{i}].{f}");
            if u.min_nm.partial_cmp(&u.max_nm) != Some(std::cmp::Ordering::Less)
                || !u.min_nm.is_finite()
                || !u.max_nm.is_finite()
            {
                return Err(setting(
                    key("min_nm"),
                    format!("need finite min_nm < max_nm, got {} and {}", u.min_nm, u.max_nm),
                ));
            }
            pos(&key("max_rate_nm_per_s"), u.max_rate_nm_per_s)?;
            pos(&key("weight_per_nm2"), u.weight_per_nm2)?;
            nonneg(&key("rate_weight_per_nm2"), u.rate_weight_per_nm2)?;
            nonneg(&key("disturbance_std_nm"), u.disturbance_std_nm)?;
        }
        for (i, y) in self.outputs.iter().enumerate() {
            let key = |f: &str| format!("outputs[{i}].{f}");
            if let Some(s) = y.noise_std {
                pos(&key("noise_std"), s)?;
            }
            nonneg(&key("weight"), y.weight)?;
            if let (Some(lo), Some(hi)) = (y.soft_min, y.soft_max) {
                if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
                    return Err(setting(key("soft_min"), format!("need soft_min < soft_max, got {lo} and {hi}")));
                }
            }
            for v in [y.soft_min, y.soft_max].into_iter().flatten() {
                if !v.is_finite() {
                    return Err(setting(key("soft_max"), "soft bounds must be finite"));
                }
            }
        }
        if !self.outputs.iter().any(|y| y.noise_std.is_some()) {
            return Err(setting("outputs", "at least one output must be measured (noise_std)"));
        }
        pos("solver.tol_gap", self.solver.tol_gap)?;
        pos("solver.tol_feas", self.solver.tol_feas)?;
        pos("solver.time_limit_s", self.solver.time_limit_s)?;
        if self.solver.max_iter == 0 {
            return Err(setting("solver.max_iter", "must be at least 1"));
        }
        Ok(())
    }

    /// The move blocks actually used (every step its own block when none are set).
    pub fn blocks(&self) -> Vec<usize> {
        if self.move_blocks.is_empty() {
            vec![1; self.horizon]
        } else {
            self.move_blocks.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponential_blocks_cover_the_horizon() {
        assert_eq!(exponential_blocks(10, 5), vec![1, 2, 4, 3]);
        assert_eq!(exponential_blocks(50, 5), vec![1, 2, 4, 8, 35]);
        assert_eq!(exponential_blocks(50, 1), vec![50]);
        for n in 1..200 {
            for c in 1..8 {
                let b = exponential_blocks(n, c);
                assert_eq!(b.iter().sum::<usize>(), n);
                assert!(b.len() <= c);
            }
        }
    }
}

#[cfg(test)]
mod section_tests {
    use super::*;

    #[test]
    fn an_empty_section_is_the_rig_default() {
        assert_eq!(MpcSection::default().rig_settings(50).unwrap(), MpcSettings::powertrain(50));
        let s =
            MpcSection { input_max: Some(vec![250.0, 150.0, 250.0]), speed_weight: Some(50.0), ..Default::default() };
        let r = s.rig_settings(50).unwrap();
        assert_eq!((r.inputs[1].min_nm, r.inputs[1].max_nm), (-150.0, 150.0));
        assert_eq!(r.outputs.iter().filter(|o| o.tracked).map(|o| o.weight).collect::<Vec<_>>(), [50.0, 50.0]);
        let e = MpcSection { tracked: Some(vec!["w_drive".into()]), ..Default::default() }.rig_settings(50);
        assert!(e.unwrap_err().to_string().contains("[mpc] tracked"));
        let e = MpcSection { input_max: Some(vec![1.0]), ..Default::default() }.rig_settings(50);
        assert!(e.unwrap_err().to_string().contains("1 values for the model's 3 inputs"));
    }

    #[test]
    fn a_drive_section_names_what_is_wrong() {
        let inputs = vec!["M_motor".to_string()];
        let outputs: Vec<String> = ["w_motor", "w_load", "T_coupling_1"].map(String::from).into();
        let e = MpcSection::default().drive_settings(&inputs, &outputs, 50).unwrap_err().to_string();
        assert!(e.contains("input_max") && e.contains("M_motor"), "{e}");
        let s = MpcSection { input_max: Some(vec![5.0]), ..Default::default() };
        let d = s.drive_settings(&inputs, &outputs, 50).unwrap();
        // defaults: the last speed tracked, every coupling penalised, every speed measured
        let tracked: Vec<&str> = d.outputs.iter().filter(|o| o.tracked).map(|o| o.name.as_str()).collect();
        assert_eq!(tracked, ["w_load"]);
        assert!(d.outputs.iter().any(|o| o.name == "T_coupling_1" && o.noise_std.is_none()));
        assert_eq!(d.outputs.iter().filter(|o| o.noise_std.is_some()).count(), 2);
        assert_eq!(d.inputs[0].max_rate_nm_per_s, 500.0);
        let bad = MpcSection { tracked: Some(vec!["w_nowhere".into()]), ..s.clone() };
        let e = bad.drive_settings(&inputs, &outputs, 50).unwrap_err().to_string();
        assert!(e.contains("w_nowhere") && e.contains("w_motor, w_load"), "{e}");
    }
}
