//! The plant FMU's instance — the paper rig with each kind of effect, with its bearing block,
//! and a drive model — counted by a global allocator (alone in its test binary, so no other
//! test's allocations are counted): after the first steps (which discretise the step length and
//! grow the dead time's history to its size) a communication step — set the inputs, read
//! states, outputs and derivatives, DoStep — allocates nothing.

#[global_allocator]
static ALLOCATOR: mpc::alloc_counter::Counting = mpc::alloc_counter::Counting;

mod common;

use common::Quiet;
use rigtwin_fmu::instance::{Instance, Interface};
use rigtwin_fmu::variables::{Causality, Slot};
use rigtwin_fmu::{FmuParams, RigPlant};

fn rig(f: impl FnOnce(&mut plant::rig::DriveEffects)) -> FmuParams {
    let mut r = RigPlant::default();
    f(&mut r.effects);
    FmuParams::of_rig(r)
}

fn drive_model() -> FmuParams {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../rigs/branched_gearbox.toml");
    let file = modelfile::read(&path).unwrap();
    let modelfile::Model::Drive(m) = file.model else { panic!("a drive model") };
    FmuParams::of_drive(m)
}

/// Allocations of each of `steps` communication steps after `warm` steps.
fn allocations_per_step(p: &FmuParams, warm: usize, steps: usize) -> Vec<u64> {
    let mut i = Instance::new("t", Interface::CoSimulation, Box::new(Quiet), false, p);
    let table = i.table().clone();
    let vrs = |f: &dyn Fn(&rigtwin_fmu::variables::Variable) -> bool| -> Vec<u32> {
        table.variables.iter().filter(|v| f(v)).map(|v| v.vr).collect()
    };
    let inputs = vrs(&|v| v.causality == Causality::Input);
    let outputs = vrs(&|v| v.causality == Causality::Output || matches!(v.slot, Slot::Derivative(_)));
    i.enter_initialization_mode(0.0, None).unwrap();
    i.exit_initialization_mode().unwrap();
    let (mut u, mut y) = (vec![0.0; inputs.len()], vec![0.0; outputs.len()]);
    let mut counts = Vec::new();
    for k in 0..warm + steps {
        let t = k as f64 * 1e-3;
        let before = mpc::alloc_counter::allocations();
        for (j, v) in u.iter_mut().enumerate() {
            // torques that reverse, so the play and the friction switch
            *v = 20.0 * (2.0 * std::f64::consts::PI * (3.0 + j as f64) * t).sin();
        }
        i.set_f64(&inputs, &u).unwrap();
        i.get_f64(&outputs, &mut y).unwrap();
        i.do_step(t, 1e-3).unwrap();
        if k >= warm {
            counts.push(mpc::alloc_counter::allocations() - before);
        }
        assert!(y.iter().all(|v| v.is_finite()));
    }
    counts
}

#[test]
fn a_plant_communication_step_allocates_nothing() {
    let cases = [
        ("rig", FmuParams::default()),
        ("rig with bearing", FmuParams::with_sfd_bearing()),
        (
            "rig with dead time and lag",
            rig(|e| {
                e.time_delay_s = 0.0043;
                e.actuator_lag_s = 0.005;
            }),
        ),
        ("rig with play", rig(|e| e.backlash_rad = 0.002)),
        (
            "rig with friction and compliance",
            rig(|e| {
                e.coulomb_friction_nm = [0.5, 0.2, 0.5];
                e.compliance_stiffness_nm_per_rad = 3000.0;
                e.compliance_motor_fraction = 0.4;
            }),
        ),
        ("branched gearbox", drive_model()),
    ];
    for (name, p) in cases {
        let counts = allocations_per_step(&p, 50, 300);
        let total: u64 = counts.iter().sum();
        assert_eq!(total, 0, "{name}: allocations per step {counts:?}");
    }
}
