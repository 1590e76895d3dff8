//! A drive model as its FMU steps it ([`Stepper`]), closed in a loop: the plant a controller
//! of any drive model is tried on (`rigtwin mpc`, the C API's and the controller FMU's tests).

use nalgebra::DVector;
use plant::rig::DriveEffects;
use plant::{DelayLine, DriveModel, RigParams, Stepper, Variant};

use crate::closed_loop::Plant;
use crate::error::{MpcError, Result};

/// Where an output comes from.
#[derive(Debug, Clone, Copy)]
enum Source {
    /// A state (a body's speed).
    Speed(usize),
    /// A coupling's force.
    Force(usize),
}

/// A drive model as the FMU integrates it (`plant::Stepper`: exact ZOH
/// pieces between the dead times' switching instants, RK4 with friction or play), its outputs
/// in the order of the controller state space's names (speeds, coupling forces).
pub struct DrivePlant {
    dynamics: Stepper,
    x: DVector<f64>,
    delays: Vec<DelayLine>,
    t: f64,
    dt_s: f64,
    /// Per output: a state index (speed) or a coupling (force).
    outputs: Vec<Source>,
    y: Vec<f64>,
    /// Every coupling's force now.
    forces: Vec<f64>,
}

impl DrivePlant {
    /// The plant of `model` at rest, sampled every `dt_s`, reporting `output_names`.
    pub fn new(model: &DriveModel, dt_s: f64, output_names: &[String]) -> Result<Self> {
        let stepper = Stepper::new(model)?;
        let nu = model.inputs.len();
        let x0 = stepper.dynamics.initial_state(0.0, &vec![0.0; nu]);
        DrivePlant::starting(model, stepper, dt_s, &x0, &vec![0.0; nu], output_names)
    }

    /// The plant of `model` stepped by `stepper` (a preset's: the paper rig steps in its own
    /// coordinates, `plant::Stepper::paper_rig`), from the plant's state `x0` with
    /// the inputs `u0` applied before the start, sampled every `dt_s`, reporting
    /// `output_names` (the bodies' speeds, the couplings' forces).
    pub fn starting(
        model: &DriveModel,
        stepper: Stepper,
        dt_s: f64,
        x0: &[f64],
        u0: &[f64],
        output_names: &[String],
    ) -> Result<Self> {
        let n = model.line.bodies.len();
        let states = model.state_names();
        let forces = model.coupling_force_names();
        let outputs = output_names
            .iter()
            .map(|name| {
                if let Some(i) = states[n..2 * n].iter().position(|s| s == name) {
                    Ok(Source::Speed(n + i))
                } else if let Some(i) = forces.iter().position(|s| s == name) {
                    Ok(Source::Force(i))
                } else {
                    Err(MpcError::UnknownSignal {
                        key: "outputs".into(),
                        kind: "output",
                        name: name.clone(),
                        available: [&states[n..2 * n], &forces[..]].concat().join(", "),
                    })
                }
            })
            .collect::<Result<Vec<_>>>()?;
        let nu = model.inputs.len();
        let x = stepper.state_of(x0);
        let mut delays = vec![DelayLine::default(); nu];
        for (d, &u) in delays.iter_mut().zip(u0.iter().chain(std::iter::repeat(&0.0))) {
            d.record(f64::NEG_INFINITY, u);
        }
        let mut p = DrivePlant {
            forces: vec![0.0; stepper.couplings()],
            dynamics: stepper,
            x,
            delays,
            t: 0.0,
            dt_s,
            y: vec![0.0; outputs.len()],
            outputs,
        };
        p.read();
        Ok(p)
    }

    /// The paper rig (`rig` in `variant` with `effects`) as its FMU steps it
    /// (`plant::Stepper::paper_rig`), spinning steadily at `speed_radps` with no drive torque and
    /// `u0` applied before the start, sampled every `dt_s`, reporting `output_names`.
    pub fn paper_rig(
        rig: &RigParams,
        variant: Variant,
        effects: &DriveEffects,
        dt_s: f64,
        speed_radps: f64,
        u0: &[f64],
        output_names: &[String],
    ) -> Result<Self> {
        let truth = DriveModel::paper_rig(rig, variant, effects)?;
        let x0 = plant::record_start(&truth, 0.0, speed_radps);
        DrivePlant::starting(&truth, Stepper::paper_rig(&truth)?, dt_s, &x0, u0, output_names)
    }

    fn read(&mut self) {
        self.dynamics.coupling_forces(self.x.as_slice(), &mut self.forces);
        for (y, s) in self.y.iter_mut().zip(&self.outputs) {
            *y = match *s {
                Source::Speed(i) => self.x[i],
                Source::Force(i) => self.forces[i],
            };
        }
    }
}

impl Plant for DrivePlant {
    fn outputs(&self) -> &[f64] {
        &self.y
    }
    fn advance(&mut self, u: &[f64]) -> std::result::Result<(), String> {
        for (j, line) in self.delays.iter_mut().enumerate() {
            if self.dynamics.dynamics.delay_s(j) > 0.0 {
                line.record(self.t, u[j]);
            }
        }
        self.dynamics.step(&mut self.x, u, self.t, self.dt_s, &self.delays).map_err(|e| e.to_string())?;
        self.t += self.dt_s;
        for (j, line) in self.delays.iter_mut().enumerate() {
            line.forget_before(self.t, self.dynamics.dynamics.delay_s(j));
        }
        self.read();
        Ok(())
    }
}
