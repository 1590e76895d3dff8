//! A compliance inside a body (a motor's rotor on a soft shaft to its cage, a coupling's rubber
//! element): the body splits in two with a spring between them.

use serde::{Deserialize, Serialize};

use super::{EffectModel, EffectParameter, Element, Limit, Moves, Scale, Search, Shows, SizeContext};
use crate::drive::{Dimension, DriveModel, Dynamics, Effect};
use crate::error::{PlantError, Result};
use crate::line::{Coupling, LineBody, MAX_BODIES, MAX_COUPLINGS};

/// A compliance inside body `body`: the body splits into the part its couplings join (its
/// drag stays there), of inertia (1 − `motor_share`)·J, and a motor part of `motor_share`·J
/// that its inputs drive and its friction brakes (a machine's rotor), joined by a spring of
/// `stiffness` with the body's own stiffness-proportional damping, d = k·D_bb/K_bb — the
/// generic damping of the paper's section 4.3, D_bb and K_bb the body's diagonal entries of
/// the line's damping and stiffness matrices: an undamped internal mode would be a resonance
/// no measurement shows — unless `damping` gives it. The total inertia stays the declared one,
/// and the declared couplings' stiffness now acts in series with the spring
/// ([`Moves::SeriesSpring`]).
///
/// The split is structure, not a slot of the right-hand side: [`DriveModel::resolved`] writes
/// it into the line (the motor part appended as body `<body>_motor`, the spring as coupling
/// `<body>_compliance` on φ_motor − φ_body), so the dynamics, the FMU's states (the spring's
/// twist), the controller and the modal analysis see two bodies and a coupling.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Compliance {
    /// The body.
    pub body: usize,
    /// Stiffness of the spring between the motor part and the rest, N/m (Nm/rad).
    pub stiffness: f64,
    /// The motor part's share of the body's inertia, between 0 and 1 (default 0.5).
    #[serde(default = "half")]
    pub motor_share: f64,
    /// The spring's damping, N s/m (Nm s/rad); `None`: k·D_bb/K_bb.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
}

fn half() -> f64 {
    0.5
}

impl EffectModel for Compliance {
    const NAME: &'static str = "compliance";
    const PARAMETERS: &'static [EffectParameter] = &[
        EffectParameter {
            name: "compliance_stiffness",
            key: "compliance_stiffness",
            dimension: Dimension::Stiffness,
            what: "stiffness of a compliance",
        },
        EffectParameter {
            name: "compliance_motor_share",
            key: "compliance_motor_share",
            dimension: Dimension::Ratio,
            what: "share of the inertia on the driven side of the compliance",
        },
    ];
    const MOVES: Moves = Moves::SeriesSpring;
    const STRUCTURAL: bool = true;

    const PREDICTION: &'static str = "in the prediction: the line's bodies and couplings hold it";

    /// Anywhere: from a tenth to ten times the stiffness the body's couplings give it (K_bb),
    /// 9 starts; beyond a hundred times it the spring is rigid to any record.
    const SEARCH: Search = Search {
        shows: Shows::Always,
        scale: Scale::BodyStiffness,
        grid: (0.1, 10.0, 9),
        rough: false,
        limit: Limit::TimesScale(100.0),
        floor: 0.0,
        offset_where_one_way: false,
    };

    fn element(&self) -> Element {
        Element::Body(self.body)
    }
    fn at_index(self, body: usize) -> Self {
        Compliance { body, ..self }
    }
    fn values(&self) -> Vec<f64> {
        vec![self.stiffness, self.motor_share]
    }
    fn set_values(&mut self, v: &[f64]) {
        (self.stiffness, self.motor_share) = (v[0], v[1]);
    }
    fn of_size(self, stiffness: f64, _: &SizeContext) -> Self {
        Compliance { stiffness, ..self }
    }
    /// Nothing: [`DriveModel::resolved`] has made it structure before the dynamics are built.
    fn enter(&self, _: &mut Dynamics) {}

    /// Splits the body (see [`Compliance`]); the motor part is the last body, the spring the
    /// last coupling.
    fn write_into_line(&self, m: &mut DriveModel) -> Result<()> {
        let (b, f) = (self.body, self.motor_share);
        // the spring's name from the body's signal label (`phi_<label>`, `T_<label>_compliance`)
        let label = Element::Body(b).label(m);
        let line = &mut m.line;
        let name = line.bodies.get(b).map(|body| body.name.clone()).ok_or_else(|| {
            PlantError::Invalid(format!("a compliance at body {} of a line of {}", b + 1, line.bodies.len()))
        })?;
        if !(f > 0.0 && f < 1.0) {
            return Err(PlantError::Invalid(format!(
                "the compliance at {name}: motor_share {f}: expected a share of its inertia between 0 and 1"
            )));
        }
        let n = line.bodies.len();
        if n + 1 > MAX_BODIES || line.couplings.len() + 1 > MAX_COUPLINGS {
            return Err(PlantError::Invalid(format!(
                "the compliance at {name} makes the line longer than {MAX_BODIES} bodies or {MAX_COUPLINGS} couplings"
            )));
        }
        let damping = match self.damping {
            Some(d) if d.is_finite() && d >= 0.0 => d,
            Some(d) => {
                return Err(PlantError::Invalid(format!(
                    "the compliance at {name}: damping {d}: expected a finite value of at least 0"
                )))
            }
            None => match line.diagonal(b) {
                (k_bb, d_bb) if k_bb > 0.0 => self.stiffness * d_bb / k_bb,
                _ => 0.0,
            },
        };
        let j = line.bodies[b].inertia;
        line.bodies[b].inertia = (1.0 - f) * j;
        line.bodies.push(LineBody { name: format!("{name}_motor"), inertia: f * j, drag: 0.0 });
        for c in &mut line.couplings {
            if let Some(e) = &mut c.elongation {
                e.push(0.0);
            }
        }
        let mut e = vec![0.0; n + 1];
        (e[b], e[n]) = (-1.0, 1.0);
        line.couplings.push(Coupling {
            name: Some(format!("{label}_compliance")),
            elongation: Some(e),
            ..Coupling::new(self.stiffness, damping, 1.0)
        });
        // the motor part is what the inputs drive and the friction brakes
        for input in &mut m.inputs {
            if *input == b {
                *input = n;
            }
        }
        for other in &mut m.effects {
            if let Effect::CoulombFriction(friction) = other {
                if friction.body == b {
                    friction.body = n;
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drive::CoulombFriction;
    use crate::line::{Domain, Line};

    /// A motor driving a load through a shaft of stiffness `k1` (damping `beta`·k1).
    fn motor_load(jm: f64, jl: f64, k1: f64, beta: f64, effects: Vec<Effect>) -> DriveModel {
        DriveModel {
            line: Line {
                domain: Domain::Rotational,
                bodies: vec![
                    LineBody { name: "motor".into(), inertia: jm, drag: 1e-3 },
                    LineBody { name: "load".into(), inertia: jl, drag: 2e-3 },
                ],
                couplings: vec![Coupling::new(k1, beta * k1, 1.0)],
            },
            inputs: vec![0, 1],
            effects,
        }
    }

    /// The motor split by a compliance of stiffness k2 is the free–free three-mass chain
    /// J_a = f J_m —k2— J_b = (1 − f) J_m —k1— J_c = J_l, whose squared natural frequencies
    /// solve ω⁴ − ω² (k2 (1/J_a + 1/J_b) + k1 (1/J_b + 1/J_c)) + k1 k2 (J_a + J_b + J_c)/(J_a J_b
    /// J_c) = 0 (the textbook characteristic polynomial of the chain). The linearisation's
    /// eigenvalues (undamped) equal them to 1e-9 (round-off of an eigen-solution of a 6×6 A).
    #[test]
    fn a_compliance_makes_the_three_mass_chain() {
        let (jm, jl, k1, k2, f) = (0.02, 0.5, 3000.0, 900.0, 0.3);
        let split = Compliance { body: 0, stiffness: k2, motor_share: f, damping: None };
        let m = motor_load(jm, jl, k1, 0.0, vec![split.into()]);
        let mut m = m.resolved().unwrap().into_owned();
        for b in &mut m.line.bodies {
            b.drag = 0.0;
        }
        let (ja, jb, jc) = (f * jm, (1.0 - f) * jm, jl);
        let p = k2 * (1.0 / ja + 1.0 / jb) + k1 * (1.0 / jb + 1.0 / jc);
        let q = k1 * k2 * (ja + jb + jc) / (ja * jb * jc);
        let disc = (p * p - 4.0 * q).sqrt();
        let mut expected = [((p - disc) / 2.0).sqrt(), ((p + disc) / 2.0).sqrt()];
        expected.sort_by(f64::total_cmp);
        let (a, _) = m.linearisation().unwrap();
        let mut omega: Vec<f64> = a.complex_eigenvalues().iter().map(|l| l.im).filter(|w| *w > 1e-3).collect();
        omega.sort_by(f64::total_cmp);
        assert_eq!(omega.len(), 2, "{omega:?}");
        for (w, e) in omega.iter().zip(expected) {
            assert!((w - e).abs() <= 1e-9 * e, "{w} rad/s against {e}");
        }
    }

    /// The split keeps the total inertia, moves the inputs and the friction of the body to the
    /// motor part (the last body), keeps the other body's, gives the spring the shaft's own
    /// damping ratio d/c (a stiffness-proportional line stays one), twists it as φ_motor −
    /// φ_body, and a share outside (0, 1) is refused by name.
    #[test]
    fn the_split_keeps_the_inertia_and_moves_what_drives_the_motor() {
        let (jm, beta) = (0.02, 4e-4);
        let friction = |body| Effect::from(CoulombFriction { body, friction: 0.1, smoothing_speed: 0.05 });
        let split = Compliance { body: 0, stiffness: 700.0, motor_share: 0.25, damping: None };
        let m = motor_load(jm, 0.5, 3000.0, beta, vec![friction(0), split.into(), friction(1)]);
        let r = m.resolved().unwrap();
        assert_eq!(r.line.bodies.len(), 3);
        assert_eq!(r.line.bodies[2].name, "motor_motor");
        assert_eq!(r.line.bodies[0].inertia + r.line.bodies[2].inertia, jm);
        assert_eq!(r.line.bodies[2].inertia, 0.25 * jm);
        assert_eq!(r.inputs, [2, 1]);
        let bodies: Vec<usize> = r
            .effects
            .iter()
            .map(|e| match e {
                Effect::CoulombFriction(c) => c.body,
                other => panic!("{} left in the effects", other.name()),
            })
            .collect();
        assert_eq!(bodies, [2, 1]);
        let spring = r.line.couplings.last().unwrap();
        assert_eq!(spring.name.as_deref(), Some("motor_compliance"));
        assert_eq!(spring.elongation.as_deref(), Some(&[-1.0, 0.0, 1.0][..]));
        assert!((spring.damping / spring.stiffness - beta).abs() <= 1e-15, "{}", spring.damping);
        // the states: three angles, three speeds
        assert_eq!(Dynamics::new(&m).unwrap().nstates(), 6);
        // a record starting in motion starts the motor part at its body's speed, also behind a
        // gear stage (4:1 to the load, the compliance in the load)
        let mut geared = motor_load(jm, 0.5, 3000.0, beta, vec![Compliance { body: 1, ..split }.into()]);
        geared.line.couplings[0].ratio = 4.0;
        let x = Dynamics::new(&geared).unwrap().initial_state(10.0, &[0.0, 0.0]);
        assert_eq!(&x[3..6], &[10.0, 2.5, 2.5]);
        // a damping given is the spring's
        let given = motor_load(jm, 0.5, 3000.0, beta, vec![Compliance { damping: Some(0.7), ..split }.into()]);
        assert_eq!(given.resolved().unwrap().line.couplings[1].damping, 0.7);
        for share in [0.0, 1.0, 1.5] {
            let bad = motor_load(jm, 0.5, 3000.0, beta, vec![Compliance { motor_share: share, ..split }.into()]);
            let e = bad.resolved().unwrap_err().to_string();
            assert!(e.contains("motor_share"), "{e}");
        }
        for d in [-1.0, f64::NAN] {
            let bad = motor_load(jm, 0.5, 3000.0, beta, vec![Compliance { damping: Some(d), ..split }.into()]);
            let e = bad.resolved().unwrap_err().to_string();
            assert!(e.contains("damping"), "{e}");
        }
    }
}
