//! The FMU's dynamics: the open-differential powertrain with its drive-path effects
//! (`plant::effects::Powertrain`) beside the bearing block (4 states) where the rig has one. The physics is written in
//! absolute angles x (the powertrain's coordinates); the FMU's continuous states are z = T x, the
//! same vector with the drive's angle replaced by the side shafts' twist 2φ_drive − φ_m2 − φ_m3
//! and the motor's angle by the compliance's twist φ_motor − φ_drive (bounded states, see
//! `variables::STATES`); every matrix below is in z unless its name says otherwise. Without backlash the model
//! is linear, x' = A x + B u, and the co-simulation step is exact for inputs held over the step:
//! x⁺ = Ad x + Bd u with (Ad, Bd) from the matrix exponential, cached per step length. A dead
//! time splits the step where the delayed drive torque changes, each piece exact; backlash and
//! friction are integrated by the diagnosis's integrator, `plant::integrate::PiecewiseRk4` with
//! the steps of `Powertrain::rk4_steps_s` (coarse within a smooth piece, fine across the play's
//! edges and the friction's steep band).

use nalgebra::{DMatrix, DVector};

use crate::params::FmuParams;
use crate::variables::{powertrain_states, Table};
use plant::effects::{DelayLine, Powertrain};
use plant::integrate::PieceMaps;
use plant::integrate::{PiecewiseRk4, PiecewiseSmooth};
use plant::zoh_step::{longest_exact_piece, ZohCache, CACHE, MAX_PIECES};

/// Number of inputs: M_m2, M_drive, M_m3, bearing F_x, F_y.
pub const NU: usize = 5;
/// Index of the drive torque among the inputs (the one the dead time acts on).
pub const DRIVE_INPUT: usize = 1;

/// The model of one parameter set and its discretisations.
#[derive(Debug, Clone)]
pub struct Model {
    /// System matrix with the side shafts engaged (the whole linear model without backlash).
    pub a: DMatrix<f64>,
    /// Input matrix (nx × 5).
    pub b: DMatrix<f64>,
    /// Side-shaft torques from the states (2 × nx), shafts engaged.
    pub torque: DMatrix<f64>,
    /// System matrix and torques inside the backlash play (shafts carry nothing).
    a_open: DMatrix<f64>,
    torque_open: DMatrix<f64>,
    /// The engaged system and input matrices in absolute angles (the backlash integrator's),
    /// the system inside the play and the play's offset (`Powertrain::play_offset`).
    a_x: DMatrix<f64>,
    b_x: DMatrix<f64>,
    a_open_x: DMatrix<f64>,
    play_offset_x: Vec<f64>,
    /// Exact steps of the play's linear pieces per step length (backlash without friction), as
    /// the diagnosis steps them.
    piece_maps: Vec<PieceMaps>,
    /// z = T x and x = T⁻¹ z.
    t: DMatrix<f64>,
    t_inv: DMatrix<f64>,
    /// State-vector index of the motor's angle (drive compliance).
    motor: Option<usize>,
    /// Absolute angles of a state, the state being stepped (scratch).
    xs: DVector<f64>,
    next: DVector<f64>,
    /// Longest exact piece, s: ‖[A B]‖₁ · piece = `plant::statespace::ZOH_MAX_NORM` / 2^10.
    max_piece_s: f64,
    /// The nonlinear model's integrator (`Powertrain::rk4_steps_s`, the coarse step shortened
    /// where the bearing block is faster).
    rk: PiecewiseRk4,
    powertrain: Powertrain,
    /// State-vector index of each powertrain state.
    map: Vec<usize>,
    cache: ZohCache,
    /// The effects make the model nonlinear (play, friction): RK4 rather than exact steps.
    is_nonlinear: bool,
    pieces: Vec<(f64, f64)>,
    pt_x: Vec<f64>,
    pt_dx: Vec<f64>,
}

impl Model {
    /// Builds the model; the error names the offending parameter.
    pub fn new(p: &FmuParams) -> Result<Self, String> {
        if p.drive.is_some() {
            return Err("a drive model's parameter set is stepped by `plant::Stepper`".into());
        }
        let powertrain = Powertrain::new(&p.powertrain, p.variant, &p.effects).map_err(|e| e.to_string())?;
        let br = p.bearing.as_ref().map(|b| b.state_space()).transpose().map_err(|e| e.to_string())?;
        let table = Table::of_plant(p);
        // the bearing block's states are next to the powertrain's speeds (`variables::STATES`)
        let bearing_at = table.states.iter().position(|&s| s == 6);
        let nx = table.nx();
        let map: Vec<usize> = powertrain_states(&p.effects)
            .iter()
            .map(|s| table.states.iter().position(|x| x == s).expect("every powertrain state is in the table"))
            .collect();
        let assemble = |contact: bool| {
            let (pa, pb, pc) = powertrain.linear(contact);
            let mut a = DMatrix::zeros(nx, nx);
            let mut b = DMatrix::zeros(nx, NU);
            let mut torque = DMatrix::zeros(2, nx);
            for (i, &fi) in map.iter().enumerate() {
                for (j, &fj) in map.iter().enumerate() {
                    a[(fi, fj)] = pa[(i, j)];
                }
                for k in 0..3 {
                    b[(fi, k)] = pb[(i, k)];
                }
                for k in 0..2 {
                    torque[(k, fi)] = pc[(k, i)];
                }
            }
            if let (Some(br), Some(k)) = (&br, bearing_at) {
                a.view_mut((k, k), (4, 4)).copy_from(&br.a);
                b.view_mut((k, 3), (4, 2)).copy_from(&br.b);
            }
            (a, b, torque)
        };
        let (a_x, b_x, torque_x) = assemble(true);
        let (a_open_x, _, torque_open_x) = assemble(false);
        if a_x.iter().chain(b_x.iter()).any(|v| !v.is_finite()) {
            return Err("the parameters give a system matrix with non-finite entries".into());
        }
        // z = T x: the twist 2φ_drive − φ_m2 − φ_m3 in place of φ_drive, φ_motor − φ_drive in
        // place of φ_motor; T⁻¹ written out (φ_drive = (twist + φ_m2 + φ_m3)/2), so exact
        let (m2, drive, m3) = (map[0], map[1], map[2]);
        let motor = (powertrain.dofs() == 4).then(|| map[3]);
        let mut t = DMatrix::identity(nx, nx);
        let mut t_inv = DMatrix::identity(nx, nx);
        t[(drive, drive)] = 2.0;
        t[(drive, m2)] = -1.0;
        t[(drive, m3)] = -1.0;
        for j in [drive, m2, m3] {
            t_inv[(drive, j)] = 0.5;
        }
        if let Some(mo) = motor {
            t[(mo, drive)] = -1.0;
            for j in [drive, m2, m3] {
                t_inv[(mo, j)] = 0.5;
            }
        }
        let similar = |m: &DMatrix<f64>| &t * m * &t_inv;
        let npt = map.len();
        let (a, b) = (similar(&a_x), &t * &b_x);
        let max_piece_s = longest_exact_piece(&a, &b).map_err(|e| e.to_string())?;
        // the powertrain's RK4 step (the diagnosis's), shorter only where the bearing block is
        // faster than it resolves (h·|λ|max ≤ 0.5)
        let bearing_rate =
            br.as_ref().map_or(0.0, |br| br.a.complex_eigenvalues().iter().map(|l| l.norm()).fold(0.0, f64::max));
        let (coarse, fine) = powertrain.rk4_steps_s();
        let coarse = coarse.min(plant::integrate::RK4_STEP_TIMES_RATE / bearing_rate.max(1e-300));
        let rk = PiecewiseRk4::new(nx, coarse, fine);
        let mut play_offset_x = vec![0.0; nx];
        for (&i, e) in map.iter().zip(powertrain.play_offset()) {
            play_offset_x[i] = e;
        }
        Ok(Model {
            max_piece_s,
            rk,
            next: DVector::zeros(nx),
            a,
            b,
            torque: torque_x * &t_inv,
            a_open: similar(&a_open_x),
            torque_open: torque_open_x * &t_inv,
            a_x,
            b_x,
            a_open_x,
            play_offset_x,
            piece_maps: Vec::new(),
            t,
            t_inv,
            motor,
            xs: DVector::zeros(nx),
            powertrain,
            map,
            cache: ZohCache::default(),
            is_nonlinear: p.effects.is_nonlinear(),
            pieces: Vec::new(),
            pt_x: vec![0.0; npt],
            pt_dx: vec![0.0; npt],
        })
    }

    /// Number of continuous states.
    pub fn nx(&self) -> usize {
        self.a.nrows()
    }

    /// The powertrain with its effects.
    pub fn powertrain(&self) -> &Powertrain {
        &self.powertrain
    }

    /// Dead time of the drive torque, s (0: none).
    pub fn delay_s(&self) -> f64 {
        self.powertrain.effects.time_delay_s
    }

    /// Backlash or friction: the right-hand side is nonlinear, integrated by RK4.
    fn nonlinear(&self) -> bool {
        self.is_nonlinear
    }

    /// The state vector z of the powertrain state `x` (absolute angles, the order of
    /// `Powertrain::state_names`), the bearing at rest.
    pub fn state_of_powertrain(&self, x: &[f64]) -> DVector<f64> {
        let mut full = DVector::zeros(self.nx());
        for (&i, &v) in self.map.iter().zip(x) {
            full[i] = v;
        }
        &self.t * full
    }

    /// The powertrain's states (absolute angles, its own order) of state vector `z`.
    pub fn powertrain_part(&self, z: &[f64]) -> Vec<f64> {
        let x = &self.t_inv * DVector::from_column_slice(z);
        self.map.iter().map(|&i| x[i]).collect()
    }

    /// ż into `out` for the inputs `u` with the drive torque replaced by `drive` (the delayed
    /// value; `u[DRIVE_INPUT]` without a dead time).
    pub fn derivatives(&mut self, z: &[f64], u: &[f64], drive: f64, out: &mut [f64]) {
        let mut u_eff = [0.0; NU];
        u_eff.copy_from_slice(u);
        u_eff[DRIVE_INPUT] = drive;
        if self.nonlinear() {
            let mut xs = std::mem::take(&mut self.xs);
            xs.gemv(1.0, &self.t_inv, &DVector::from_column_slice(z), 0.0);
            let mut dx = DVector::zeros(z.len());
            self.system(u_eff, None).rhs(xs.as_slice(), dx.as_mut_slice());
            out.copy_from_slice((&self.t * dx).as_slice());
            self.xs = xs;
        } else {
            affine(&self.a, &self.b, z, &u_eff, out);
        }
    }

    /// The side-shaft torques [T_short, T_long] in state `z`.
    pub fn torques(&self, z: &[f64]) -> [f64; 2] {
        if self.nonlinear() {
            self.powertrain.shaft_torques(&self.powertrain_part(z))
        } else {
            let t = &self.torque * DVector::from_column_slice(z);
            [t[0], t[1]]
        }
    }

    /// The absolute angles that are not states, [φ_drive, φ_motor] (φ_motor is φ_drive without
    /// a compliance), in state `z`.
    pub fn angles(&self, z: &[f64]) -> [f64; 2] {
        [0, 1].map(|i| self.t_inv.row(self.angle_row(i)).iter().zip(z).map(|(a, b)| a * b).sum())
    }

    /// ∂[φ_drive, φ_motor][i]/∂z_j: an entry of T⁻¹.
    pub fn angle_gradient(&self, i: usize, j: usize) -> f64 {
        self.t_inv[(self.angle_row(i), j)]
    }

    /// The row of x (and of T⁻¹) of angle `i` of [`Model::angles`].
    fn angle_row(&self, i: usize) -> usize {
        if i == 0 {
            self.map[1]
        } else {
            self.motor.unwrap_or(self.map[1])
        }
    }

    /// The Jacobians (∂ż/∂z, ∂ż/∂u, ∂T/∂z) at state `z`: the linear model, or with backlash the
    /// one of the contact state `z` is in, with friction its slope at the present speeds. With a
    /// dead time, ż does not depend on the present drive torque (its column of ∂ż/∂u is then to
    /// be taken as zero by the caller).
    pub fn jacobians(&self, z: &[f64]) -> (std::borrow::Cow<'_, DMatrix<f64>>, &DMatrix<f64>, &DMatrix<f64>) {
        use std::borrow::Cow;
        if !self.nonlinear() {
            return (Cow::Borrowed(&self.a), &self.b, &self.torque);
        }
        let x = self.powertrain_part(z);
        let (a, torque) =
            if self.powertrain.in_contact(&x) { (&self.a, &self.torque) } else { (&self.a_open, &self.torque_open) };
        let slopes = self.powertrain.friction_slopes(&x);
        if slopes.is_empty() {
            return (Cow::Borrowed(a), &self.b, torque);
        }
        // the speeds are states of z as of x: the slope sits on the diagonal
        let mut a = a.clone();
        for (i, slope) in slopes {
            a[(self.map[i], self.map[i])] += slope;
        }
        (Cow::Owned(a), &self.b, torque)
    }

    /// One step of state `z` of length `h` from time `t` with `u` held (the drive torque delayed
    /// through `delay`); the linear model allocates only when a new piece length is discretised.
    /// Backlash is integrated in absolute angles, as the diagnosis integrates it. A step longer
    /// than the model can take exactly (linear: [`MAX_PIECES`] exact pieces, each within
    /// `plant::statespace::ZOH_MAX_NORM` of the model's time scales; backlash: [`MAX_PIECES`]
    /// RK4 sub-steps) is refused, and so is a step whose state comes out non-finite; `z` is
    /// then left as it was.
    pub fn step(
        &mut self,
        z: &mut DVector<f64>,
        u: &DVector<f64>,
        t: f64,
        h: f64,
        delay: &DelayLine,
    ) -> Result<(), String> {
        // the common case — linear, no dead time: one exact step over [Ad Bd]
        if !self.nonlinear() && self.delay_s() <= 0.0 && h <= MAX_PIECES as f64 * self.max_piece_s {
            let i = self.discretise(h)?;
            return self
                .cache
                .advance(i, z.as_mut_slice(), u.as_slice())
                .map_err(|k| format!("state {k} became non-finite over the step from {t} s"));
        }
        let finest = if self.nonlinear() { self.rk.fine_s } else { self.max_piece_s };
        let sub_steps = h / finest;
        if sub_steps.is_nan() || sub_steps > MAX_PIECES as f64 {
            let longest = MAX_PIECES as f64 * finest;
            return Err(format!(
                "a step of {h} s is longer than this model integrates exactly (at most {longest:.4e} s)"
            ));
        }
        let mut pieces = std::mem::take(&mut self.pieces);
        pieces.clear();
        if self.delay_s() > 0.0 {
            delay.segments(t, t + h, self.delay_s(), u[DRIVE_INPUT], &mut pieces);
        } else {
            pieces.push((h, u[DRIVE_INPUT]));
        }
        let mut u_eff = [0.0; NU];
        u_eff.copy_from_slice(u.as_slice());
        let mut x = std::mem::take(&mut self.xs);
        let mut out = std::mem::take(&mut self.next);
        out.copy_from(z);
        if self.nonlinear() {
            x.gemv(1.0, &self.t_inv, z, 0.0);
        }
        let mut result = Ok(());
        for &(len, drive) in &pieces {
            u_eff[DRIVE_INPUT] = drive;
            if self.nonlinear() {
                let maps = self.piece_maps_for(len);
                let mut rk = std::mem::replace(&mut self.rk, PiecewiseRk4::new(0, 1.0, 1.0));
                rk.advance(&mut self.system(u_eff, maps), x.as_mut_slice(), len);
                self.rk = rk;
            } else {
                let i = match self.discretise(len) {
                    Ok(i) => i,
                    Err(e) => {
                        result = Err(e);
                        break;
                    }
                };
                if let Err(k) = self.cache.advance(i, out.as_mut_slice(), &u_eff) {
                    result = Err(format!("state {k} became non-finite over the step from {t} s"));
                    break;
                }
            }
        }
        if self.nonlinear() {
            out.gemv(1.0, &self.t, &x, 0.0);
        }
        if result.is_ok() {
            if let Some(i) = out.iter().position(|v| !v.is_finite()) {
                result = Err(format!("state {i} became {} over the step from {t} s", out[i]));
            } else {
                z.copy_from(&out);
            }
        }
        self.xs = x;
        self.next = out;
        self.pieces = pieces;
        result
    }

    /// The right-hand side in absolute angles with the inputs `u` held, and the exact steps of
    /// the play's pieces `maps` (an index into the cache).
    fn system(&mut self, u: [f64; NU], maps: Option<usize>) -> System<'_> {
        System {
            a_x: &self.a_x,
            b_x: &self.b_x,
            powertrain: &self.powertrain,
            map: &self.map,
            pt_x: &mut self.pt_x,
            pt_dx: &mut self.pt_dx,
            u,
            maps: maps.and_then(|i| self.piece_maps.get(i)),
        }
    }

    /// The index of the exact piece steps of length `h` (built on first use, [`CACHE`] kept);
    /// `None` where the pieces are not linear (friction) or cannot be discretised (RK4 then).
    fn piece_maps_for(&mut self, h: f64) -> Option<usize> {
        if !self.powertrain.pieces_are_linear() {
            return None;
        }
        if let Some(i) = self.piece_maps.iter().position(|m| m.h() == h) {
            return Some(i);
        }
        let (a, a_open, b) = (&self.a_x, &self.a_open_x, &self.b_x);
        let maps = PieceMaps::new(
            h,
            &|contact| (if contact { a.clone() } else { a_open.clone() }, b.clone()),
            &self.play_offset_x,
        )?;
        if self.piece_maps.len() >= CACHE {
            self.piece_maps.remove(0);
        }
        self.piece_maps.push(maps);
        Some(self.piece_maps.len() - 1)
    }

    /// (Ad, Bd) of step size `h` (the linear model, shafts engaged).
    pub fn discretisation(&mut self, h: f64) -> Result<(&DMatrix<f64>, &DMatrix<f64>), String> {
        let i = self.discretise(h)?;
        Ok(self.cache.get(i))
    }

    #[inline]
    fn discretise(&mut self, h: f64) -> Result<usize, String> {
        self.cache.index(&self.a, &self.b, h, self.max_piece_s).map_err(|e| e.to_string())
    }
}

/// out = A x + B u (no allocation).
fn affine(a: &DMatrix<f64>, b: &DMatrix<f64>, x: &[f64], u: &[f64], out: &mut [f64]) {
    for (i, o) in out.iter_mut().enumerate() {
        *o = a.row(i).iter().zip(x).map(|(a, v)| a * v).sum::<f64>()
            + b.row(i).iter().zip(u).map(|(b, v)| b * v).sum::<f64>();
    }
}

/// ẋ = A x + B u in absolute angles, the powertrain's rows from its own (nonlinear) derivative
/// with backlash and friction; its pieces are the powertrain's.
struct System<'a> {
    a_x: &'a DMatrix<f64>,
    b_x: &'a DMatrix<f64>,
    powertrain: &'a Powertrain,
    map: &'a [usize],
    pt_x: &'a mut Vec<f64>,
    pt_dx: &'a mut Vec<f64>,
    u: [f64; NU],
    maps: Option<&'a PieceMaps>,
}

impl System<'_> {
    fn gather(&mut self, x: &[f64]) {
        for (k, &i) in self.map.iter().enumerate() {
            self.pt_x[k] = x[i];
        }
    }
}

impl PiecewiseSmooth for System<'_> {
    fn rhs(&mut self, x: &[f64], out: &mut [f64]) {
        affine(self.a_x, self.b_x, x, &self.u, out);
        if self.powertrain.effects.is_nonlinear() {
            self.gather(x);
            self.powertrain.derivative(self.pt_x, [self.u[0], self.u[1], self.u[2]], self.pt_dx);
            for (k, &i) in self.map.iter().enumerate() {
                out[i] = self.pt_dx[k];
            }
        }
    }

    fn piece(&mut self, x: &[f64]) -> u64 {
        self.gather(x);
        self.powertrain.piece(self.pt_x)
    }

    fn exact(&mut self, piece: u64, x: &[f64], h: f64, out: &mut [f64]) -> bool {
        self.maps.is_some_and(|m| m.step(piece, x, &self.u, h, out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn shuffle_and_bearing_poles_survive_the_assembly() {
        let p = FmuParams::with_sfd_bearing();
        let m = Model::new(&p).unwrap();
        let poles = plant::damp(&m.a).unwrap();
        let f_shuffle = p.powertrain.open_differential(p.variant).unwrap().modes().unwrap().frequencies_hz[2];
        assert!(poles.iter().any(|q| (q.natural_hz - f_shuffle).abs() < 0.01 * f_shuffle), "{poles:?}");
        // bearing on its support: ω² ≈ (K + Kh)/(M + Mh) along x
        let b = p.bearing.as_ref().unwrap();
        let k = b.element.k_n_per_m[0][0] + b.support.k_x;
        let mass = b.element.m_kg[0][0] + b.support.m_x;
        let f_b = (k / mass).sqrt() / (2.0 * std::f64::consts::PI);
        assert!(poles.iter().any(|q| (q.natural_hz - f_b).abs() < 0.05 * f_b), "{poles:?}");
        // the paper rig alone has the powertrain's six states and no pole near the bearing's
        let rig = Model::new(&FmuParams::default()).unwrap();
        assert_eq!(rig.nx(), 6);
        let poles = plant::damp(&rig.a).unwrap();
        assert!(poles.iter().all(|q| (q.natural_hz - f_b).abs() > 0.5 * f_b), "{poles:?}");
    }

    #[test]
    fn two_half_steps_are_one_step() {
        let mut m = Model::new(&FmuParams::with_sfd_bearing()).unwrap();
        let u = DVector::from_vec(vec![1.0, 10.0, -2.0, 50.0, -20.0]);
        let mut x1 = DVector::from_element(10, 1e-3);
        let mut x2 = x1.clone();
        let d = DelayLine::default();
        m.step(&mut x1, &u, 0.0, 2e-3, &d).unwrap();
        m.step(&mut x2, &u, 0.0, 1e-3, &d).unwrap();
        m.step(&mut x2, &u, 1e-3, 1e-3, &d).unwrap();
        for i in 0..10 {
            assert_relative_eq!(x1[i], x2[i], max_relative = 1e-9, epsilon = 1e-15);
        }
    }
}
