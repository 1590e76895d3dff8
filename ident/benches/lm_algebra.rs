//! The dense algebra of one Levenberg–Marquardt iteration of a 60 s, 1 kHz diagnosis (issue 15,
//! item 6): a Jacobian of 120 000 residuals (two speeds) × p parameters (p = 5: j_drive, c_short
//! and two effects' three parameters) and the step from it. Four ways, side by side:
//! - `columns_i16`: what `ident::diagnose::lm` does — columns kept in 16 bits an entry
//!   (`lm::Column`, a quarter of the memory), JᵀJ and Jᵀr summed in f64 row by row
//!   (`lm::normal_sums`), the p × p system by nalgebra's LU;
//! - `nalgebra_normal`: an f64 DMatrix J, `J.tr_mul(&J)`, `J.tr_mul(&r)`, LU;
//! - `faer_normal`: a faer Mat J, `Jᵀ * J`, `Jᵀ * r`, LU of the small system;
//! - `faer_qr` / `nalgebra_qr`: least squares by QR of the tall J (no normal equations).
//!
//! Run: `cargo bench -p ident --features faer-bench --bench lm_algebra` (faer is built for this
//! bench only).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use faer::linalg::solvers::{Solve, SolveLstsqCore};
use ident::diagnose::lm;
use nalgebra::{DMatrix, DVector};

const ROWS: usize = 120_000;
const P: usize = 5;

fn column(j: usize) -> Vec<f64> {
    (0..ROWS)
        .map(|k| ((k as f64 * 0.001 * (j + 1) as f64).sin() + 0.1 * (k % (7 + j)) as f64) / (j + 1) as f64)
        .collect()
}

fn bench(c: &mut Criterion) {
    let cols: Vec<Vec<f64>> = (0..P).map(column).collect();
    let r: Vec<f64> = (0..ROWS).map(|k| (k as f64 * 0.0037).cos()).collect();
    let zeros = vec![0.0; ROWS];
    let cols16: Vec<lm::Column> = cols.iter().map(|c| lm::Column::of(c, &zeros, 1.0)).collect();
    let jn = DMatrix::from_fn(ROWS, P, |i, j| cols[j][i]);
    let rn = DVector::from_column_slice(&r);
    let jf = faer::Mat::<f64>::from_fn(ROWS, P, |i, j| cols[j][i]);
    let rf = faer::Mat::<f64>::from_fn(ROWS, 1, |i, _| r[i]);
    let mut g = c.benchmark_group("lm_step_120000x5");
    g.bench_function("columns_i16", |b| {
        b.iter(|| {
            let (jtj, grad) = lm::normal_sums(&cols16, &r, 1, &|_| 0).pop().expect("one group");
            black_box(jtj.lu().solve(&grad))
        })
    });
    g.bench_function("nalgebra_normal", |b| {
        b.iter(|| {
            let jtj = jn.tr_mul(&jn);
            let grad = jn.tr_mul(&rn);
            black_box(jtj.lu().solve(&grad))
        })
    });
    g.bench_function("faer_normal", |b| {
        b.iter(|| {
            let jtj = jf.transpose() * &jf;
            let grad = jf.transpose() * &rf;
            black_box(jtj.partial_piv_lu().solve(&grad))
        })
    });
    g.bench_function("nalgebra_qr", |b| {
        b.iter(|| {
            let qr = jn.clone().qr();
            let qtr = qr.q().tr_mul(&rn);
            black_box(qr.r().solve_upper_triangular(&qtr))
        })
    });
    g.bench_function("faer_qr", |b| {
        b.iter(|| {
            let mut x = rf.clone();
            jf.qr().solve_lstsq_in_place_with_conj(faer::Conj::No, x.as_mut());
            black_box(x)
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(3));
    targets = bench
}
criterion_main!(benches);
