use mpc::closed_loop::*;
use mpc::*;
use plant::mechanical::Output;
use plant::rig::Variant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let horizon: usize = args.get(1).map(|s| s.parse().unwrap()).unwrap_or(50);
    let sparse = args.get(2).map(|s| s == "sparse").unwrap_or(false);
    let noblock = args.get(3).map(|s| s == "noblock").unwrap_or(false);
    let ss = plant::paper::damped_params()
        .open_differential(Variant::V1)
        .unwrap()
        .state_space(&[Output::Speeds, Output::SpringTorques])
        .unwrap();
    let mut s = MpcSettings::powertrain(horizon);
    if let Ok(v) = std::env::var("TL") {
        s.solver.time_limit_s = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("TOL") {
        s.solver.tol_gap = v.parse().unwrap();
        s.solver.tol_feas = s.solver.tol_gap;
    }
    if std::env::var("NOEQ").is_ok() {
        s.solver.equilibrate = false;
    }
    if std::env::var("NOIR").is_ok() {
        s.solver.iterative_refinement = false;
    }
    if std::env::var("NOSOFT").is_ok() {
        for o in s.outputs.iter_mut() {
            o.soft_min = None;
            o.soft_max = None;
        }
    }
    if sparse {
        s.formulation = Formulation::Sparse;
    }
    if noblock {
        s.move_blocks.clear();
    }
    let sc = Scenario::new(ScenarioKind::Step);
    let sig = RigSignals::of(&ss).unwrap();
    let (x0, u0) = steady_spin(&ss, sc.speed_radps).unwrap();
    let mut c = Controller::new(&ss, &s).unwrap();
    println!(
        "refs {:?} nvars {} nrows {} nnzP {} nnzA {}",
        c.reference_names(),
        c.qp().nvars(),
        c.qp().nrows(),
        c.qp().p.nzval.len(),
        c.qp().a.nzval.len()
    );
    c.reset(&x0, &u0);
    let mut p = LinearPlant::new(&ss, 1e-3, &x0).unwrap();
    let samples = (sc.duration_s / 1e-3) as usize;
    let refs = |k: usize| vec![sc.speed_radps, sc.speed_radps, sc.drive_torque(k as f64 * 1e-3)];
    let mut times = vec![];
    let mut iters = vec![];
    let mut u = u0.clone();
    let mut tr = vec![];
    for k in 0..samples {
        let y = p.outputs().to_vec();
        let (v, info) = c.step(&y, &refs(k));
        u.copy_from_slice(v);
        times.push(info.elapsed_s * 1e6);
        iters.push(info.solve.iterations);
        tr.push(y[sig.short_shaft]);
        p.advance(&u).unwrap();
    }
    times.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let mean_it = iters.iter().sum::<u32>() as f64 / iters.len() as f64;
    println!(
        "median {:.1} us p99 {:.1} max {:.1}, iters mean {mean_it:.1} fallbacks {}",
        times[times.len() / 2],
        times[times.len() * 99 / 100],
        times[times.len() - 1],
        c.fallbacks()
    );
    let f = step_figures(&tr, (sc.start_s / 1e-3) as usize, 1e-3, 0.02);
    println!("mpc {:?} final {:.2}", f, tr[tr.len() - 1]);
    let ex = c.exact_first_input().unwrap();
    println!("u0 rt {:?} exact {:?}", c.planned_first_input(), ex);
    let mut pi = PiBaseline::new(
        vec![(sig.inputs[0], sig.speeds[0], 0), (sig.inputs[2], sig.speeds[2], 1)],
        vec![(sig.inputs[1], 2)],
        plant::paper::J_LOAD_KGM2,
        5.0,
        1e-3,
        vec![u0[0], u0[2]],
    );
    let mut p = LinearPlant::new(&ss, 1e-3, &x0).unwrap();
    let t = simulate(&mut p, &mut pi, samples, 1e-3, &u0, &refs).unwrap();
    let f = step_figures(&t.output(sig.short_shaft), (sc.start_s / 1e-3) as usize, 1e-3, 0.02);
    println!("pi {:?}", f);
}
