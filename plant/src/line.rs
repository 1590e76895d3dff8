//! Bodies in a line, each coupled to the next by a spring-damper, optionally through a gear
//! stage (`../shared/DATA.md`, `drive_test`): a motor driving a load through shafts and gears,
//! a linear axis, a shaft line with disks. Rotational or translational; one [`MechanicalModel`].
//!
//! Coupling i joins body i and body i+1 with ratio r (speed of body i = r · speed of body i+1):
//! its elongation (twist) is q_i / r − q_{i+1}, its force T = c·twist + d·d(twist)/dt drives
//! body i+1 forward and loads body i with T / r. As a spring of [`MechanicalModel`] that is the
//! elongation vector e with e_i = 1/r and e_{i+1} = −1 (potential ½ c (eᵀq)²), so a gear stage
//! reflects the load side's stiffness to the motor side by 1/r², the textbook reduction.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::error::{non_negative, positive, PlantError, Result};
use crate::mechanical::{MechanicalModel, Output, Spring};
use crate::statespace::StateSpace;

/// What a measured output of a line is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// Angle (rad) or position (m) of a body.
    Position,
    /// Speed of a body (rad/s or m/s).
    Speed,
    /// Force (Nm or N) a coupling transmits, T = c·twist + d·d(twist)/dt.
    CouplingForce,
}

/// Rotational (kg m², Nm/rad, rad) or translational (kg, N/m, m).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Domain {
    /// Angles, torques, inertias.
    Rotational,
    /// Positions, forces, masses.
    Translational,
}

impl Domain {
    /// SI units: (inertia, stiffness, damping, force, coordinate, speed).
    pub fn units(self) -> [&'static str; 6] {
        match self {
            Domain::Rotational => ["kg m^2", "Nm/rad", "Nm s/rad", "Nm", "rad", "rad/s"],
            Domain::Translational => ["kg", "N/m", "N s/m", "N", "m", "m/s"],
        }
    }
}

/// One body of the line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LineBody {
    /// Name (unique in the line).
    pub name: String,
    /// Inertia (kg m²) or mass (kg).
    pub inertia: f64,
    /// Viscous friction to ground (Nm s/rad or N s/m).
    #[serde(default)]
    pub drag: f64,
}

/// Coupling i: by default between body i and body i+1 (through a gear stage of `ratio`); with
/// an `elongation`, a spring-damper on any linear combination of the bodies' coordinates — an
/// open differential's side shafts act on 2φ_cage − φ_left − φ_right (eq. (A1)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Coupling {
    /// Stiffness (Nm/rad or N/m).
    pub stiffness: f64,
    /// Damping (Nm s/rad or N s/m).
    #[serde(default)]
    pub damping: f64,
    /// Gear ratio: speed of body i = ratio · speed of body i+1 (1: no gear stage; must be 1
    /// with an `elongation`, which carries any ratio itself).
    #[serde(default = "one")]
    pub ratio: f64,
    /// Name, the stem of its force's signal name (`T_<name>`/`F_<name>`); default `coupling_<i>`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The twist (elongation) as eᵀq, one coefficient per body (rad per rad, m per m); default
    /// q_i / ratio − q_{i+1}. Its force T acts on body j as −e_j T.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub elongation: Option<Vec<f64>>,
    /// The bodies it joins, by name, as engineers draw a gearbox: two bodies — a shaft, or a
    /// gear mesh of `ratio` (speed of the first = ratio · speed of the second; twist
    /// q_first / ratio − q_second, the mesh's stiffness at the second) — or one, a spring and
    /// damper to ground (twist q_body). [`Line::resolved`] turns it into the `elongation`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub between: Option<Vec<String>>,
}

impl Coupling {
    /// A coupling between neighbours: stiffness, damping and gear ratio, unnamed.
    pub fn new(stiffness: f64, damping: f64, ratio: f64) -> Coupling {
        Coupling { stiffness, damping, ratio, name: None, elongation: None, between: None }
    }

    /// The twist's coefficients of coupling `i` as (body, coefficient), the zeros left out.
    pub fn terms(&self, i: usize) -> Vec<(usize, f64)> {
        match &self.elongation {
            Some(e) => e.iter().enumerate().filter(|(_, c)| **c != 0.0).map(|(j, c)| (j, *c)).collect(),
            None => vec![(i, 1.0 / self.ratio), (i + 1, -1.0)],
        }
    }
}

fn one() -> f64 {
    1.0
}

/// A line of bodies and the couplings between neighbours (`couplings.len() == bodies.len() − 1`
/// when none has an explicit elongation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Line {
    /// Rotational or translational.
    pub domain: Domain,
    /// The bodies in line order.
    pub bodies: Vec<LineBody>,
    /// Coupling i joins body i and i+1.
    pub couplings: Vec<Coupling>,
}

/// Most bodies a line may have: four times a real-sized shaft line (8 bodies, two gear stages);
/// the work of a diagnosis or an MPC grows with a high power of the count, and a model far
/// larger than this would take hours or exhaust memory on a rig's PC.
pub const MAX_BODIES: usize = 32;
/// Most couplings a line may have (twice [`MAX_BODIES`]: branched gearboxes, parallel paths).
pub const MAX_COUPLINGS: usize = 2 * MAX_BODIES;

impl Line {
    /// Checks every value; errors name the key as a bundle spells it (`model.bodies[2].inertia`,
    /// 1-based like the bundle's positions).
    pub fn validate(&self) -> Result<()> {
        let u = self.domain.units();
        if self.bodies.is_empty() {
            return Err(PlantError::Invalid("`model.bodies` is empty: a line needs at least one body".into()));
        }
        if self.bodies.len() > MAX_BODIES || self.couplings.len() > MAX_COUPLINGS {
            return Err(PlantError::Invalid(format!(
                "`model.bodies` has {} entries and `model.couplings` {}: rigtwin takes lines of at most {MAX_BODIES} bodies and {MAX_COUPLINGS} couplings (a diagnosis or MPC of a larger model would not finish on this class of machine): reduce the line to its lowest modes first",
                self.bodies.len(),
                self.couplings.len()
            )));
        }
        let general = self.couplings.iter().any(|c| c.elongation.is_some());
        if !general && self.couplings.len() + 1 != self.bodies.len() {
            return Err(PlantError::Invalid(format!(
                "`model.couplings` has {} entries for {} bodies: coupling i joins body i and i+1, so {} are expected",
                self.couplings.len(),
                self.bodies.len(),
                self.bodies.len() - 1
            )));
        }
        for (i, b) in self.bodies.iter().enumerate() {
            if b.name.trim().is_empty() {
                return Err(PlantError::Invalid(format!("`model.bodies[{}].name` is empty", i + 1)));
            }
            if self.bodies[..i].iter().any(|o| o.name == b.name) {
                return Err(PlantError::Invalid(format!(
                    "`model.bodies[{}].name` = \"{}\" is used twice: names must be unique",
                    i + 1,
                    b.name
                )));
            }
            positive(|| format!("model.bodies[{}].inertia", i + 1), b.inertia, u[0])?;
            non_negative(|| format!("model.bodies[{}].drag", i + 1), b.drag, u[2])?;
        }
        for (i, c) in self.couplings.iter().enumerate() {
            if c.between.is_some() {
                return Err(PlantError::Invalid(format!(
                    "`model.couplings[{}].between` is not resolved (`Line::resolved`)",
                    i + 1
                )));
            }
            positive(|| format!("model.couplings[{}].stiffness", i + 1), c.stiffness, u[1])?;
            non_negative(|| format!("model.couplings[{}].damping", i + 1), c.damping, u[2])?;
            positive(
                || format!("model.couplings[{}].ratio", i + 1),
                c.ratio,
                "(speed of body i per speed of body i+1)",
            )?;
            let key = || format!("model.couplings[{}]", i + 1);
            match &c.elongation {
                None if i + 1 >= self.bodies.len() => {
                    return Err(PlantError::Invalid(format!(
                        "`{}` joins body {} and {}, but the line has {} bodies (give its `elongation` to couple other bodies)",
                        key(),
                        i + 1,
                        i + 2,
                        self.bodies.len()
                    )));
                }
                None => {}
                Some(e) => {
                    if e.len() != self.bodies.len() {
                        return Err(PlantError::Invalid(format!(
                            "`{}.elongation` has {} coefficients: expected one per body, {}",
                            key(),
                            e.len(),
                            self.bodies.len()
                        )));
                    }
                    if !e.iter().all(|v| v.is_finite()) || e.iter().all(|&v| v == 0.0) {
                        return Err(PlantError::Invalid(format!(
                            "`{}.elongation` = {e:?}: expected finite coefficients, not all zero",
                            key()
                        )));
                    }
                    if c.ratio != 1.0 {
                        return Err(PlantError::Invalid(format!(
                            "`{}.ratio` = {}: a coupling with an `elongation` carries its ratios in the coefficients; \
                             expected 1 (or no ratio)",
                            key(),
                            c.ratio
                        )));
                    }
                }
            }
            if let Some(name) = &c.name {
                let ok = !name.is_empty() && name.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '_');
                if !ok {
                    return Err(PlantError::Invalid(format!(
                        "`{}.name` = \"{name}\": expected letters, digits and `_` (it names a signal)",
                        key()
                    )));
                }
            }
        }
        Ok(())
    }

    /// The line with every coupling given by the bodies it joins (`between`) written as its
    /// elongation (ratio 1); errors name the coupling's key.
    pub fn resolved(mut self) -> Result<Line> {
        let n = self.bodies.len();
        for i in 0..self.couplings.len() {
            let Some(names) = self.couplings[i].between.take() else { continue };
            let key = format!("model.couplings[{}]", i + 1);
            let c = &mut self.couplings[i];
            if c.elongation.is_some() {
                return Err(PlantError::Invalid(format!("`{key}` has both `between` and `elongation`: give one")));
            }
            let mut at = Vec::with_capacity(names.len());
            for name in &names {
                let b = self.bodies.iter().position(|b| &b.name == name).ok_or_else(|| {
                    PlantError::Invalid(format!("`{key}.between` names `{name}`, which is no body of the line"))
                })?;
                at.push(b);
            }
            let mut e = vec![0.0; n];
            match at[..] {
                [a] => {
                    if c.ratio != 1.0 {
                        return Err(PlantError::Invalid(format!(
                            "`{key}.ratio` = {}: a spring to ground has no ratio",
                            c.ratio
                        )));
                    }
                    e[a] = 1.0;
                }
                [a, b] if a != b => {
                    positive(|| format!("{key}.ratio"), c.ratio, "(speed of the first body per speed of the second)")?;
                    e[a] = 1.0 / c.ratio;
                    e[b] = -1.0;
                }
                _ => {
                    return Err(PlantError::Invalid(format!(
                        "`{key}.between` = {names:?}: expected two different bodies (a shaft or a gear mesh) or one (a spring to ground)"
                    )))
                }
            }
            c.elongation = Some(e);
            c.ratio = 1.0;
        }
        self.validate()?;
        Ok(self)
    }

    /// 0-based position of the body named `name`.
    pub fn body(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }

    /// Body `b`'s diagonal entries of the stiffness and damping matrices, (K_bb, D_bb) =
    /// (Σ c e_b², Σ d e_b²) over the couplings' twist coefficients e: the stiffness and damping
    /// that hold it when every other body stands still.
    pub fn diagonal(&self, b: usize) -> (f64, f64) {
        let (mut k, mut d) = (0.0, 0.0);
        for (i, c) in self.couplings.iter().enumerate() {
            for (j, e) in c.terms(i) {
                if j == b {
                    k += c.stiffness * e * e;
                    d += c.damping * e * e;
                }
            }
        }
        (k, d)
    }

    /// The line as a mechanical model: diagonal inertia, one spring per coupling with its
    /// elongation (q_i / r − q_{i+1} between neighbours), drag on each body.
    pub fn model(&self) -> Result<MechanicalModel> {
        self.validate()?;
        let n = self.bodies.len();
        let springs = self
            .couplings
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let mut e = DVector::zeros(n);
                for (j, v) in c.terms(i) {
                    e[j] = v;
                }
                Spring {
                    name: c.name.as_ref().map_or_else(|| format!("coupling {}", i + 1), |s| s.replace('_', " ")),
                    elongation: e,
                    stiffness: c.stiffness,
                    damping: c.damping,
                }
            })
            .collect();
        Ok(MechanicalModel {
            dof_names: self.bodies.iter().map(|b| b.name.replace(' ', "_")).collect(),
            inertia: DMatrix::from_diagonal(&DVector::from_iterator(n, self.bodies.iter().map(|b| b.inertia))),
            springs,
            drag: DVector::from_iterator(n, self.bodies.iter().map(|b| b.drag)),
            layout: None,
        })
    }
}

impl Line {
    /// The state space x = [q; q̇] with the forces on the bodies `inputs` (0-based) as inputs and
    /// the `outputs` (quantity, 0-based body or coupling) as outputs.
    pub fn state_space(&self, inputs: &[usize], outputs: &[(Quantity, usize)]) -> Result<StateSpace> {
        let n = self.bodies.len();
        let full = self.model()?.state_space(&[Output::Angles, Output::Speeds, Output::SpringTorques])?;
        let row = |&(q, i): &(Quantity, usize)| -> Result<usize> {
            let (offset, count) = match q {
                Quantity::Position => (0, n),
                Quantity::Speed => (n, n),
                Quantity::CouplingForce => (2 * n, self.couplings.len()),
            };
            if i >= count {
                return Err(PlantError::Invalid(format!("output {q:?} of position {} is outside the line", i + 1)));
            }
            Ok(offset + i)
        };
        let rows = outputs.iter().map(row).collect::<Result<Vec<usize>>>()?;
        if let Some(&i) = inputs.iter().find(|&&i| i >= n) {
            return Err(PlantError::Invalid(format!("input on body {} is outside the line", i + 1)));
        }
        Ok(StateSpace {
            b: full.b.select_columns(inputs),
            c: full.c.select_rows(&rows),
            d: DMatrix::zeros(rows.len(), inputs.len()),
            input_names: inputs.iter().map(|&i| full.input_names[i].clone()).collect(),
            output_names: rows.iter().map(|&r| full.output_names[r].clone()).collect(),
            a: full.a,
            state_names: full.state_names,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn body(name: &str, inertia: f64) -> LineBody {
        LineBody { name: name.into(), inertia, drag: 0.0 }
    }

    /// Motor – shaft – hub – 4:1 gear – load: the frequencies equal those of the same line with
    /// the gear reduced by hand to the motor side (load inertia and stiffness over r²), written
    /// as a plain spring chain: J q̈ + K q = 0 with K tridiagonal.
    #[test]
    fn a_gear_stage_reflects_by_the_square_of_its_ratio() {
        let (jm, jh, jl, c1, c2, r) = (0.002, 0.0004, 0.05, 800.0, 20000.0, 4.0);
        let line = Line {
            domain: Domain::Rotational,
            bodies: vec![body("motor", jm), body("hub", jh), body("load", jl)],
            couplings: vec![Coupling::new(c1, 0.0, 1.0), Coupling::new(c2, 0.0, r)],
        };
        let f = line.model().unwrap().modes().unwrap().frequencies_hz;
        // by hand: the load seen from the hub side in hub radians q_l' = r q_l: kinetic energy
        // ½ jl (q̇_l'/r)² gives J' = jl / r², potential ½ c2 ((q_h − q_l')/r)² gives c' = c2 / r²
        let (jl2, c22) = (jl / (r * r), c2 / (r * r));
        let j = DMatrix::from_diagonal(&DVector::from_vec(vec![jm, jh, jl2]));
        let k = DMatrix::from_row_slice(3, 3, &[c1, -c1, 0.0, -c1, c1 + c22, -c22, 0.0, -c22, c22]);
        let jinv_sqrt = j.map(|v| if v > 0.0 { 1.0 / v.sqrt() } else { 0.0 });
        let mut w2: Vec<f64> = (&jinv_sqrt * k * &jinv_sqrt).symmetric_eigenvalues().iter().copied().collect();
        w2.sort_by(|a, b| a.total_cmp(b));
        let by_hand: Vec<f64> = w2.iter().map(|v| v.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)).collect();
        assert_eq!(f.len(), 3);
        assert!(f[0].abs() < 1e-6, "rigid body: {f:?}");
        for (a, b) in f.iter().zip(&by_hand).skip(1) {
            assert_relative_eq!(*a, *b, max_relative = 1e-9);
        }
        // a single mass on its own: no coupling, one rigid-body mode
        let one = Line { domain: Domain::Translational, bodies: vec![body("carriage", 20.0)], couplings: vec![] };
        assert_eq!(one.model().unwrap().dofs(), 1);
    }

    /// A single mass m with drag d under a force: the speed's transfer function 1/(m s + d),
    /// so after a unit force step the speed is (1 − e^(−d t/m))/d.
    #[test]
    fn a_single_mass_state_space_is_the_first_order_law() {
        let line = Line {
            domain: Domain::Translational,
            bodies: vec![LineBody { name: "carriage".into(), inertia: 20.0, drag: 60.0 }],
            couplings: vec![],
        };
        let ss = line.state_space(&[0], &[(Quantity::Speed, 0), (Quantity::Position, 0)]).unwrap();
        let u = DMatrix::from_element(1001, 1, 1.0);
        let y = ss.lsim(&u, 1e-3, &DVector::zeros(2)).unwrap();
        let t = 1.0;
        assert_relative_eq!(y[(1000, 0)], (1.0 - (-60.0 * t / 20.0f64).exp()) / 60.0, max_relative = 1e-9);
        assert!(line.state_space(&[0], &[(Quantity::CouplingForce, 0)]).is_err(), "no coupling to measure");
    }

    #[test]
    fn bad_lines_name_the_key() {
        let mut line = Line {
            domain: Domain::Rotational,
            bodies: vec![body("a", 1.0), body("b", 1.0)],
            couplings: vec![Coupling::new(1.0, 0.0, 1.0)],
        };
        line.couplings[0].ratio = 0.0;
        assert!(line.validate().unwrap_err().to_string().contains("model.couplings[1].ratio"));
        line.couplings[0].ratio = 1.0;
        line.bodies[1].inertia = -1.0;
        assert!(line.validate().unwrap_err().to_string().contains("model.bodies[2].inertia"));
        line.bodies[1] = body("a", 1.0);
        assert!(line.validate().unwrap_err().to_string().contains("used twice"));
        line.couplings.clear();
        assert!(line.validate().unwrap_err().to_string().contains("1 are expected"));
    }

    /// A coupling with an elongation: one finite coefficient per body, not all zero, no ratio,
    /// a name that can name a signal; each error names the key.
    /// A coupling by the bodies it joins is the elongation q_a / r − q_b (a spring to ground:
    /// q_a); a wrong name, both forms, three bodies or a ratio on a ground spring are refused by
    /// key.
    #[test]
    fn couplings_between_named_bodies() {
        let between = |names: &[&str], ratio: f64| Coupling {
            between: Some(names.iter().map(|n| n.to_string()).collect()),
            ..Coupling::new(100.0, 0.0, ratio)
        };
        let line = |couplings: Vec<Coupling>| Line {
            domain: Domain::Rotational,
            bodies: vec![body("pinion", 1.0), body("wheel", 1.0), body("load", 1.0)],
            couplings,
        };
        let ok = line(vec![between(&["pinion", "wheel"], 4.0), between(&["load"], 1.0)]).resolved().unwrap();
        assert_eq!(ok.couplings[0].elongation, Some(vec![0.25, -1.0, 0.0]));
        assert_eq!(ok.couplings[0].ratio, 1.0);
        assert_eq!(ok.couplings[1].elongation, Some(vec![0.0, 0.0, 1.0]));
        let err = |c: Coupling| line(vec![c]).resolved().unwrap_err().to_string();
        assert!(err(between(&["pinion", "gear"], 2.0)).contains("`gear`"));
        assert!(err(between(&["pinion", "wheel", "load"], 1.0)).contains("model.couplings[1].between"));
        assert!(err(between(&["wheel", "wheel"], 1.0)).contains("two different bodies"));
        assert!(err(between(&["load"], 3.0)).contains("model.couplings[1].ratio"));
        assert!(err(Coupling { elongation: Some(vec![1.0, 0.0, 0.0]), ..between(&["load"], 1.0) }).contains("both"));
        // unresolved, the line is refused rather than read as neighbours
        assert!(line(vec![between(&["pinion", "wheel"], 1.0)]).validate().is_err());
    }

    #[test]
    fn bad_elongations_name_the_key() {
        let mut line = Line {
            domain: Domain::Rotational,
            bodies: vec![body("a", 1.0), body("b", 1.0), body("c", 1.0)],
            couplings: vec![
                Coupling { elongation: Some(vec![-1.0, 2.0, -1.0]), ..Coupling::new(1.0, 0.0, 1.0) },
                Coupling::new(1.0, 0.0, 1.0),
            ],
        };
        assert!(line.validate().is_ok());
        let err = |line: &Line| line.validate().unwrap_err().to_string();
        line.couplings[0].elongation = Some(vec![1.0, -1.0]);
        assert!(err(&line).contains("model.couplings[1].elongation") && err(&line).contains("3"), "{}", err(&line));
        line.couplings[0].elongation = Some(vec![0.0, f64::NAN, 1.0]);
        assert!(err(&line).contains("finite"), "{}", err(&line));
        line.couplings[0].elongation = Some(vec![0.0; 3]);
        assert!(err(&line).contains("not all zero"), "{}", err(&line));
        line.couplings[0].elongation = Some(vec![-1.0, 2.0, -1.0]);
        line.couplings[0].ratio = 4.0;
        assert!(err(&line).contains("model.couplings[1].ratio"), "{}", err(&line));
        line.couplings[0].ratio = 1.0;
        line.couplings[0].name = Some("short shaft".into());
        assert!(err(&line).contains("model.couplings[1].name"), "{}", err(&line));
        // a coupling between neighbours past the last body
        line.couplings[0].name = None;
        line.couplings.push(Coupling::new(1.0, 0.0, 1.0));
        assert!(err(&line).contains("model.couplings[3]"), "{}", err(&line));
    }
}
