//! A first-order lag of an input (a drive's torque control).

use serde::{Deserialize, Serialize};

use super::{EffectModel, EffectParameter, Element, Search, SizeContext, INPUT_TIME_SEARCH};
use crate::drive::{Dimension, DriveModel, Dynamics};

/// The force on the body follows the recorded input through τ ż = u − z.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ActuatorLag {
    /// The input.
    pub input: usize,
    /// Time constant τ, s.
    pub time_constant_s: f64,
}

impl EffectModel for ActuatorLag {
    const NAME: &'static str = "actuator_lag";
    const PARAMETERS: &'static [EffectParameter] = &[EffectParameter {
        name: "time_constant",
        key: "time_constant",
        dimension: Dimension::Time,
        what: "first-order lag",
    }];

    const PREDICTION: &'static str = "in the prediction as a state";
    const SEARCH: Search = INPUT_TIME_SEARCH;

    fn element(&self) -> Element {
        Element::Input(self.input)
    }
    fn at_index(self, input: usize) -> Self {
        ActuatorLag { input, ..self }
    }
    fn values(&self) -> Vec<f64> {
        vec![self.time_constant_s]
    }
    fn set_values(&mut self, v: &[f64]) {
        self.time_constant_s = v[0];
    }
    fn state_names(&self, model: &DriveModel) -> Vec<String> {
        vec![format!("{}_lagged", Element::Input(self.input).label(model))]
    }
    fn of_size(self, time_constant_s: f64, _: &SizeContext) -> Self {
        ActuatorLag { time_constant_s, ..self }
    }
    /// One state z after the angles and speeds; the body feels z instead of the input.
    fn enter(&self, d: &mut Dynamics) {
        let input = &mut d.inputs[self.input];
        input.2 = self.time_constant_s;
        input.3 = d.nstates;
        d.nstates += 1;
    }
}
