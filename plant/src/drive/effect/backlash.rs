//! Play in a coupling (a gear mesh, a spline, a side shaft).

use serde::{Deserialize, Serialize};

use super::{EffectModel, EffectParameter, Element, Limit, Scale, Search, Shows, SizeContext};
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

    const PREDICTION: &'static str = "NOT in the prediction: it stays linear with the play in contact";

    /// Where the coupling's force changes sign: a profile over five decades of the declared
    /// model's elastic twist (a play can be far wider than the twist the spring takes), 10 %
    /// apart. A coupling that rattles in its play has an error over the play with a narrow
    /// notch at the truth (±0.3 % wide for a shaft at 4 % of critical damping, measured), whose
    /// shoulder a 10 % grid meets and a 21 % grid misses (measured on
    /// `tests/diagnose_drive.rs`); up to 3000 times the twist.
    const SEARCH: Search = Search {
        shows: Shows::ForceChangesSign,
        scale: Scale::CouplingTwist,
        grid: (0.01, 1000.0, 121),
        rough: true,
        limit: Limit::TimesScale(3000.0),
        floor: 0.0,
        offset_where_one_way: false,
    };

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
    fn of_size(self, backlash: f64, _: &SizeContext) -> Self {
        Backlash { backlash, ..self }
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
