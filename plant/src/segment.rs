//! Hollow-cylinder shaft segments → inertia and partial stiffness (section 2.1, Figure 2).

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

use crate::chain::Body;
use crate::error::{non_negative, positive, PlantError, Result};

/// Shear modulus of steel, Pa (the default of a segment).
pub const STEEL_SHEAR_MODULUS_PA: f64 = 81.0e9;
/// Density of steel, kg/m³ (the default of a segment).
pub const STEEL_DENSITY_KG_PER_M3: f64 = 7850.0;

/// One rotationally symmetric, hollow cylindrical segment of a stepped shaft.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// Outer diameter d1, m.
    pub outer_diameter_m: f64,
    /// Inner diameter d2, m (0 for a solid shaft).
    pub inner_diameter_m: f64,
    /// Length l, m.
    pub length_m: f64,
    /// Shear modulus G, Pa.
    pub shear_modulus_pa: f64,
    /// Density ρ, kg/m³.
    pub density_kg_per_m3: f64,
}

impl Segment {
    /// A solid or hollow steel segment.
    pub fn steel(outer_diameter_m: f64, inner_diameter_m: f64, length_m: f64) -> Self {
        Segment {
            outer_diameter_m,
            inner_diameter_m,
            length_m,
            shear_modulus_pa: STEEL_SHEAR_MODULUS_PA,
            density_kg_per_m3: STEEL_DENSITY_KG_PER_M3,
        }
    }

    /// Checks that the geometry and material describe a real segment; `field` prefixes the key names.
    pub fn validate(&self, field: &str) -> Result<()> {
        positive(|| format!("{field}.outer_diameter_m"), self.outer_diameter_m, "m")?;
        non_negative(|| format!("{field}.inner_diameter_m"), self.inner_diameter_m, "m")?;
        positive(|| format!("{field}.length_m"), self.length_m, "m")?;
        positive(|| format!("{field}.shear_modulus_Pa"), self.shear_modulus_pa, "Pa")?;
        positive(|| format!("{field}.density_kg_per_m3"), self.density_kg_per_m3, "kg/m^3")?;
        if self.inner_diameter_m >= self.outer_diameter_m {
            return Err(PlantError::Invalid(format!(
                "`{field}.inner_diameter_m` = {} m must be smaller than `{field}.outer_diameter_m` = {} m",
                self.inner_diameter_m, self.outer_diameter_m
            )));
        }
        Ok(())
    }

    /// Polar second moment of area π (d1⁴ − d2⁴) / 32, m⁴.
    pub fn polar_moment_m4(&self) -> f64 {
        PI * (self.outer_diameter_m.powi(4) - self.inner_diameter_m.powi(4)) / 32.0
    }

    /// Eq. (1): J = ρ l π (d1⁴ − d2⁴) / 32, kg m².
    pub fn inertia_kgm2(&self) -> f64 {
        self.density_kg_per_m3 * self.length_m * self.polar_moment_m4()
    }

    /// Eq. (2): c = G π (d1⁴ − d2⁴) / (32 l), Nm/rad, for the segment's own length.
    pub fn stiffness_nm_per_rad(&self) -> f64 {
        self.stiffness_for_length(self.length_m)
    }

    fn stiffness_for_length(&self, length_m: f64) -> f64 {
        self.shear_modulus_pa * self.polar_moment_m4() / length_m
    }
}

/// Eqs. (5)–(6) for a sharp step (r̄ = 0): the additional length Δl by which the force flow
/// reaches into the larger segment, m. `d_small` is the smaller, `d_big` the larger diameter.
///
/// Δl/d = 0.155 for d/D ≤ 0.3; −0.115 d/D + 0.1895 for 0.3 < d/D ≤ 0.5; 0.264 (1 − d/D) above.
/// (The three branches are continuous at 0.3 and 0.5, which fixes the sign of the middle one.)
pub fn step_length_correction_m(d_small: f64, d_big: f64) -> f64 {
    let ratio = (d_small / d_big).clamp(0.0, 1.0);
    let per_diameter = if ratio <= 0.3 {
        0.155
    } else if ratio <= 0.5 {
        -0.115 * ratio + 0.1895
    } else {
        0.264 * (1.0 - ratio)
    };
    per_diameter * d_small
}

/// Bodies of a stepped shaft: inertia from eq. (1) on the drawn lengths, partial stiffness from
/// eq. (2) on lengths corrected at every diameter step (eqs. (4)–(6): the smaller segment gets
/// Δl longer, the larger Δl shorter). `names[i]` names segment i; errors call segment i
/// `{field}[first + i]`, so a caller can number them as its own list does.
pub fn bodies_from_segments(segments: &[Segment], names: &[String], field: &str, first: usize) -> Result<Vec<Body>> {
    for (i, s) in segments.iter().enumerate() {
        s.validate(&format!("{field}[{}]", first + i))?;
    }
    let mut effective: Vec<f64> = segments.iter().map(|s| s.length_m).collect();
    for i in 0..segments.len().saturating_sub(1) {
        let (a, b) = (&segments[i], &segments[i + 1]);
        if a.outer_diameter_m == b.outer_diameter_m {
            continue;
        }
        let (small, big) = if a.outer_diameter_m < b.outer_diameter_m { (i, i + 1) } else { (i + 1, i) };
        let dl = step_length_correction_m(segments[small].outer_diameter_m, segments[big].outer_diameter_m);
        effective[small] += dl; // eq. (4): the thin segment acts longer ...
        effective[big] -= dl; // ... and the thick one shorter
    }
    segments
        .iter()
        .zip(&effective)
        .enumerate()
        .map(|(i, (s, &l))| {
            if l <= 0.0 {
                return Err(PlantError::Invalid(format!(
                    "`{field}[{}].length_m` = {} m is shorter than the diameter-step corrections of eq. (6) \
                     that act on it ({:.4} m in all)",
                    first + i,
                    s.length_m,
                    s.length_m - l
                )));
            }
            Ok(Body {
                name: names.get(i).cloned().unwrap_or_else(|| format!("segment {}", i + 1)),
                inertia_kgm2: s.inertia_kgm2(),
                stiffness_nm_per_rad: s.stiffness_for_length(l),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn solid_shaft_matches_textbook_formulas() {
        // d = 40 mm, l = 0.5 m steel: Ip = π d⁴/32 = 2.5133e-7 m⁴ (hand computation).
        let s = Segment::steel(0.04, 0.0, 0.5);
        assert_relative_eq!(s.polar_moment_m4(), 2.513_274e-7, max_relative = 1e-6);
        assert_relative_eq!(s.inertia_kgm2(), 7850.0 * 0.5 * 2.513_274e-7, max_relative = 1e-6);
        assert_relative_eq!(s.stiffness_nm_per_rad(), 81e9 * 2.513_274e-7 / 0.5, max_relative = 1e-6);
    }

    #[test]
    fn hollow_shaft_subtracts_bore() {
        let s = Segment::steel(0.04, 0.02, 1.0);
        // (0.04⁴ − 0.02⁴) = 2.4e-6 m⁴ → × π/32
        assert_relative_eq!(s.polar_moment_m4(), PI * 2.4e-6 / 32.0, max_relative = 1e-12);
    }

    #[test]
    fn step_correction_is_continuous_and_vanishes_without_a_step() {
        let d = 0.02;
        assert_relative_eq!(step_length_correction_m(d, d / 0.3), 0.155 * d, max_relative = 1e-12);
        assert_relative_eq!(step_length_correction_m(0.3 * 0.1, 0.1), 0.155 * 0.03, max_relative = 1e-9);
        assert_relative_eq!(step_length_correction_m(0.05, 0.1), 0.132 * 0.05, max_relative = 1e-9);
        assert_eq!(step_length_correction_m(0.1, 0.1), 0.0);
        assert_relative_eq!(step_length_correction_m(0.01, 0.1), 0.155 * 0.01);
    }

    #[test]
    fn step_softens_the_chain_and_keeps_inertia() {
        let segs = [Segment::steel(0.06, 0.0, 0.1), Segment::steel(0.03, 0.0, 0.2)];
        let bodies = bodies_from_segments(&segs, &[], "chain.segments", 1).unwrap();
        // d/D = 0.5 → Δl = 0.132 d = 3.96 mm
        let dl = 0.132 * 0.03;
        assert_relative_eq!(
            bodies[1].stiffness_nm_per_rad,
            81e9 * segs[1].polar_moment_m4() / (0.2 + dl),
            max_relative = 1e-9
        );
        assert_relative_eq!(
            bodies[0].stiffness_nm_per_rad,
            81e9 * segs[0].polar_moment_m4() / (0.1 - dl),
            max_relative = 1e-9
        );
        assert_relative_eq!(bodies[0].inertia_kgm2, segs[0].inertia_kgm2());
    }

    #[test]
    fn bad_geometry_names_the_key() {
        let segs = [Segment::steel(0.02, 0.03, 0.1)];
        let e = bodies_from_segments(&segs, &[], "chain.segments", 1).unwrap_err().to_string();
        assert!(e.contains("chain.segments[1].inner_diameter_m"), "{e}");
    }
}
