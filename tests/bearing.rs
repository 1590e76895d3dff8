//! Bearing identification: round trips through simulated shake tests, why the IVFM exists, and
//! the squeeze-film-damper bundle.

use std::f64::consts::PI;
use std::process::Command;

use nalgebra::{Complex, DMatrix, DVector, Matrix2};
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

use ident::bearing::fit;
use ident::{Coupling, Impedances, IvfmSettings, Method, ShakeTest, Structure};
use plant::{BearingModel, Coefficients, Support};

fn support() -> Support {
    Support { k_x: 3.68e6, k_y: 3.85e6, c_x: 1226.0, c_y: 1313.0, m_x: 18.14, m_y: 18.14 }
}

/// An element with every kind of term, cross-coupled stiffness included.
fn element() -> Coefficients {
    Coefficients {
        k_n_per_m: [[4.0e5, 1.5e5], [-1.2e5, 5.0e5]],
        c_ns_per_m: [[2600.0, 150.0], [100.0, 2800.0]],
        m_kg: [[5.4, 0.0], [0.0, 5.9]],
    }
}

/// Two shake tests, mainly along x then mainly along y (the other shaker adds a tenth, out of
/// step, so the tests are not ideal), 16 s at 1024 Hz, with white noise on the displacements.
/// Periodic: a multisine of 1 Hz lines 5–85 Hz with random phases. Otherwise: 400 sines at
/// random frequencies in 3–100 Hz (broadband, smooth, not periodic in the record). Simulated
/// with the plant's state space on a grid 4× finer; each hold step carries the force at its
/// midpoint, so the staircase has no half-step delay against the recorded samples.
fn shake(model: &BearingModel, noise_m: f64, seed: u64, periodic: bool) -> [ShakeTest; 2] {
    let ss = model.state_space().unwrap();
    let (fs, fine) = (1024.0, 4);
    let n = 1024 * 16;
    let dt = 1.0 / fs / fine as f64;
    let mut rng = StdRng::seed_from_u64(seed);
    let mut uniform = || rand::Rng::random::<f64>(&mut rng);
    let components: Vec<(f64, f64, f64)> = if periodic {
        (5..=85).map(|f| (f as f64, 25.0, uniform() * 2.0 * PI)).collect()
    } else {
        (0..400).map(|_| (3.0 + 97.0 * uniform(), 14.0, uniform() * 2.0 * PI)).collect()
    };
    let main = |t: f64| components.iter().map(|&(f, a, p)| a * (2.0 * PI * f * t + p).cos()).sum::<f64>();
    let other = |t: f64| 0.1 * main(t - 0.009);
    let noise = Normal::new(0.0, noise_m.max(1e-300)).unwrap();
    let mut out = Vec::new();
    for dir in 0..2 {
        let pair = |t: f64| if dir == 0 { (main(t), other(t)) } else { (other(t), main(t)) };
        let u = DMatrix::from_fn(n * fine, 2, |k, j| {
            let (fx, fy) = pair((k as f64 + 0.5) * dt);
            if j == 0 {
                fx
            } else {
                fy
            }
        });
        // periodic: start on the steady state, reached by running the last period first
        let x0 = if periodic {
            let d = ss.c2d(dt).unwrap();
            let mut x = DVector::zeros(4);
            for k in 0..1024 * fine {
                x = &d.ad * &x + &d.bd * u.row(k).transpose();
            }
            x
        } else {
            DVector::zeros(4)
        };
        let y = ss.lsim(&u, dt, &x0).unwrap();
        let keep: Vec<usize> = (0..n).map(|i| i * fine).collect();
        let forces: Vec<(f64, f64)> = keep.iter().map(|&k| pair(k as f64 * dt)).collect();
        out.push(ShakeTest {
            dt_s: 1.0 / fs,
            force_x_n: forces.iter().map(|f| f.0).collect(),
            force_y_n: forces.iter().map(|f| f.1).collect(),
            disp_x_m: keep.iter().map(|&k| y[(k, 0)] + noise.sample(&mut rng)).collect(),
            disp_y_m: keep.iter().map(|&k| y[(k, 1)] + noise.sample(&mut rng)).collect(),
        });
    }
    [out.remove(0), out.remove(0)]
}

fn close(a: &Coefficients, b: &Coefficients, rel: f64) {
    let scale = |m: &[[f64; 2]; 2]| m.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
    for (name, x, y) in
        [("K", &a.k_n_per_m, &b.k_n_per_m), ("C", &a.c_ns_per_m, &b.c_ns_per_m), ("M", &a.m_kg, &b.m_kg)]
    {
        let s = scale(y);
        for i in 0..2 {
            for j in 0..2 {
                assert!(
                    (x[i][j] - y[i][j]).abs() <= rel * s,
                    "{name}[{i}][{j}]: {} vs {} (tolerance {rel} of {s})",
                    x[i][j],
                    y[i][j]
                );
            }
        }
    }
}

#[test]
fn periodic_shake_round_trip_recovers_every_coefficient() {
    // Displacement noise 0.1 µm against ~20 µm motions. Tolerance 1 % of each matrix's
    // largest entry: the held staircase of the simulation differs from the continuous force by
    // O((ω dt)²) ≈ 1e-4 at 85 Hz, which moves the element's stiffness — a small difference of
    // the system's, which the support dominates — by ~0.1 % of the support's; the noise adds a
    // few 0.1 %.
    let model = BearingModel { element: element(), support: support(), table: None };
    let tests = shake(&model, 1e-7, 7, true);
    let imp = Impedances::from_tests([&tests[0], &tests[1]], (5.0, 85.0)).unwrap();
    assert_eq!(imp.h.len(), 81);
    assert!(matches!(imp.averaging, ident::bearing::Averaging::Periodic { periods: 16 }));
    for method in [Method::Ivfm, Method::Direct] {
        let f = fit(&imp, &support(), Structure::KCM, Coupling::Full, method, &IvfmSettings::default()).unwrap();
        close(&f.element, &element(), 0.01);
        assert!(f.r2.hxx[0] > 0.999 && f.r2.hyy[0] > 0.999 && f.r2.hxx[1] > 0.99, "{:?}", f.r2);
    }
}

#[test]
fn random_excitation_uses_an_h1_estimate() {
    let model = BearingModel { element: element(), support: support(), table: None };
    let tests = shake(&model, 1e-8, 3, false);
    let imp = Impedances::from_tests([&tests[0], &tests[1]], (5.0, 85.0)).unwrap();
    assert!(matches!(imp.averaging, ident::bearing::Averaging::H1 { .. }));
    let f = fit(&imp, &support(), Structure::KCM, Coupling::Full, Method::Ivfm, &IvfmSettings::default()).unwrap();
    // Hann-windowed segments of a random record leak (bias of order the line spacing over the
    // resonance width): a looser 5 %
    close(&f.element, &element(), 0.05);
}

#[test]
fn ivfm_is_consistent_where_least_squares_is_biased() {
    // Slide 30: displacement noise enters the measured flexibilities, so least squares on
    // G H = I sees it squared in AᵀA — a bias that does not average out — while the IVFM's
    // WᵀA sees it only linearly. A model the fit can represent exactly (KCM, direct), exact
    // forces, complex Gaussian noise of 3 % of the displacements' RMS, 200 seeds. Each
    // estimator's mean bias is compared with its own standard error.
    let el = Coefficients {
        k_n_per_m: [[4.0e5, 0.0], [0.0, 5.0e5]],
        c_ns_per_m: [[2600.0, 0.0], [0.0, 2800.0]],
        m_kg: [[5.4, 0.0], [0.0, 5.9]],
    };
    let model = BearingModel { element: el, support: support(), table: None };
    let freqs: Vec<f64> = (5..=85).map(|f| f as f64).collect();
    let force = Matrix2::new(
        Complex::new(100.0, 0.0),
        Complex::new(10.0, 5.0),
        Complex::new(-8.0, 3.0),
        Complex::new(100.0, 0.0),
    );
    let z_true: Vec<Matrix2<Complex<f64>>> =
        freqs.iter().map(|f| model.flexibility(2.0 * PI * f).unwrap() * force).collect();
    let rms = (z_true.iter().map(|z| z.norm_squared()).sum::<f64>() / (4.0 * z_true.len() as f64)).sqrt();
    let noise = Normal::new(0.0, 0.03 * rms / 2f64.sqrt()).unwrap();
    let mut rng = StdRng::seed_from_u64(5);
    let seeds = 200;
    let (mut ls, mut iv): (Vec<Coefficients>, Vec<Coefficients>) = (Vec::new(), Vec::new());
    for _ in 0..seeds {
        let z: Vec<Matrix2<Complex<f64>>> = z_true
            .iter()
            .map(|z| z.map(|c| c + Complex::new(noise.sample(&mut rng), noise.sample(&mut rng))))
            .collect();
        let imp = Impedances::from_spectra(&freqs, &vec![force; freqs.len()], &z).unwrap();
        let s = IvfmSettings::default();
        ls.push(fit(&imp, &support(), Structure::KCM, Coupling::Direct, Method::LeastSquares, &s).unwrap().element);
        iv.push(fit(&imp, &support(), Structure::KCM, Coupling::Direct, Method::Ivfm, &s).unwrap().element);
    }
    let stats = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let sd = (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt();
        (m, sd / (v.len() as f64).sqrt())
    };
    type Pick = fn(&Coefficients) -> f64;
    let terms: [(&str, Pick); 6] = [
        ("Kxx", |c| c.k_n_per_m[0][0]),
        ("Kyy", |c| c.k_n_per_m[1][1]),
        ("Cxx", |c| c.c_ns_per_m[0][0]),
        ("Cyy", |c| c.c_ns_per_m[1][1]),
        ("Mxx", |c| c.m_kg[0][0]),
        ("Myy", |c| c.m_kg[1][1]),
    ];
    println!("mean relative bias over {seeds} seeds, 3 % displacement noise (± standard error):");
    let mut ls_biased = 0;
    for (name, pick) in terms {
        let truth = pick(&el);
        let (m_ls, se_ls) = stats(&ls.iter().map(pick).collect::<Vec<_>>());
        let (m_iv, se_iv) = stats(&iv.iter().map(pick).collect::<Vec<_>>());
        println!(
            "  {name}: least squares {:+.3} ± {:.3} %, IVFM {:+.3} ± {:.3} %",
            100.0 * (m_ls / truth - 1.0),
            100.0 * se_ls / truth,
            100.0 * (m_iv / truth - 1.0),
            100.0 * se_iv / truth
        );
        // the IVFM is unbiased within 3.5 standard errors (6 terms: a false alarm < 0.3 %)
        assert!((m_iv - truth).abs() < 3.5 * se_iv, "{name}: IVFM {m_iv} ± {se_iv} vs {truth}");
        if (m_ls - truth).abs() > 5.0 * se_ls {
            ls_biased += 1;
        }
    }
    assert!(ls_biased >= 2, "least squares should show its noise bias on some terms");
}

#[test]
fn similar_tests_are_flagged_by_their_condition_number() {
    // Slide 20: two tests whose motions are nearly alike make [Z1 Z2] nearly singular.
    let model = BearingModel { element: element(), support: support(), table: None };
    let freqs: Vec<f64> = (5..=85).map(|f| f as f64).collect();
    let force =
        Matrix2::new(Complex::new(100.0, 0.0), Complex::new(99.0, 0.0), Complex::new(1.0, 0.0), Complex::new(2.0, 0.0));
    let z: Vec<Matrix2<Complex<f64>>> =
        freqs.iter().map(|f| model.flexibility(2.0 * PI * f).unwrap() * force).collect();
    let imp = Impedances::from_spectra(&freqs, &vec![force; freqs.len()], &z).unwrap();
    assert!(imp.condition_max() > ident::bearing::CONDITION_WARNING);
    assert!(!imp.ill_conditioned_hz().is_empty());
}

fn rigtwin(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rigtwin")).args(args).output().expect("run rigtwin")
}

#[test]
fn sfd_bundle_gives_a_squeeze_film_damper_of_the_slides_size() {
    let bundle = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/sfd_shake.toml");
    assert!(bundle.exists(), "{} is missing", bundle.display());
    let svg = std::env::temp_dir().join(format!("rigtwin-sfd-{}.svg", std::process::id()));
    let out = rigtwin(&[
        "bearing",
        bundle.to_str().unwrap(),
        "--structure",
        "KCM",
        "--coupling",
        "full",
        "--json",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["method"], "ivfm");
    let c = |k: &str, i: usize, j: usize| v[k][i][j].as_f64().unwrap();
    // Slides 46–47: the SFD's damping is 5–25 lbf s/in and its inertia 5–25 lb over the tested
    // orbits; 1 lbf s/in = 175.13 N s/m, 1 lb = 0.4536 kg.
    for i in 0..2 {
        let c_lbf = c("C_Ns_per_m", i, i) / 175.1268;
        let m_lb = c("M_kg", i, i) / 0.45359237;
        assert!((5.0..25.0).contains(&c_lbf), "C{i}{i} = {c_lbf} lbf s/in");
        assert!((5.0..25.0).contains(&m_lb), "M{i}{i} = {m_lb} lb");
    }
    // slide 44: cross-coupling an order of magnitude below the direct terms
    assert!(c("C_Ns_per_m", 0, 1).abs() < 0.1 * c("C_Ns_per_m", 0, 0));
    for term in ["Hxx", "Hyy"] {
        assert!(v["r2"][term][0].as_f64().unwrap() > 0.99 && v["r2"][term][1].as_f64().unwrap() > 0.99, "{}", v["r2"]);
    }
    assert!(v["condition_number_max"].as_f64().unwrap() < 2.0);
    let plot = std::fs::read_to_string(&svg).unwrap();
    assert!(plot.starts_with("<svg") && plot.contains("Re Hxx") && plot.contains("Im Hyy"));
    // the declared KC fit: its real parts are not explained, and the report says why
    let out = rigtwin(&["bearing", bundle.to_str().unwrap(), "--json"]);
    let kc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(kc["structure"], "KC");
    assert!(kc["r2"]["Hxx"][0].as_f64().unwrap() < 0.97, "{}", kc["r2"]);
    assert!(kc["K_N_per_m"][0][0].as_f64().unwrap() < 0.0, "KC mimics the inertia with a negative stiffness");
    let warnings = kc["warnings"].to_string();
    assert!(warnings.contains("KCM") && warnings.contains("inertia"), "{warnings}");
    // the FMU's squeeze-film bearing is this identification (KCM, full coupling, IVFM) of sfd_shake,
    // with the bundle's support: the numbers in fmu/src/params.rs are not typed in by hand
    let default = rigtwin_fmu::params::sfd_bearing();
    for (key, table) in [
        ("K_N_per_m", default.element.k_n_per_m),
        ("C_Ns_per_m", default.element.c_ns_per_m),
        ("M_kg", default.element.m_kg),
    ] {
        for (i, row) in table.iter().enumerate() {
            for (j, &want) in row.iter().enumerate() {
                // the JSON carries the identification to float_roundtrip precision; 1e-9 of the
                // direct term leaves room for the last bits of a different summation order
                let scale = table[i][i].abs();
                assert!(
                    (c(key, i, j) - want).abs() <= 1e-9 * scale,
                    "{key}[{i}][{j}]: {} vs default {want}",
                    c(key, i, j)
                );
            }
        }
    }
    let b = rigtwin::bundle::load_bearing(&bundle).unwrap();
    assert_eq!(b.support, default.support);
}

#[test]
fn bad_bearing_bundles_are_refused_with_the_key() {
    let dir = std::env::temp_dir().join(format!("rigtwin-bearing-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = "kind = \"bearing_shake\"\ntests = [\"a.csv\", \"b.csv\"]\nf_min_hz = 5.0\nf_max_hz = 85.0\n[support]\nk_x = 1e6\nk_y = 1e6\nc_x = 1e3\nc_y = 1e3\nm_x = 10.0\nm_y = 10.0\n[model]\nstructure = \"KC\"\ncoupling = \"direct\"\n";
    for (bad, expect) in [
        (good.replace("m_x = 10.0", "m_x = 0.0"), "support.m_x"),
        (good.replace("structure = \"KC\"", "structure = \"KCD\""), "KCD"),
        (good.replace("tests = [\"a.csv\", \"b.csv\"]", "tests = [\"a.csv\"]"), "two"),
        (good.replace("f_max_hz = 85.0", "f_max_hz = 1.0"), "f_min"),
        (good.to_string(), "a.csv"),
    ] {
        let f = dir.join("b.toml");
        std::fs::write(&f, &bad).unwrap();
        let out = rigtwin(&["bearing", f.to_str().unwrap()]);
        assert!(!out.status.success());
        let e = String::from_utf8_lossy(&out.stderr);
        assert!(e.contains(expect), "expected `{expect}` in: {e}");
    }
}
