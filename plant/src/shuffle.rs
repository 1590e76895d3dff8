//! Which mode is the vehicle shuffle (sections 2.2, 4.4): the drive oscillates against both
//! outputs, the outputs in phase, and the side shafts are the vibration nodes.

use nalgebra::DVector;
use serde::Serialize;

use crate::mechanical::Layout;
use crate::modal::Modes;

/// A mode's character.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ModeKind {
    /// All coordinates move together (0 Hz).
    RigidBody,
    /// The load machines oscillate against each other.
    OutputsAntiphase,
    /// The shuffle mode.
    Shuffle,
    /// Anything else (local, higher modes).
    Other,
}

/// Below this fraction of the largest component a coordinate counts as standing still: the
/// classifier asks who moves against whom, and 5 % is well above round-off and well below any
/// participation that can be seen in a measurement.
const STILL: f64 = 0.05;

/// Classifies one mode shape of a rig.
pub fn classify(frequency_hz: f64, shape: &DVector<f64>, layout: &Layout) -> ModeKind {
    let max = shape.amax();
    if max == 0.0 {
        return ModeKind::Other;
    }
    let s = shape / max;
    let spread = s.max() - s.min();
    if frequency_hz == 0.0 && spread < 1e-6 {
        return ModeKind::RigidBody;
    }
    let moves = |x: f64| x.abs() >= STILL;
    let (m2, m3) = (s[layout.m2], s[layout.m3]);
    if moves(m2) && moves(m3) && m2.signum() != m3.signum() {
        return ModeKind::OutputsAntiphase;
    }
    let Some(d) = layout.drive.map(|i| s[i]) else { return ModeKind::Other };
    let node_in = |(a, b): (usize, usize)| s[a] * s[b] <= 0.0;
    if frequency_hz > 0.0
        && moves(m2)
        && moves(m3)
        && moves(d)
        && m2.signum() == m3.signum()
        && d.signum() != m2.signum()
        && node_in(layout.short_shaft)
        && node_in(layout.long_shaft)
    {
        return ModeKind::Shuffle;
    }
    ModeKind::Other
}

impl Modes {
    /// The kind of every mode.
    pub fn kinds(&self, layout: &Layout) -> Vec<ModeKind> {
        self.frequencies_hz.iter().zip(&self.shapes).map(|(&f, s)| classify(f, s, layout)).collect()
    }

    /// Index of the lowest shuffle mode, if any.
    pub fn shuffle_mode(&self, layout: &Layout) -> Option<usize> {
        self.kinds(layout).iter().position(|&k| k == ModeKind::Shuffle)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const L: Layout = Layout { m2: 0, drive: Some(1), m3: 2, short_shaft: (0, 1), long_shaft: (1, 2) };

    #[test]
    fn textbook_shapes() {
        let v = |a: &[f64]| DVector::from_row_slice(a);
        assert_eq!(classify(0.0, &v(&[1.0, 1.0, 1.0]), &L), ModeKind::RigidBody);
        assert_eq!(classify(6.0, &v(&[1.0, 0.02, -0.9]), &L), ModeKind::OutputsAntiphase);
        assert_eq!(classify(12.0, &v(&[-0.3, 1.0, -0.3]), &L), ModeKind::Shuffle);
        assert_eq!(classify(12.0, &v(&[0.3, 1.0, 0.3]), &L), ModeKind::Other);
        // drive standing still is not a shuffle
        assert_eq!(classify(12.0, &v(&[1.0, 0.01, 0.9]), &L), ModeKind::Other);
    }
}
