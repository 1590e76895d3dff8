//! Cost of one co-simulation step of the rigtwin FMU, in-process through its C API, beside a C
//! reference doing the same zero-order-hold step (6 states: the paper rig; compiled here with
//! gcc -O2). The rig is driven by a constant 1 N·m drive torque: left to ring down from a twist,
//! its states reach subnormal numbers after about 2e6 steps, and every loop then measures the
//! processor's slow path for them (about 400 ns for either), not the step.

use std::ffi::CString;
use std::hint::black_box;
use std::process::Command;

use criterion::{criterion_group, criterion_main, Criterion};
use rigtwin_fmu::fmi3::*;
use rigtwin_fmu::model::{Model, NU};
use rigtwin_fmu::variables::VR_TWIST;
use rigtwin_fmu::FmuParams;

fn fmu_step(c: &mut Criterion) {
    let p = FmuParams::default();
    let token = CString::new(rigtwin_fmu::token(&p)).unwrap();
    let inst = unsafe {
        fmi3InstantiateCoSimulation(
            c"bench".as_ptr(),
            token.as_ptr(),
            std::ptr::null(),
            false,
            false,
            false,
            false,
            std::ptr::null(),
            0,
            std::ptr::null_mut(),
            None,
            None,
        )
    };
    assert!(!inst.is_null());
    unsafe {
        let vr = VR_TWIST; // the side shafts' twist
        assert_eq!(fmi3SetFloat64(inst, &vr, 1, &0.02, 1), 0);
        let m_drive = rigtwin_fmu::variables::VR_INPUT + 1;
        assert_eq!(fmi3SetFloat64(inst, &m_drive, 1, &1.0, 1), 0);
        assert_eq!(fmi3EnterInitializationMode(inst, false, 0.0, 0.0, false, 0.0), 0);
        assert_eq!(fmi3ExitInitializationMode(inst), 0);
    }
    let mut t = 0.0;
    let (mut ev, mut term, mut early, mut last) = (false, false, false, 0.0);
    c.bench_function("fmi3DoStep (h = 1 ms, 6 states, in-process)", |b| {
        b.iter(|| {
            let s = unsafe { fmi3DoStep(inst, black_box(t), 1e-3, true, &mut ev, &mut term, &mut early, &mut last) };
            t += 1e-3;
            black_box(s)
        })
    });
    unsafe { fmi3FreeInstance(inst) };

    // the model's step alone (no FMI call, no instance checks)
    let mut m = Model::new(&p.plant).unwrap();
    let mut z = nalgebra::DVector::zeros(m.nx());
    z[1] = 0.01;
    let mut u = [0.0; NU];
    u[1] = 1.0;
    let delays = vec![plant::DelayLine::default(); NU];
    let mut t = 0.0;
    c.bench_function("Model::step (h = 1 ms, 6 states)", |b| {
        b.iter(|| {
            let r = m.step(black_box(&mut z), &u, t, 1e-3, &delays);
            t += 1e-3;
            black_box(r)
        })
    });

    // the C reference with the same matrices
    let dir = std::env::temp_dir().join(format!("rigtwin-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let lib = dir.join("libreference_step.so");
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/reference_step.c");
    let built = Command::new("gcc").args(["-O2", "-shared", "-fPIC", "-o"]).arg(&lib).arg(&src).status();
    if !matches!(built, Ok(s) if s.success()) {
        eprintln!("gcc is not available: no C reference");
        return;
    }
    let mut m = Model::new(&p.plant).unwrap();
    let nx = m.nx();
    let (ad, bd) = m.discretisation(1e-3).unwrap();
    let nu = bd.ncols();
    let (ad, bd): (Vec<f64>, Vec<f64>) = (ad.transpose().as_slice().to_vec(), bd.transpose().as_slice().to_vec()); // row-major
    unsafe {
        let lib = libloading::Library::new(&lib).unwrap();
        let step: libloading::Symbol<
            unsafe extern "C" fn(i32, i32, *const f64, *const f64, *mut f64, *const f64, *mut f64),
        > = lib.get(b"reference_step").unwrap();
        let mut x = vec![0.0; nx];
        x[1] = 0.01;
        let mut u = vec![0.0; nu];
        u[1] = 1.0;
        let mut scratch = vec![0.0; nx];
        c.bench_function("C reference step (gcc -O2, same 6-state ZOH matrices)", |b| {
            b.iter(|| {
                step(
                    nx as i32,
                    nu as i32,
                    ad.as_ptr(),
                    bd.as_ptr(),
                    black_box(x.as_mut_ptr()),
                    u.as_ptr(),
                    scratch.as_mut_ptr(),
                )
            })
        });
    }
}

criterion_group!(benches, fmu_step);
criterion_main!(benches);
