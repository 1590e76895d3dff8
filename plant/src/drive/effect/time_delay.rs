//! A dead time of an input (a drive's torque reaching its body late).

use serde::{Deserialize, Serialize};

use super::{EffectModel, EffectParameter, Element, Search, SizeContext, INPUT_TIME_SEARCH};
use crate::drive::{Dimension, Dynamics};

/// The input reaches its body `delay_s` later than recorded.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TimeDelay {
    /// The input (position among the model's inputs).
    pub input: usize,
    /// Dead time, s.
    pub delay_s: f64,
}

impl EffectModel for TimeDelay {
    const NAME: &'static str = "time_delay";
    const PARAMETERS: &'static [EffectParameter] =
        &[EffectParameter { name: "delay", key: "delay", dimension: Dimension::Time, what: "dead time" }];

    const PREDICTION: &'static str = "in the prediction as input-delay states (the whole samples of the delay, its fraction by the split of the held input)";
    const SEARCH: Search = INPUT_TIME_SEARCH;

    fn element(&self) -> Element {
        Element::Input(self.input)
    }
    fn at_index(self, input: usize) -> Self {
        TimeDelay { input, ..self }
    }
    fn values(&self) -> Vec<f64> {
        vec![self.delay_s]
    }
    fn set_values(&mut self, v: &[f64]) {
        self.delay_s = v[0];
    }
    fn of_size(self, delay_s: f64, _: &SizeContext) -> Self {
        TimeDelay { delay_s, ..self }
    }
    /// The right-hand side sees the input after its dead time: the simulation shifts the held
    /// sequence (whole samples and a fraction), the linearisation's input is the delayed one.
    fn enter(&self, d: &mut Dynamics) {
        d.inputs[self.input].1 = self.delay_s;
    }
}
