//! Static bending of a shaft line under its own weight (section 2.5, eqs. (41)–(43)).
//!
//! The shaft line is a beam of hollow cylindrical segments on two bearings (a fixed and a loose
//! one, v = 0 at both); what lies beyond them overhangs freely, e.g. up to a wide-angle joint
//! that transmits no bending moment. The paper finds the deflection with Castigliano's theorem
//! and an auxiliary force F_C (eq. (43)); for a statically determinate beam that is the same as
//! integrating the curvature M/(E I) twice with v = 0 at the bearings, which is what this does,
//! segment by segment on a fine grid.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

use crate::error::{non_negative, positive, PlantError, Result};

/// Young's modulus of steel, Pa.
pub const STEEL_YOUNGS_MODULUS_PA: f64 = 210.0e9;
/// Standard gravity, m/s².
pub const GRAVITY_M_PER_S2: f64 = 9.80665;

/// One segment of the beam.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BeamSegment {
    /// Length, m.
    pub length_m: f64,
    /// Outer diameter, m.
    pub outer_diameter_m: f64,
    /// Inner diameter, m.
    pub inner_diameter_m: f64,
    /// Density, kg/m³.
    pub density_kg_per_m3: f64,
    /// Young's modulus E, Pa.
    pub youngs_modulus_pa: f64,
}

impl BeamSegment {
    fn area_m2(&self) -> f64 {
        PI * (self.outer_diameter_m.powi(2) - self.inner_diameter_m.powi(2)) / 4.0
    }
    /// Axial second moment of area I = π (D⁴ − d⁴)/64, m⁴.
    pub fn second_moment_m4(&self) -> f64 {
        PI * (self.outer_diameter_m.powi(4) - self.inner_diameter_m.powi(4)) / 64.0
    }
}

/// A beam of segments on two bearings at `bearing_a_m` < `bearing_b_m` (measured from the
/// beam's start).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Beam {
    /// Segments from the start of the beam.
    pub segments: Vec<BeamSegment>,
    /// Position of the first bearing, m.
    pub bearing_a_m: f64,
    /// Position of the second bearing, m.
    pub bearing_b_m: f64,
}

/// The bending line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Deflection {
    /// Largest deflection magnitude, m.
    pub max_m: f64,
    /// Where it occurs, m from the start.
    pub at_m: f64,
    /// Bearing forces F_A, F_B (eqs. (41), (42)), N.
    pub bearing_forces_n: [f64; 2],
    /// Sampled bending line (position m, deflection m, positive downwards).
    pub line: Vec<(f64, f64)>,
}

impl Beam {
    /// Total length, m.
    pub fn length_m(&self) -> f64 {
        self.segments.iter().map(|s| s.length_m).sum()
    }

    /// Checks the geometry; keys are named under `section`.
    pub fn validate(&self, section: &str) -> Result<()> {
        if self.segments.is_empty() {
            return Err(PlantError::Invalid(format!("`{section}.segments` is empty")));
        }
        for (i, s) in self.segments.iter().enumerate() {
            let k = |n: &str| format!("{section}.segments[{}].{n}", i + 1);
            positive(|| k("length_m"), s.length_m, "m")?;
            positive(|| k("outer_diameter_m"), s.outer_diameter_m, "m")?;
            non_negative(|| k("inner_diameter_m"), s.inner_diameter_m, "m")?;
            positive(|| k("density_kg_per_m3"), s.density_kg_per_m3, "kg/m^3")?;
            positive(|| k("youngs_modulus_Pa"), s.youngs_modulus_pa, "Pa")?;
            if s.inner_diameter_m >= s.outer_diameter_m {
                return Err(PlantError::Invalid(format!(
                    "`{}` must be smaller than `{}`",
                    k("inner_diameter_m"),
                    k("outer_diameter_m")
                )));
            }
        }
        let l = self.length_m();
        non_negative(|| format!("{section}.bearing_a_m"), self.bearing_a_m, "m")?;
        if !(self.bearing_b_m > self.bearing_a_m && self.bearing_b_m <= l) {
            return Err(PlantError::Invalid(format!(
                "`{section}.bearing_b_m` = {} m must lie after `bearing_a_m` = {} m and within the beam's {l} m",
                self.bearing_b_m, self.bearing_a_m
            )));
        }
        Ok(())
    }

    /// Deflection under self-weight with gravity `g`, on `points` + 1 grid points.
    pub fn deflection(&self, g: f64, points: usize) -> Result<Deflection> {
        self.validate("bending")?;
        let l = self.length_m();
        let n = points.max(100);
        let h = l / n as f64;
        let z: Vec<f64> = (0..=n).map(|i| i as f64 * h).collect();
        let seg_at = |x: f64| {
            let mut acc = 0.0;
            for s in &self.segments {
                acc += s.length_m;
                if x <= acc + 1e-15 {
                    return s;
                }
            }
            self.segments.last().expect("validated non-empty")
        };
        // eqs. (41), (42): total weight and its moment about bearing A fix F_A and F_B
        let (mut weight, mut moment_a) = (0.0, 0.0);
        let mut start = 0.0;
        for s in &self.segments {
            let w = s.density_kg_per_m3 * s.area_m2() * g * s.length_m;
            weight += w;
            moment_a += w * (start + 0.5 * s.length_m - self.bearing_a_m);
            start += s.length_m;
        }
        let fb = moment_a / (self.bearing_b_m - self.bearing_a_m);
        let fa = weight - fb;
        // bending moment M(z) = Σ (reactions left of z)(z − z_r) − ∫₀^z q(ζ)(z − ζ) dζ
        let q: Vec<f64> = z.iter().map(|&x| seg_at(x).density_kg_per_m3 * seg_at(x).area_m2() * g).collect();
        let mut shear_load = vec![0.0; n + 1]; // ∫ q
        let mut moment_load = vec![0.0; n + 1]; // ∫ q (z − ζ)
        for i in 1..=n {
            shear_load[i] = shear_load[i - 1] + 0.5 * (q[i] + q[i - 1]) * h;
            moment_load[i] =
                moment_load[i - 1] + shear_load[i - 1] * h + (q[i - 1] / 2.0 + (q[i] - q[i - 1]) / 6.0) * h * h;
        }
        let m: Vec<f64> = (0..=n)
            .map(|i| {
                let x = z[i];
                let mut v = -moment_load[i];
                if x > self.bearing_a_m {
                    v += fa * (x - self.bearing_a_m);
                }
                if x > self.bearing_b_m {
                    v += fb * (x - self.bearing_b_m);
                }
                v
            })
            .collect();
        // E I y'' = M for the upward deflection y and sagging M > 0; reported v = −y (downwards)
        let kappa: Vec<f64> = (0..=n)
            .map(|i| {
                let s = seg_at(z[i]);
                m[i] / (s.youngs_modulus_pa * s.second_moment_m4())
            })
            .collect();
        let mut slope = vec![0.0; n + 1];
        let mut y = vec![0.0; n + 1];
        for i in 1..=n {
            slope[i] = slope[i - 1] + 0.5 * (kappa[i] + kappa[i - 1]) * h;
            y[i] = y[i - 1] + 0.5 * (slope[i] + slope[i - 1]) * h;
        }
        // add a + b z so that v = 0 at both bearings
        let interp = |x: f64| {
            let i = ((x / h).floor() as usize).min(n - 1);
            let t = (x - z[i]) / h;
            y[i] * (1.0 - t) + y[i + 1] * t
        };
        let (ya, yb) = (interp(self.bearing_a_m), interp(self.bearing_b_m));
        let b = (yb - ya) / (self.bearing_b_m - self.bearing_a_m);
        let a = ya - b * self.bearing_a_m;
        let line: Vec<(f64, f64)> = z.iter().zip(&y).map(|(&x, &yi)| (x, -(yi - a - b * x))).collect();
        let (at_m, max_m) =
            line.iter().fold((0.0, 0.0), |best, &(x, d)| if d.abs() > best.1 { (x, d.abs()) } else { best });
        Ok(Deflection { max_m, at_m, bearing_forces_n: [fa, fb], line })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn uniform(l: f64) -> BeamSegment {
        BeamSegment {
            length_m: l,
            outer_diameter_m: 0.04,
            inner_diameter_m: 0.0,
            density_kg_per_m3: 7850.0,
            youngs_modulus_pa: 210e9,
        }
    }

    #[test]
    fn simply_supported_uniform_beam_is_5wl4_over_384ei() {
        let s = uniform(1.0);
        let w = 7850.0 * s.area_m2() * GRAVITY_M_PER_S2;
        let beam = Beam { segments: vec![s.clone()], bearing_a_m: 0.0, bearing_b_m: 1.0 };
        let d = beam.deflection(GRAVITY_M_PER_S2, 4000).unwrap();
        assert!(d.line[2000].1 > 0.0, "sags downwards");
        assert_relative_eq!(d.max_m, 5.0 * w / (384.0 * 210e9 * s.second_moment_m4()), max_relative = 1e-5);
        assert_relative_eq!(d.at_m, 0.5, epsilon = 1e-3);
        assert_relative_eq!(d.bearing_forces_n[0], w / 2.0, max_relative = 1e-12);
    }

    #[test]
    fn overhang_tip_matches_roark() {
        // Span L on two bearings, overhang a, uniform load w over all: tip deflection (down)
        // w a (4 a² L − L³ + 3 a³) / (24 E I) (Roark, beam with one overhang).
        let (span, a) = (0.6, 0.4);
        let s = uniform(span + a);
        let w = 7850.0 * s.area_m2() * GRAVITY_M_PER_S2;
        let beam = Beam { segments: vec![uniform(span), uniform(a)], bearing_a_m: 0.0, bearing_b_m: span };
        let d = beam.deflection(GRAVITY_M_PER_S2, 10000).unwrap();
        let tip = d.line.last().unwrap().1;
        let want =
            w * a * (4.0 * a * a * span - span.powi(3) + 3.0 * a.powi(3)) / (24.0 * 210e9 * s.second_moment_m4());
        assert_relative_eq!(tip, want, max_relative = 1e-4);
    }

    #[test]
    fn bearing_outside_the_beam_is_an_error() {
        let beam = Beam { segments: vec![uniform(0.5)], bearing_a_m: 0.0, bearing_b_m: 0.7 };
        assert!(beam.deflection(GRAVITY_M_PER_S2, 100).unwrap_err().to_string().contains("bending.bearing_b_m"));
    }
}
