//! `rigtwin modal --params` on drive models written as engineers draw them, against
//! openTorsion (PyPI) on the same assemblies (tests/opentorsion_modes.py): a five-disk chain, a
//! geared chain with shaft damping and damping to ground, and a branched gearbox (one pinion
//! meshing two wheels, each with its own load). openTorsion models the gears as nodes tied by
//! their radii; rigtwin's line has the gear stage in the coupling (twist q_pinion/r − q_load)
//! and the wheels' inertia reflected onto the pinion (J/r²), so the two are the same mechanics
//! written two ways.

mod common;

use std::path::Path;
use std::process::Command;

use serde_json::Value;

fn opentorsion(case: &str) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/opentorsion_modes.py");
    let out = Command::new(common::python()).arg(script).arg(case).output().unwrap();
    assert!(out.status.success(), "opentorsion_modes.py {case}: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

fn rigtwin_modal(dir: &Path, name: &str, model: &str) -> Value {
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, format!("kind = \"drive_model\"\ndomain = \"rotational\"\n{model}\n[[inputs]]\nbody = 1\n"))
        .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
        .args(["modal", "--params", file.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

/// Both tools' elastic natural frequencies agree to 1e-9 (two eigensolvers on the same matrices:
/// round-off, not modelling), and where there is damping each underdamped pole's damping ratio
/// to 1e-9 absolute.
fn compare(name: &str, model: &str) {
    let dir = common::scratch("modal", name);
    let ours = rigtwin_modal(&dir, name, model);
    let theirs = opentorsion(name);
    let f: Vec<f64> = floats(&ours["frequencies_hz"]).into_iter().filter(|f| *f > 0.0).collect();
    let g = floats(&theirs["frequencies_hz"]);
    assert_eq!(f.len(), g.len(), "{name}: {f:?} vs {g:?}");
    for (a, b) in f.iter().zip(&g) {
        assert!((a / b - 1.0).abs() < 1e-9, "{name}: {a} Hz vs openTorsion's {b} Hz");
    }
    let under: Vec<(f64, f64)> = ours["poles"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["damped_hz"].as_f64().unwrap() > 0.0)
        .map(|p| (p["natural_hz"].as_f64().unwrap(), p["damping_ratio"].as_f64().unwrap()))
        .collect();
    let theirs_under: Vec<(f64, f64)> = theirs["underdamped"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p["natural_hz"].as_f64().unwrap(), p["damping_ratio"].as_f64().unwrap()))
        .collect();
    assert_eq!(under.len(), theirs_under.len(), "{name}: {under:?} vs {theirs_under:?}");
    for ((n, z), (m, y)) in under.iter().zip(&theirs_under) {
        assert!((n / m - 1.0).abs() < 1e-9, "{name}: pole at {n} Hz vs {m} Hz");
        assert!((z - y).abs() < 1e-9, "{name}: damping ratio {z} vs {y}");
    }
    // every elastic mode is named, the rigid-body one as such
    let kinds: Vec<&str> = ours["mode_kinds"].as_array().unwrap().iter().map(|k| k.as_str().unwrap()).collect();
    assert_eq!(kinds[0], "rigid body", "{name}");
    assert!(kinds[1..].iter().all(|k| k.contains(" against ")), "{name}: {kinds:?}");
}

#[test]
fn a_five_disk_chain_has_opentorsions_modes() {
    compare(
        "chain5",
        "[model]\nbodies = [\n  { name = \"d1\", inertia = 100.0 },\n  { name = \"d2\", inertia = 10.0 },\n  \
         { name = \"d3\", inertia = 50.0 },\n  { name = \"d4\", inertia = 10.0 },\n  { name = \"d5\", inertia = 80.0 },\n]\n\
         couplings = [\n  { stiffness = 25e6 },\n  { stiffness = 25e6 },\n  { stiffness = 25e6 },\n  { stiffness = 25e6 },\n]\n",
    );
}

#[test]
fn a_damped_geared_chain_has_opentorsions_modes_and_damping() {
    // the wheel (0.002 kg m², ratio 3) reflected onto the pinion: 0.001 + 0.002/9
    let hub = 0.001 + 0.002 / 9.0;
    compare(
        "geared_damped",
        &format!(
            "[model]\nbodies = [\n  {{ name = \"motor\", inertia = 0.004, drag = 0.02 }},\n  {{ name = \"pinion\", inertia = {hub:?} }},\n  \
             {{ name = \"load\", inertia = 0.06, drag = 0.3 }},\n]\ncouplings = [\n  {{ stiffness = 800.0, damping = 0.5 }},\n  \
             {{ stiffness = 15000.0, damping = 2.0, ratio = 3.0 }},\n]\n"
        ),
    );
}

/// The damped geared chain with a compliance inside its motor, declared as the effect a model
/// file names (`effect = "compliance"`): rigtwin splits the motor into its rotor and the rest
/// with the spring between them; openTorsion is given the five disks, spring and damper by hand.
#[test]
fn a_compliance_inside_the_motor_has_opentorsions_modes_and_damping() {
    let hub = 0.001 + 0.002 / 9.0;
    compare(
        "compliant_motor",
        &format!(
            "[model]\nbodies = [\n  {{ name = \"motor\", inertia = 0.004, drag = 0.02 }},\n  {{ name = \"pinion\", inertia = {hub:?} }},\n  \
             {{ name = \"load\", inertia = 0.06, drag = 0.3 }},\n]\ncouplings = [\n  {{ stiffness = 800.0, damping = 0.5 }},\n  \
             {{ stiffness = 15000.0, damping = 2.0, ratio = 3.0 }},\n]\n\
             [[effects]]\neffect = \"compliance\"\nbody = 1\nstiffness = 300.0\nmotor_share = 0.4\n"
        ),
    );
}

#[test]
fn a_branched_gearbox_has_opentorsions_modes() {
    // the two wheels (ratio 2 and 4) reflected onto the pinion; each wheel's shaft twists by
    // q_pinion/r − q_load (an elongation over the pinion and its load)
    let hub = 0.002 + 0.003 / 4.0 + 0.008 / 16.0;
    compare(
        "branched",
        &format!(
            "[model]\nbodies = [\n  {{ name = \"motor\", inertia = 0.01 }},\n  {{ name = \"pinion\", inertia = {hub:?} }},\n  \
             {{ name = \"load_a\", inertia = 0.05 }},\n  {{ name = \"load_b\", inertia = 0.4 }},\n]\ncouplings = [\n  \
             {{ stiffness = 2000.0 }},\n  {{ name = \"shaft_a\", stiffness = 9000.0, elongation = [0.0, 0.5, -1.0, 0.0] }},\n  \
             {{ name = \"shaft_b\", stiffness = 30000.0, elongation = [0.0, 0.25, 0.0, -1.0] }},\n]\n"
        ),
    );
}

/// Issue 31, item 2: the same branched gearbox drawn as engineers draw it — the pinion and both
/// wheels bodies with their own inertia, each mesh a coupling `between` the two gears with its
/// ratio, no reduction by hand. The meshes are stiff springs (1e10 N m/rad at the wheel) where
/// openTorsion ties the gears rigidly: the three elastic modes openTorsion has are rigtwin's
/// lowest three to 1e-4 (the mesh compliance in series with the shafts' shifts them by about
/// k_shaft/(2 k_mesh r²) ≤ 2e-6; the bound leaves room for that estimate), and the two modes
/// above are the meshes' own, far beyond (above 10 kHz).
#[test]
fn a_branched_gearbox_drawn_with_its_gears_has_opentorsions_modes() {
    let dir = common::scratch("modal", "branched_gears");
    let model =
        "[model]\nbodies = [\n  { name = \"motor\", inertia = 0.01 },\n  { name = \"pinion\", inertia = 0.002 },\n  \
        { name = \"wheel_a\", inertia = 0.003 },\n  { name = \"load_a\", inertia = 0.05 },\n  \
        { name = \"wheel_b\", inertia = 0.008 },\n  { name = \"load_b\", inertia = 0.4 },\n]\ncouplings = [\n  \
        { name = \"input_shaft\", between = [\"motor\", \"pinion\"], stiffness = 2000.0 },\n  \
        { name = \"mesh_a\", between = [\"pinion\", \"wheel_a\"], ratio = 2.0, stiffness = 1e10 },\n  \
        { name = \"shaft_a\", between = [\"wheel_a\", \"load_a\"], stiffness = 9000.0 },\n  \
        { name = \"mesh_b\", between = [\"pinion\", \"wheel_b\"], ratio = 4.0, stiffness = 1e10 },\n  \
        { name = \"shaft_b\", between = [\"wheel_b\", \"load_b\"], stiffness = 30000.0 },\n]\n";
    let ours = rigtwin_modal(&dir, "branched_gears", model);
    let theirs = floats(&opentorsion("branched")["frequencies_hz"]);
    let f: Vec<f64> = floats(&ours["frequencies_hz"]).into_iter().filter(|f| *f > 0.0).collect();
    assert_eq!(f.len(), 5, "{f:?}");
    assert_eq!(theirs.len(), 3, "{theirs:?}");
    for (a, b) in f.iter().zip(&theirs) {
        assert!((a / b - 1.0).abs() < 1e-4, "{a} Hz vs openTorsion's {b} Hz");
    }
    assert!(f[3] > 1e4 && f[4] > 1e4, "the meshes' own modes: {f:?}");
}
