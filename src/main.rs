//! rigtwin — turn a test rig into a model that others can run.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

use plant::{paper, Rig, Variant};
use rigtwin::report::{self, ModelKind};
use rigtwin::rigfile::load_rig;

#[derive(Parser)]
#[command(
    name = "rigtwin",
    version,
    about = "Torsional models of powertrain HIL rigs, after Hübner & Prokop (Vehicles 2026)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Args)]
struct RigArgs {
    /// Rig description (TOML, see rigs/paper.toml); default: the paper's rig.
    #[arg(long, value_name = "FILE")]
    rig: Option<PathBuf>,
    /// Rig variant; default: the rig file's `variant`.
    #[arg(long, value_parser = parse_variant)]
    variant: Option<Variant>,
    /// Give the side shafts stiffness-proportional damping so that the open differential's
    /// shuffle mode has this damping ratio (the generic damping of section 4.3); replaces the
    /// rig's d_short and d_long.
    #[arg(long, value_name = "ZETA", allow_negative_numbers = true)]
    damping_ratio: Option<f64>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Subcommand)]
enum Command {
    /// The main job on a rig: modal summary of the full chain, its reduction, the three-mass
    /// variants and the open-differential model.
    Run {
        #[command(flatten)]
        rig: RigArgs,
    },
    /// Natural frequencies, mode shapes and the shuffle mode of one model.
    Modal {
        #[command(flatten)]
        rig: RigArgs,
        /// Which model.
        #[arg(long, value_enum, default_value_t = ModelKind::Differential)]
        model: ModelKind,
    },
    /// Reduce the full chain after Rivin/Di (section 2.2).
    Reduce {
        #[command(flatten)]
        rig: RigArgs,
        /// Number of masses to keep.
        #[arg(long, default_value_t = 3)]
        masses: usize,
    },
}

fn parse_variant(s: &str) -> Result<Variant, String> {
    s.parse().map_err(|e: plant::PlantError| e.to_string())
}

fn load(args: &RigArgs) -> anyhow::Result<(Rig, Variant)> {
    let mut rig = match &args.rig {
        Some(f) => load_rig(f)?,
        None => paper::rig(),
    };
    let variant = args.variant.unwrap_or(rig.variant);
    if let Some(zeta) = args.damping_ratio {
        rig.model =
            rig.model.with_shaft_damping_ratio(zeta, variant).map_err(|e| anyhow::anyhow!("--damping-ratio: {e}"))?;
    }
    Ok((rig, variant))
}

fn print_json<T: serde::Serialize>(v: &T) -> anyhow::Result<()> {
    println!("{}", serde_json::to_string_pretty(v)?);
    Ok(())
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Modal { rig, model } => {
            let (r, variant) = load(&rig)?;
            let rep = report::modal(&r, model, variant)?;
            if rig.json {
                print_json(&rep)?;
            } else {
                print!("{}", rep.human(12));
            }
        }
        Command::Reduce { rig, masses } => {
            let (r, variant) = load(&rig)?;
            let rep = report::reduction(&r, variant, masses)?;
            if rig.json {
                print_json(&rep)?;
            } else {
                print!("{}", rep.human());
            }
        }
        Command::Run { rig } => {
            let (r, variant) = load(&rig)?;
            let summary = report::summary(&r, variant)?;
            if rig.json {
                print_json(&summary)?;
            } else {
                print!("{}", summary.human());
            }
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
