#[global_allocator]
static A: mpc::alloc_counter::Counting = mpc::alloc_counter::Counting;
use mpc::closed_loop::*;
use mpc::*;
use plant::mechanical::Output;
fn main() {
    let ss = plant::paper::damped_params()
        .open_differential(plant::rig::Variant::V1)
        .unwrap()
        .state_space(&[Output::Speeds, Output::SpringTorques])
        .unwrap();
    let s = MpcSettings::powertrain(50);
    let (x0, u0) = steady_spin(&ss, 10.0).unwrap();
    let mut c = Controller::new(&ss, &s).unwrap();
    c.reset(&x0, &u0);
    let mut p = LinearPlant::new(&ss, 1e-3, &x0).unwrap();
    let mut u = u0.clone();
    let r = [10.0, 10.0, 40.0];
    let mut y = vec![0.0; 5];
    for k in 0..200 {
        y.copy_from_slice(p.outputs());
        let before = mpc::alloc_counter::allocations();
        let (v, _) = c.step(&y, &r);
        u.copy_from_slice(v);
        let after = mpc::alloc_counter::allocations();
        if k < 5 || k % 50 == 0 {
            println!("step {k}: {} allocations", after - before);
        }
        p.advance(&u).unwrap();
    }
}
