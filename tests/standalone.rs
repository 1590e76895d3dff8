//! The `rigtwin` binary is the product: copied alone into an empty folder it writes both FMUs,
//! with the stripped FMU library it carries, and `run` and `fmu` write the same parameter set.

mod common;

use std::io::Read;
use std::path::Path;
use std::process::Command;

fn scratch(name: &str) -> common::Scratch {
    common::scratch("standalone", name)
}

fn entry(fmu: &Path, name: &str) -> Vec<u8> {
    let mut zip = zip::ZipArchive::new(std::fs::File::open(fmu).unwrap()).unwrap();
    let mut e = zip.by_name(name).unwrap_or_else(|_| panic!("{}: no {name}", fmu.display()));
    let mut bytes = Vec::new();
    e.read_to_end(&mut bytes).unwrap();
    bytes
}

/// The section names of a little-endian ELF64 file (the header's section table and its
/// section-name string table).
fn elf_sections(b: &[u8]) -> Vec<String> {
    let u16_at = |o: usize| u16::from_le_bytes([b[o], b[o + 1]]) as usize;
    let u32_at = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap()) as usize;
    let u64_at = |o: usize| u64::from_le_bytes(b[o..o + 8].try_into().unwrap()) as usize;
    assert_eq!((b[4], b[5]), (2, 1), "ELF64, little-endian");
    let (shoff, shentsize, shnum, shstrndx) = (u64_at(0x28), u16_at(0x3a), u16_at(0x3c), u16_at(0x3e));
    let strtab = u64_at(shoff + shstrndx * shentsize + 0x18);
    (0..shnum)
        .map(|i| {
            let start = strtab + u32_at(shoff + i * shentsize);
            let end = start + b[start..].iter().position(|&c| c == 0).unwrap();
            String::from_utf8_lossy(&b[start..end]).into_owned()
        })
        .collect()
}

#[test]
fn a_binary_copied_alone_writes_both_fmus() {
    let dir = scratch("alone");
    let exe = dir.join("rigtwin");
    std::fs::copy(env!("CARGO_BIN_EXE_rigtwin"), &exe).unwrap();
    let out = Command::new(&exe)
        .args(["fmu", "--out", "fmus"])
        .current_dir(&dir)
        .env_remove("RIGTWIN_FMU_LIB")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let run = Command::new(&exe)
        .args(["run", "--out", "run"])
        .current_dir(&dir)
        .env_remove("RIGTWIN_FMU_LIB")
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    for (fmu, lib) in
        [("rigtwin-fmi3.fmu", "binaries/x86_64-linux/rigtwin.so"), ("rigtwin-fmi2.fmu", "binaries/linux64/rigtwin.so")]
    {
        if !cfg!(all(target_os = "linux", target_arch = "x86_64")) {
            continue;
        }
        let bytes = entry(&dir.join("fmus").join(fmu), lib);
        assert_eq!(&bytes[..4], b"\x7fELF", "{fmu}: {lib} is a shared library");
        // stripped: small, and no DWARF or symbol-table sections
        assert!(bytes.len() < 3 << 20, "{fmu}: the library has {} bytes", bytes.len());
        let sections = elf_sections(&bytes);
        assert!(sections.iter().any(|s| s == ".text"), "{fmu}: {sections:?}");
        assert!(!sections.iter().any(|s| s.starts_with(".debug") || s == ".symtab"), "{fmu}: {sections:?}");
        // the exported functions stay in the dynamic symbol table
        assert!(bytes.windows(11).any(|w| w == b"fmi3DoStep\0"), "{fmu}: fmi3DoStep is not exported");
        // one default parameter set: run and fmu write the same params.json, byte for byte
        let a = entry(&dir.join("fmus").join(fmu), "resources/params.json");
        let b = entry(&dir.join("run").join(fmu), "resources/params.json");
        assert_eq!(a, b, "{fmu}: params.json of `fmu` and `run` differ");
        let p: serde_json::Value = serde_json::from_slice(&a).unwrap();
        assert!(
            p["plant"]["paper_rig"]["powertrain"]["d_short"].as_f64().unwrap() > 0.0,
            "the default is the damped rig: {p}"
        );
    }
}

/// What `cargo build --release --workspace` compiles needs no bindgen, so no libclang: the FMI
/// headers' bindings are checked in (only the tests' fmi-sys generates them).
#[test]
fn the_products_build_needs_no_bindgen() {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args(["tree", "-e", "normal,build", "--workspace", "--prefix", "none", "--offline"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let tree = String::from_utf8_lossy(&out.stdout);
    assert!(tree.contains("nalgebra") && tree.contains("clarabel"), "the tree lists the dependencies:\n{tree}");
    for banned in ["bindgen", "clang-sys", "fmi-sys"] {
        assert!(!tree.contains(banned), "{banned} is built by the product:\n{tree}");
    }
}
