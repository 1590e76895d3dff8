//! Play in a coupling (a gear mesh, a spline, a side shaft).

use serde::{Deserialize, Serialize};

use super::{EffectModel, EffectParameter, Element};
use crate::drive::{Dimension, Dynamics};

/// Play in a coupling: no force while |twist| < backlash/2, the spring and damper act on the
/// twist beyond it (total play `backlash`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Backlash {
    /// The coupling.
    pub coupling: usize,
    /// Total play, m (rad) of the coupling's twist.
    pub backlash: f64,
}

impl EffectModel for Backlash {
    const NAME: &'static str = "backlash";
    const PARAMETERS: &'static [EffectParameter] =
        &[EffectParameter { name: "backlash", key: "backlash", dimension: Dimension::Coordinate, what: "total play" }];
    const NONLINEAR: bool = true;

    fn element(&self) -> Element {
        Element::Coupling(self.coupling)
    }
    fn at_index(self, coupling: usize) -> Self {
        Backlash { coupling, ..self }
    }
    fn values(&self) -> Vec<f64> {
        vec![self.backlash]
    }
    fn set_values(&mut self, v: &[f64]) {
        self.backlash = v[0];
    }
    fn enter(&self, d: &mut Dynamics) {
        d.couplings[self.coupling].half = 0.5 * self.backlash;
    }
    /// In contact: the coupling's spring and damper on the whole twist (the play's offset is
    /// [`Dynamics::play_offset`]); open: no force.
    fn linearise(&self, d: &mut Dynamics, contact: bool) {
        let s = &mut d.couplings[self.coupling];
        s.half = 0.0;
        if !contact {
            (s.c, s.d) = (0.0, 0.0);
        }
    }
}
