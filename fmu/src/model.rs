//! The plant FMU's dynamics, for the paper rig and any drive model alike: the drivetrain
//! stepped by `plant::Stepper` — the one step of every model (the rig's in its own twist
//! coordinates and with the diagnosis's integrator, `Stepper::paper_rig`) — and, where the
//! rig has one, the bearing block beside it (4 states, its own forces as inputs, no coupling
//! to the powertrain), stepped exactly. The FMU's continuous states are the variable table's:
//! a drive model's are the stepper's; the rig's are its powertrain's with the bearing's after
//! the speeds (`variables::STATES`).

use nalgebra::{DMatrix, DVector};

use crate::params::{Plant, RigPlant};
use crate::variables::{powertrain_states, Table};
use plant::zoh_step::{longest_exact_piece, ZohCache, MAX_PIECES};
use plant::{DelayLine, DriveModel, Stepper};

/// The paper rig's input slots: M_m2, M_drive, M_m3, bearing F_x, F_y.
pub const NU: usize = 5;
/// Index of the rig's drive torque among the inputs (the one its dead time acts on).
pub const DRIVE_INPUT: usize = 1;

/// The bearing block: ẋ = A x + B [F_x F_y] on [x, y, vx, vy], stepped by exact ZOH.
#[derive(Debug, Clone)]
struct Bearing {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    /// Table index of its first state.
    at: usize,
    max_piece_s: f64,
    cache: ZohCache,
    /// Scratch: its states.
    x: [f64; 4],
}

/// The model of one parameter set.
#[derive(Debug)]
pub struct Model {
    stepper: Stepper,
    bearing: Option<Bearing>,
    /// Table state index of each of the stepper's states.
    map: Vec<usize>,
    /// The table's states are the stepper's, in its order.
    direct: bool,
    /// The drivetrain's inputs (the first of the table's input slots; the bearing's follow).
    nu: usize,
    /// The table's input slots.
    input_slots: usize,
    /// The bodies whose positions are the table's angle outputs, in `Slot::Angle` order.
    angle_bodies: Vec<usize>,
    /// Scratch: the stepper's state, its derivative, the coupling forces, the positions.
    zp: DVector<f64>,
    dzp: Vec<f64>,
    forces: Vec<f64>,
    q: Vec<f64>,
}

impl Model {
    /// Builds the model; the error names the offending parameter.
    pub fn new(p: &Plant) -> Result<Self, String> {
        let table = Table::of_plant(p);
        match p {
            Plant::Drive(m) => Model::of_drive(m, table.input_slots),
            Plant::PaperRig(r) => Model::of_rig(r, &table),
        }
    }

    /// A drive model: the stepper's states are the table's, every body's position an angle.
    fn of_drive(m: &DriveModel, input_slots: usize) -> Result<Self, String> {
        let stepper = Stepper::new(m).map_err(|e| e.to_string())?;
        let nx = stepper.nx();
        Ok(Model::assemble(stepper, None, (0..nx).collect(), input_slots, (0..m.line.bodies.len()).collect()))
    }

    /// The paper rig: its drive model ([`DriveModel::paper_rig`], stepped by
    /// [`Stepper::paper_rig`]) and bearing block.
    fn of_rig(p: &RigPlant, table: &Table) -> Result<Self, String> {
        let rig = p.drive_model()?;
        let stepper = Stepper::paper_rig(&rig).map_err(|e| e.to_string())?;
        let map: Vec<usize> = powertrain_states(&p.effects)
            .iter()
            .map(|s| table.states.iter().position(|x| x == s).expect("every powertrain state is in the table"))
            .collect();
        let bearing = match &p.bearing {
            None => None,
            Some(b) => {
                let ss = b.state_space().map_err(|e| e.to_string())?;
                let at = table.states.iter().position(|&s| s == 6).expect("a bearing's states are in the table");
                let max_piece_s = longest_exact_piece(&ss.a, &ss.b).map_err(|e| e.to_string())?;
                Some(Bearing { a: ss.a, b: ss.b, at, max_piece_s, cache: ZohCache::default(), x: [0.0; 4] })
            }
        };
        // φ_drive, then φ_motor (the cage's without a compliance)
        let motor = if rig.line.bodies.len() == 4 { 3 } else { 1 };
        Ok(Model::assemble(stepper, bearing, map, table.input_slots, vec![1, motor]))
    }

    fn assemble(
        stepper: Stepper,
        bearing: Option<Bearing>,
        map: Vec<usize>,
        input_slots: usize,
        angle_bodies: Vec<usize>,
    ) -> Model {
        let direct = bearing.is_none() && map.iter().enumerate().all(|(k, &i)| k == i);
        let nzp = map.len();
        Model {
            zp: DVector::zeros(nzp),
            dzp: vec![0.0; nzp],
            forces: vec![0.0; stepper.couplings()],
            q: vec![0.0; stepper.bodies()],
            nu: stepper.dynamics.ninputs(),
            input_slots,
            angle_bodies,
            stepper,
            bearing,
            map,
            direct,
        }
    }

    /// Number of continuous states.
    pub fn nx(&self) -> usize {
        self.map.len() + if self.bearing.is_some() { 4 } else { 0 }
    }

    /// The stepper's state ← the table's state `z`.
    fn gather(&mut self, z: &[f64]) {
        for (v, &i) in self.zp.iter_mut().zip(&self.map) {
            *v = z[i];
        }
    }

    /// ż into `out` with the inputs acting now `acting` (each after its dead time).
    pub fn derivatives(&mut self, z: &[f64], acting: &[f64], out: &mut [f64]) {
        self.gather(z);
        self.stepper.derivatives(self.zp.as_slice(), &acting[..self.nu], &mut self.dzp);
        for (&i, &v) in self.map.iter().zip(&self.dzp) {
            out[i] = v;
        }
        if let Some(b) = &self.bearing {
            let (x, f) = (&z[b.at..b.at + 4], &acting[self.nu..self.nu + 2]);
            for i in 0..4 {
                out[b.at + i] =
                    (0..4).map(|j| b.a[(i, j)] * x[j]).sum::<f64>() + (0..2).map(|j| b.b[(i, j)] * f[j]).sum::<f64>();
            }
        }
    }

    /// Every coupling's force (torque) in state `z` into `out` (the rig's side shafts first:
    /// T_short, T_long). Allocation-free once `out` has held them.
    pub fn forces_into(&mut self, z: &[f64], out: &mut Vec<f64>) {
        self.gather(z);
        self.stepper.coupling_forces(self.zp.as_slice(), &mut self.forces);
        out.clear();
        out.extend_from_slice(&self.forces);
    }

    /// The absolute positions that are angle outputs (`Slot::Angle`) in state `z` into `out`:
    /// a drive model's every body's, the rig's [φ_drive, φ_motor]. Allocation-free once `out`
    /// has held them.
    pub fn angles_into(&mut self, z: &[f64], out: &mut Vec<f64>) {
        self.gather(z);
        self.stepper.positions_into(self.zp.as_slice(), &mut self.q);
        out.clear();
        out.extend(self.angle_bodies.iter().map(|&b| self.q[b]));
    }

    /// ∂(angle output i)/∂z_j.
    pub fn angle_gradient(&self, i: usize, j: usize) -> f64 {
        let body = self.angle_bodies[i];
        self.map.iter().position(|&k| k == j).map_or(0.0, |k| self.stepper.position_gradient(body, k))
    }

    /// The Jacobians (∂ż/∂z, ∂ż/∂u over the input slots, ∂(coupling forces)/∂z) at state `z`
    /// with the inputs acting now `acting` (`Stepper::jacobians`: the linear model, or the
    /// nonlinear one's slopes where the state is), the bearing's block beside. With a dead
    /// time, ż does not depend on the present input (its column of ∂ż/∂u is then to be taken
    /// as zero by the caller).
    pub fn jacobians(&mut self, z: &[f64], acting: &[f64]) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        self.gather(z);
        let (ap, bp, cp) = self.stepper.jacobians(self.zp.as_slice(), &acting[..self.nu]);
        if self.direct && self.input_slots == self.nu {
            return (ap, bp, cp);
        }
        let (nx, nc) = (self.nx(), cp.nrows());
        let (mut a, mut b, mut t) =
            (DMatrix::zeros(nx, nx), DMatrix::zeros(nx, self.input_slots), DMatrix::zeros(nc, nx));
        for (k, &i) in self.map.iter().enumerate() {
            for (l, &j) in self.map.iter().enumerate() {
                a[(i, j)] = ap[(k, l)];
            }
            for j in 0..self.nu {
                b[(i, j)] = bp[(k, j)];
            }
            for r in 0..nc {
                t[(r, i)] = cp[(r, k)];
            }
        }
        if let Some(br) = &self.bearing {
            a.view_mut((br.at, br.at), (4, 4)).copy_from(&br.a);
            b.view_mut((br.at, self.nu), (4, 2)).copy_from(&br.b);
        }
        (a, b, t)
    }

    /// One step of state `z` of length `h` from time `t` with `u` held (input j delayed
    /// through `delays[j]` where it has a dead time): the drivetrain's by [`Stepper::step`],
    /// the bearing's exact. A step longer than the model can take (more than
    /// [`MAX_PIECES`] pieces or sub-steps) is refused, and so is a step whose state comes out
    /// non-finite; `z` is then left as it was. Allocates only when a new piece length is
    /// discretised.
    pub fn step(
        &mut self,
        z: &mut DVector<f64>,
        u: &[f64],
        t: f64,
        h: f64,
        delays: &[DelayLine],
    ) -> Result<(), String> {
        let (up, ub) = u.split_at(self.nu);
        let delays = &delays[..self.nu.min(delays.len())];
        if self.direct {
            return self.stepper.step(z, up, t, h, delays).map_err(|e| e.to_string());
        }
        if let Some(b) = &mut self.bearing {
            if h > MAX_PIECES as f64 * b.max_piece_s {
                return Err(format!("a step of {h} s is longer than the bearing block is stepped exactly"));
            }
            let i = b.cache.index(&b.a, &b.b, h, b.max_piece_s).map_err(|e| e.to_string())?;
            b.x.copy_from_slice(&z.as_slice()[b.at..b.at + 4]);
            b.cache
                .advance(i, &mut b.x, ub)
                .map_err(|k| format!("bearing state {k} became non-finite over the step from {t} s"))?;
        }
        self.gather(z.as_slice());
        let mut zp = std::mem::take(&mut self.zp);
        let stepped = self.stepper.step(&mut zp, up, t, h, delays).map_err(|e| e.to_string());
        if stepped.is_ok() {
            for (&i, &v) in self.map.iter().zip(zp.iter()) {
                z[i] = v;
            }
            if let Some(b) = &self.bearing {
                z.as_mut_slice()[b.at..b.at + 4].copy_from_slice(&b.x);
            }
        }
        self.zp = zp;
        stepped
    }

    /// (Ad, Bd) of the drivetrain's linear model over `h` (its own inputs).
    pub fn discretisation(&mut self, h: f64) -> Result<(&DMatrix<f64>, &DMatrix<f64>), String> {
        self.stepper.discretisation(h).map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::FmuParams;
    use approx::assert_relative_eq;

    #[test]
    fn shuffle_and_bearing_poles_survive_the_assembly() {
        let params = FmuParams::with_sfd_bearing();
        let mut m = Model::new(&params.plant).unwrap();
        let p = params.plant.rig().unwrap();
        let nx = m.nx();
        let (a, _, _) = m.jacobians(&vec![0.0; nx], &[0.0; NU]);
        let poles = plant::damp(&a).unwrap();
        let f_shuffle = p.powertrain.open_differential(p.variant).unwrap().modes().unwrap().frequencies_hz[2];
        assert!(poles.iter().any(|q| (q.natural_hz - f_shuffle).abs() < 0.01 * f_shuffle), "{poles:?}");
        // bearing on its support: ω² ≈ (K + Kh)/(M + Mh) along x
        let b = p.bearing.as_ref().unwrap();
        let k = b.element.k_n_per_m[0][0] + b.support.k_x;
        let mass = b.element.m_kg[0][0] + b.support.m_x;
        let f_b = (k / mass).sqrt() / (2.0 * std::f64::consts::PI);
        assert!(poles.iter().any(|q| (q.natural_hz - f_b).abs() < 0.05 * f_b), "{poles:?}");
        // the paper rig alone has the powertrain's six states and no pole near the bearing's
        let mut rig = Model::new(&FmuParams::default().plant).unwrap();
        assert_eq!(rig.nx(), 6);
        let (a, _, _) = rig.jacobians(&[0.0; 6], &[0.0; NU]);
        let poles = plant::damp(&a).unwrap();
        assert!(poles.iter().all(|q| (q.natural_hz - f_b).abs() > 0.5 * f_b), "{poles:?}");
    }

    #[test]
    fn two_half_steps_are_one_step() {
        let mut m = Model::new(&FmuParams::with_sfd_bearing().plant).unwrap();
        let u = [1.0, 10.0, -2.0, 50.0, -20.0];
        let mut x1 = DVector::from_element(10, 1e-3);
        let mut x2 = x1.clone();
        let d = vec![DelayLine::default(); NU];
        m.step(&mut x1, &u, 0.0, 2e-3, &d).unwrap();
        m.step(&mut x2, &u, 0.0, 1e-3, &d).unwrap();
        m.step(&mut x2, &u, 1e-3, 1e-3, &d).unwrap();
        for i in 0..10 {
            assert_relative_eq!(x1[i], x2[i], max_relative = 1e-9, epsilon = 1e-15);
        }
    }
}
