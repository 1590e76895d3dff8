//! Reduction of degrees of freedom after Rivin and Di (section 2.2, eqs. (7)–(12), Figure 5).
//!
//! The chain is cut into n type-A subsystems (one mass between its two springs, the springs
//! clamped) and n − 1 type-B subsystems (one spring between its two masses, free). The
//! subsystem with the highest natural frequency is the least relevant for the low modes and is
//! removed:
//! - type A at mass i (eq. (7)–(9)): J_i is shared by its neighbours in proportion to the spring
//!   that ties it to them, and the two springs become one series spring;
//! - type B at spring i (eqs. (10)–(12)): the two masses merge, and the compliance 1/c_Ti is
//!   shared by the neighbouring springs in inverse proportion to the masses.
//!
//! The sum of inertias is kept exactly; the series compliance is kept except for the stub shaft
//! left when a type-B step happens at an end of the chain, which is neglected as Dresig and
//! Fidlin suggest. Damping is not reduced (the paper neglects it, section 4.3): the result is
//! undamped.

use serde::Serialize;

use crate::chain::Chain;
use crate::error::{PlantError, Result};

/// Which subsystem a step removed, 0-based in the chain as it was before the step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "type")]
pub enum ReductionStep {
    /// Mass `index` distributed to its neighbours.
    A {
        /// Removed mass.
        index: usize,
        /// ω²_A of eq. (7), rad²/s².
        omega2: f64,
    },
    /// Masses `index` and `index + 1` merged.
    B {
        /// Removed spring (between mass index and index + 1).
        index: usize,
        /// ω²_B of eq. (7), rad²/s².
        omega2: f64,
    },
}

/// The reduced chain and the steps that produced it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Reduction {
    /// The chain with the requested number of masses.
    pub chain: Chain,
    /// Every step in order.
    pub steps: Vec<ReductionStep>,
}

/// Reduces `chain` to `masses` masses (at least 1).
pub fn reduce(chain: &Chain, masses: usize) -> Result<Reduction> {
    if masses == 0 || masses > chain.len() {
        return Err(PlantError::OutOfRange { field: "masses".into(), index: masses, min: 1, max: chain.len() });
    }
    let mut j = chain.inertias_kgm2.clone();
    let mut c = chain.stiffnesses_nm_per_rad.clone();
    let mut names = chain.names.clone();
    let mut origins = chain.origins.clone();
    let mut steps = Vec::new();
    while j.len() > masses {
        let step = highest_subsystem(&j, &c);
        match step {
            ReductionStep::A { index: i, .. } => {
                // c_T0 = c_T(n) = 0 at the ends (text below eq. (7))
                let cl = if i > 0 { c[i - 1] } else { 0.0 };
                let cr = if i + 1 < j.len() { c[i] } else { 0.0 };
                if i > 0 {
                    j[i - 1] += cl * j[i] / (cl + cr); // eq. (8)
                }
                if i + 1 < j.len() {
                    j[i + 1] += cr * j[i] / (cl + cr); // eq. (7)
                }
                if i > 0 && i + 1 < j.len() {
                    c[i - 1] = cl * cr / (cl + cr); // eq. (9)
                    c.remove(i);
                } else if i == 0 {
                    c.remove(0);
                } else {
                    c.remove(i - 1);
                }
                j.remove(i);
                names.remove(i);
                origins.remove(i);
            }
            ReductionStep::B { index: i, .. } => {
                let (ji, jk, ci) = (j[i], j[i + 1], c[i]);
                if i > 0 {
                    c[i - 1] = 1.0 / (1.0 / c[i - 1] + jk / ((ji + jk) * ci)); // eq. (11)
                }
                if i + 1 < c.len() {
                    c[i + 1] = 1.0 / (1.0 / c[i + 1] + ji / ((ji + jk) * ci)); // eq. (12)
                }
                j[i] = ji + jk; // eq. (10)
                if jk > ji {
                    names[i] = names[i + 1].clone();
                    origins[i] = origins[i + 1];
                }
                j.remove(i + 1);
                names.remove(i + 1);
                origins.remove(i + 1);
                c.remove(i);
            }
        }
        steps.push(step);
    }
    let mut reduced = Chain::new(names, j, c)?;
    reduced.origins = origins;
    Ok(Reduction { chain: reduced, steps })
}

/// The subsystem with the highest natural frequency (eq. (7)); ties go to the first found,
/// type A before type B.
fn highest_subsystem(j: &[f64], c: &[f64]) -> ReductionStep {
    let n = j.len();
    let mut best = ReductionStep::A { index: 0, omega2: f64::NEG_INFINITY };
    let mut best_w = f64::NEG_INFINITY;
    for i in 0..n {
        let cl = if i > 0 { c[i - 1] } else { 0.0 };
        let cr = if i + 1 < n { c[i] } else { 0.0 };
        let w = (cl + cr) / j[i];
        if w > best_w {
            best_w = w;
            best = ReductionStep::A { index: i, omega2: w };
        }
    }
    for i in 0..n - 1 {
        let w = c[i] * (j[i] + j[i + 1]) / (j[i] * j[i + 1]);
        if w > best_w {
            best_w = w;
            best = ReductionStep::B { index: i, omega2: w };
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn chain(j: &[f64], c: &[f64]) -> Chain {
        Chain::new((0..j.len()).map(|i| format!("m{i}")).collect(), j.to_vec(), c.to_vec()).unwrap()
    }

    #[test]
    fn light_middle_mass_is_shared_by_stiffness() {
        // A tiny mass between springs 100 and 300: type A; shares 1/4 left, 3/4 right; series 75.
        let r = reduce(&chain(&[1.0, 1e-6, 2.0], &[100.0, 300.0]), 2).unwrap();
        assert!(matches!(r.steps[0], ReductionStep::A { index: 1, .. }));
        assert_relative_eq!(r.chain.inertias_kgm2[0], 1.0 + 0.25e-6, max_relative = 1e-12);
        assert_relative_eq!(r.chain.inertias_kgm2[1], 2.0 + 0.75e-6, max_relative = 1e-12);
        assert_relative_eq!(r.chain.stiffnesses_nm_per_rad[0], 75.0, max_relative = 1e-12);
    }

    #[test]
    fn stiff_middle_spring_merges_masses_and_shares_compliance() {
        // Stiff spring 1e6 between masses 1 and 3: type B; compliance 1e-6 shared 3/4 left, 1/4 right.
        let r = reduce(&chain(&[5.0, 1.0, 3.0, 5.0], &[100.0, 1e6, 200.0]), 3).unwrap();
        assert!(matches!(r.steps[0], ReductionStep::B { index: 1, .. }));
        assert_relative_eq!(r.chain.inertias_kgm2[1], 4.0);
        assert_relative_eq!(1.0 / r.chain.stiffnesses_nm_per_rad[0], 1.0 / 100.0 + 0.75e-6, max_relative = 1e-12);
        assert_relative_eq!(1.0 / r.chain.stiffnesses_nm_per_rad[1], 1.0 / 200.0 + 0.25e-6, max_relative = 1e-12);
        assert_eq!(r.chain.origins, vec![0, 2, 3]); // the heavier member names the merged mass
    }

    #[test]
    fn total_inertia_is_kept() {
        let ch = chain(&[0.3, 0.01, 2.0, 0.02, 0.5, 0.7], &[1e4, 5e5, 2e3, 8e5, 3e4]);
        for n in 1..=ch.len() {
            let r = reduce(&ch, n).unwrap();
            assert_eq!(r.chain.len(), n);
            assert_relative_eq!(r.chain.total_inertia_kgm2(), ch.total_inertia_kgm2(), max_relative = 1e-12);
        }
    }

    #[test]
    fn zero_or_too_many_masses_is_an_error() {
        let ch = chain(&[1.0, 1.0], &[1.0]);
        assert!(reduce(&ch, 0).is_err());
        assert!(reduce(&ch, 3).is_err());
    }
}
