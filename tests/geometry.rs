//! Geometry → chain (eqs. 1–3) against the analytic free–free torsion of a uniform shaft.

use approx::assert_relative_eq;
use plant::{bodies_from_segments, Chain, Segment};

#[test]
fn uniform_shaft_cut_in_segments_approaches_the_continuum() {
    // A free–free uniform shaft of length L has f1 = (1/2L)·√(G/ρ) (wave equation). N equal
    // lumped segments coupled by eq. (3) give ω1 = 2√(k/m)·sin(π/2N) with k/m = G/(ρ l²), i.e.
    // the continuum value times sin(π/2N)/(π/2N) = 1 − 2.6e-4 for N = 40. Tolerance 5e-4.
    let (l_total, n) = (1.2, 40);
    let seg = Segment::steel(0.05, 0.02, l_total / n as f64);
    let bodies = bodies_from_segments(&vec![seg.clone(); n], &[], "segments", 1).unwrap();
    let chain = Chain::from_bodies(&bodies).unwrap();
    let f = chain.mechanical().modes().unwrap().frequencies_hz;
    let continuum = (seg.shear_modulus_pa / seg.density_kg_per_m3).sqrt() / (2.0 * l_total);
    assert_relative_eq!(f[1], continuum, max_relative = 5e-4);
    // and the second mode, 2·f1 in the continuum (discretisation error 4× larger, 1.0e-3)
    assert_relative_eq!(f[2], 2.0 * continuum, max_relative = 1.5e-3);
    // total inertia is the shaft's: ρ L π (D⁴ − d⁴)/32
    let j = seg.density_kg_per_m3 * l_total * std::f64::consts::PI * (0.05f64.powi(4) - 0.02f64.powi(4)) / 32.0;
    assert_relative_eq!(chain.total_inertia_kgm2(), j, max_relative = 1e-12);
}

#[test]
fn two_inertias_on_a_stepped_shaft_use_the_corrected_lengths() {
    // Disc – thin shaft – thick shaft – disc: the series stiffness between the discs, computed
    // by hand from eqs. (2), (3) and (6), fixes the two-mass frequency ω² = c (J1 + J2)/(J1 J2).
    let thin = Segment::steel(0.02, 0.0, 0.3);
    let thick = Segment::steel(0.05, 0.0, 0.2);
    let bodies = bodies_from_segments(&[thin.clone(), thick.clone()], &[], "s", 1).unwrap();
    let dl = 0.155 * 0.02; // d/D = 0.4 → Δl/d = −0.115·0.4 + 0.1895 = 0.1435
    let dl = dl * 0.1435 / 0.155;
    let c_thin = 81e9 * thin.polar_moment_m4() / (0.3 + dl);
    let c_thick = 81e9 * thick.polar_moment_m4() / (0.2 - dl);
    assert_relative_eq!(bodies[0].stiffness_nm_per_rad, c_thin, max_relative = 1e-12);
    assert_relative_eq!(bodies[1].stiffness_nm_per_rad, c_thick, max_relative = 1e-12);
}
