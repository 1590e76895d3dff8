//! Coulomb friction at a body (bearings, seals, brushes), smoothed through zero speed.

use serde::{Deserialize, Serialize};

use super::{EffectModel, EffectParameter, Element, Limit, Scale, Search, Shows, SizeContext};
use crate::drive::{Dimension, Dynamics};

/// Coulomb friction at a body: F = friction · q̇/√(q̇² + smoothing_speed²) against its motion
/// (71 % of the friction at the smoothing speed, 97 % at 4×, 99.5 % at 10×).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoulombFriction {
    /// The body.
    pub body: usize,
    /// Friction force (torque), N (Nm).
    pub friction: f64,
    /// Smoothing speed v_s, m/s (rad/s).
    pub smoothing_speed: f64,
}

impl EffectModel for CoulombFriction {
    const NAME: &'static str = "coulomb_friction";
    const PARAMETERS: &'static [EffectParameter] = &[
        EffectParameter { name: "friction", key: "friction", dimension: Dimension::Force, what: "Coulomb friction" },
        EffectParameter {
            name: "friction_smoothing_speed",
            key: "smoothing_speed",
            dimension: Dimension::Speed,
            what: "speed of the friction's smoothing F v/sqrt(v^2 + v_s^2)",
        },
    ];
    const NONLINEAR: bool = true;

    const PREDICTION: &'static str = "NOT in the prediction: that is the linearisation without friction, and the filter's input disturbances absorb it";

    /// Where a body's speed comes near zero, from 1 % to the input's whole force (8 starts).
    const SEARCH: Search = Search {
        shows: Shows::SpeedNearZero,
        scale: Scale::BodyForce,
        grid: (0.01, 1.0, 8),
        rough: false,
        limit: Limit::Unbounded,
        floor: 0.0,
        offset_where_one_way: true,
    };

    fn element(&self) -> Element {
        Element::Body(self.body)
    }
    fn at_index(self, body: usize) -> Self {
        CoulombFriction { body, ..self }
    }
    fn values(&self) -> Vec<f64> {
        vec![self.friction, self.smoothing_speed]
    }
    fn set_values(&mut self, v: &[f64]) {
        (self.friction, self.smoothing_speed) = (v[0], v[1]);
    }
    /// Smoothed no sharper than the mechanics' fastest rate: the friction's slope F_c/(v_s J)
    /// must not set the integration step.
    fn of_size(self, friction: f64, c: &SizeContext) -> Self {
        let smoothing_speed = c.smoothing_speed.max(friction / (c.inertia * c.fastest_rate));
        CoulombFriction { friction, smoothing_speed, ..self }
    }
    fn enter(&self, d: &mut Dynamics) {
        d.friction[self.body] = (self.friction, self.smoothing_speed);
    }
    /// Left out: the linearisation is the motion clear of the friction's band.
    fn linearise(&self, d: &mut Dynamics, _contact: bool) {
        d.friction[self.body] = (0.0, 1.0);
        d.friction_band[self.body] = 0.0;
    }
}
