//! rigtwin — turn a test rig into a model that others can run.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

use ident::{DesignSettings, ModelChoice, ParametriseSettings};
use modelfile::rig::load_rig;
use plant::{paper, Rig, Variant};
use rigtwin::files::{Outputs, Target};
use rigtwin::identification::{self, FrequencyMethod, Source};
use rigtwin::report::{self, ModelKind};

/// `print!` that does not panic when stdout is closed early (`rigtwin ... | head`): what
/// cannot be written is dropped, as with any command-line tool whose reader has gone.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stdout(), $($arg)*);
    }};
}

/// `println!` that does not panic when stdout is closed early.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

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
    /// The report as JSON: to standard output instead of the text (`--json` or `--json -`), or
    /// to FILE besides the text.
    #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
    json: Option<PathBuf>,
}

#[derive(Subcommand)]
enum Command {
    /// The main job on a rig: modal summary of the full chain, its reduction, the three-mass
    /// variants and the open-differential model; then its FMUs.
    Run {
        #[command(flatten)]
        rig: RigArgs,
        /// Folder the FMUs are written to.
        #[arg(long, value_name = "DIR", default_value = "out")]
        out: PathBuf,
    },
    /// Natural frequencies, damping ratios, mode shapes and each mode's kind: of the rig (its
    /// chain, reduction or open differential) or of any drive model (`--params`).
    Modal {
        #[command(flatten)]
        rig: RigArgs,
        /// Which model of the rig.
        #[arg(long, value_enum, default_value_t = ModelKind::Differential)]
        model: ModelKind,
        /// Any model instead of the rig: a rig file, a drive model (`diagnose --write-model`) or
        /// a `drive_test` bundle's declared model.
        #[arg(long, value_name = "FILE", conflicts_with = "rig")]
        params: Option<PathBuf>,
        /// Draw the mode shapes as SVG.
        #[arg(long, value_name = "FILE.svg")]
        plot: Option<PathBuf>,
    },
    /// Reduce the full chain after Rivin/Di (section 2.2).
    Reduce {
        #[command(flatten)]
        rig: RigArgs,
        /// Number of masses to keep.
        #[arg(long, default_value_t = 3, allow_negative_numbers = true, value_parser = |s: &str| count_in(s, 2, 1000))]
        masses: usize,
    },
    /// Drive inertia and side-shaft stiffness from the natural frequencies of two or more rig
    /// variants (sections 2.3, 3), with 95 % intervals.
    Parametrise {
        /// torsional_sweep bundles, one per variant run.
        #[arg(value_name = "BUNDLE.toml")]
        bundles: Vec<PathBuf>,
        /// Frequencies instead of bundles, e.g. `--measured V1=12.77 --measured V2=12.62`.
        #[arg(long, value_name = "VARIANT=HZ", value_parser = parse_measured)]
        measured: Vec<(Variant, f64)>,
        /// Rig supplying the known parameters with --measured (default: the paper's).
        #[arg(long, value_name = "FILE")]
        rig: Option<PathBuf>,
        /// Standard uncertainty of every frequency, Hz; with --measured default 0.005
        /// (half the last digit of two-decimal values); with bundles it replaces the estimate.
        #[arg(long, value_name = "HZ", allow_negative_numbers = true, value_parser = positive)]
        sigma_hz: Option<f64>,
        /// Model the frequencies are explained with.
        #[arg(long, value_enum, default_value_t = ModelArg::Differential)]
        model: ModelArg,
        /// Which sweep estimate to use.
        #[arg(long, value_enum, default_value_t = FrequencyMethod::ModalFit)]
        method: FrequencyMethod,
        /// Monte Carlo draws for the intervals (0: linearised only).
        #[arg(long, default_value_t = 2000, allow_negative_numbers = true, value_parser = |s: &str| count_in(s, 0, ident::MAX_MONTE_CARLO_SAMPLES))]
        samples: usize,
        /// The report as JSON: to standard output instead of the text (`--json` or `--json -`),
        /// or to FILE besides the text.
        #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
        json: Option<PathBuf>,
    },
    /// Bearing/seal K, C, M from a two-test shake bundle (San Andrés 2011).
    Bearing {
        /// bearing_shake bundle.
        #[arg(value_name = "BUNDLE.toml")]
        bundle: PathBuf,
        /// Element structure; default: the bundle's declared one.
        #[arg(long, value_enum)]
        structure: Option<StructureArg>,
        /// Coupling; default: the bundle's declared one.
        #[arg(long, value_enum)]
        coupling: Option<CouplingArg>,
        /// Estimator.
        #[arg(long, value_enum, default_value_t = MethodArg::Ivfm)]
        method: MethodArg,
        /// Write measured and fitted impedances as SVG.
        #[arg(long, value_name = "FILE.svg")]
        plot: Option<PathBuf>,
        /// The report as JSON: to standard output instead of the text (`--json` or `--json -`),
        /// or to FILE besides the text.
        #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
        json: Option<PathBuf>,
    },
    /// Write the FMUs (FMI 3.0 and FMI 2.0, co-simulation and model exchange).
    Fmu {
        /// Parameter set: a rig file (its [model], variant and optional [bearing]), a
        /// drive_test bundle (its declared model) or a drive model written by `diagnose
        /// --write-model` (with its effects); default: the paper's V1/V2 powertrain with
        /// damping and the identified sfd_shake bearing.
        #[arg(long, value_name = "FILE")]
        params: Option<PathBuf>,
        /// Folder for rigtwin-fmi3.fmu and rigtwin-fmi2.fmu.
        #[arg(long, value_name = "DIR", default_value = "out")]
        out: PathBuf,
        /// Also write both modelDescription.xml files into this folder (e.g. modelDescription).
        #[arg(long, value_name = "DIR")]
        descriptions: Option<PathBuf>,
        /// Write the controller FMUs instead (rigtwin-mpc-fmi3.fmu, rigtwin-mpc-fmi2.fmu):
        /// `rigtwin mpc`'s controller of the model of --params (the rig with its [effects], or
        /// a drive model with its [mpc] section) as a co-simulation FMU stepping every 1 ms.
        #[arg(long)]
        controller: bool,
        /// The controller's prediction horizon, steps of 1 ms (with --controller).
        #[arg(long, default_value_t = 50, requires = "controller", allow_negative_numbers = true, value_parser = |s: &str| count_in(s, 1, mpc::MAX_HORIZON))]
        horizon: usize,
        /// The controller's number of move blocks, 0: every step free (with --controller).
        #[arg(long, default_value_t = 4, requires = "controller", allow_negative_numbers = true, value_parser = |s: &str| count_in(s, 0, mpc::MAX_HORIZON))]
        blocks: usize,
        /// With --controller: the plant of rigtwin-closed-loop.ssp (a model file with the
        /// signals the controller measures and commands); default: the model of --params.
        #[arg(long, value_name = "FILE", requires = "controller")]
        plant: Option<PathBuf>,
    },
    /// Model-predictive control of the rig (section 1.2) or of any drive model (`--params`):
    /// the closed loop with the MPC and with PI speed control after a drive-torque step or
    /// during a sweep; step time, allocations, first input against the exact optimum, shuffle
    /// overshoot and settling.
    Mpc {
        /// Prediction horizon, steps of 1 ms (10-100 in the real-time regime).
        #[arg(long, default_value_t = 50, allow_negative_numbers = true, value_parser = |s: &str| count_in(s, 1, mpc::MAX_HORIZON))]
        horizon: usize,
        /// What the rig is asked to do.
        #[arg(long, value_enum, default_value_t = ScenarioArg::Step)]
        scenario: ScenarioArg,
        /// Length of the timed run, s, at most 120 (default: 1 s step, 3.5 s sweep; the sweep's
        /// chirp spans the whole run; a drive model's reference step, 1 s). The rig's shuffle
        /// figures always come from its 1 s step.
        #[arg(long, value_name = "S", allow_negative_numbers = true, value_parser = positive)]
        duration: Option<f64>,
        /// Number of move blocks (1, 2, 4, … steps, the last taking the rest); 0: every step free.
        #[arg(long, default_value_t = 4, allow_negative_numbers = true, value_parser = |s: &str| count_in(s, 0, mpc::MAX_HORIZON))]
        blocks: usize,
        /// QP formulation.
        #[arg(long, value_enum, default_value_t = FormulationArg::Condensed)]
        formulation: FormulationArg,
        /// The model the controller is designed on (a rig file, as for `rigtwin fmu --params`,
        /// with its `[effects]`); default: the embedded rig.
        #[arg(long, value_name = "FILE")]
        params: Option<PathBuf>,
        /// The plant the loop is closed on, integrated as the FMU integrates it (a rig file with
        /// its `[effects]`); default: the model of `--params`.
        #[arg(long, value_name = "FILE")]
        plant: Option<PathBuf>,
        /// Wall-clock limit of one QP solve, µs; past it the shifted previous plan is applied.
        #[arg(long, default_value_t = 600.0, allow_negative_numbers = true, value_parser = positive)]
        time_limit_us: f64,
        /// The report as JSON: to standard output instead of the text (`--json` or `--json -`),
        /// or to FILE besides the text.
        #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
        json: Option<PathBuf>,
        /// Write side-shaft torque, load speed and machine torques over time as SVG.
        #[arg(long, value_name = "FILE.svg")]
        plot: Option<PathBuf>,
        /// Write the QPs of the checked steps as JSON for scripts/qp_compare.py (OSQP, DAQP).
        #[arg(long, value_name = "FILE.json")]
        export_qp: Option<PathBuf>,
    },
    /// Close the loop with measured data: the declared model's residual, the effects it lacks,
    /// the extended model, the error before and after, and a verdict (torsional_sweep,
    /// drive_test or bearing_shake; exit 3 where the record is not explained).
    Diagnose {
        /// The measurement bundle.
        #[arg(value_name = "BUNDLE.toml")]
        bundle: PathBuf,
        /// The report as JSON: to standard output instead of the text (`--json` or `--json -`),
        /// or to FILE besides the text.
        #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
        json: Option<PathBuf>,
        /// Write measured vs model (before and after) and the residual spectrum as SVG.
        #[arg(long, value_name = "FILE.svg")]
        plot: Option<PathBuf>,
        /// Write the extended model as a rig file (`rigtwin fmu --params` takes it).
        #[arg(long, value_name = "FILE.toml")]
        write_model: Option<PathBuf>,
        /// Write the measured outputs, the declared and the extended model's outputs and the
        /// residuals on one base as CSV (a sweep: time and both speeds, high-passed as the error
        /// is; a shake test: the four impedances per excited line).
        #[arg(long, value_name = "FILE.csv")]
        save_signals: Option<PathBuf>,
        /// A drive_test record: search a compliance inside every body as well (a machine's
        /// rotor on a soft shaft, a rubber coupling): not in the default search yet, see
        /// docs/diagnosis.md.
        #[arg(long)]
        search_compliance: bool,
    },
    /// Read and validate a bundle as a diagnosis would: its samples, sample time, signals and
    /// the unit conversions applied.
    Check {
        /// The measurement bundle.
        #[arg(value_name = "BUNDLE.toml")]
        bundle: PathBuf,
    },
    /// Which additional spring and variants make j_drive and c_short identifiable.
    DesignSpring {
        /// Rig description (default: the paper's); its j_drive and c_short are the expected values.
        #[arg(long, value_name = "FILE")]
        rig: Option<PathBuf>,
        /// Standard uncertainty of each measured frequency, Hz.
        #[arg(long, default_value_t = 0.05, allow_negative_numbers = true, value_parser = positive)]
        sigma_hz: f64,
        /// Required relative 95 % half-width of both parameters.
        #[arg(long, default_value_t = 0.05, allow_negative_numbers = true, value_parser = positive)]
        target: f64,
        /// Model.
        #[arg(long, value_enum, default_value_t = ModelArg::Differential)]
        model: ModelArg,
        /// The report as JSON: to standard output instead of the text (`--json` or `--json -`),
        /// or to FILE besides the text.
        #[arg(long, value_name = "FILE|-", num_args = 0..=1, default_missing_value = "-")]
        json: Option<PathBuf>,
    },
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum ScenarioArg {
    Step,
    Sweep,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum FormulationArg {
    Condensed,
    Sparse,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum StructureArg {
    #[value(name = "KC")]
    Kc,
    #[value(name = "KCM")]
    Kcm,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum CouplingArg {
    Direct,
    Full,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum MethodArg {
    Ivfm,
    Direct,
    LeastSquares,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum ModelArg {
    Differential,
    Smooth,
}

impl From<ModelArg> for ModelChoice {
    fn from(m: ModelArg) -> Self {
        match m {
            ModelArg::Differential => ModelChoice::Differential,
            ModelArg::Smooth => ModelChoice::Smooth,
        }
    }
}

fn parse_measured(s: &str) -> Result<(Variant, f64), String> {
    let (v, f) = s.split_once('=').ok_or_else(|| format!("`{s}`: expected VARIANT=HZ, e.g. V1=12.77"))?;
    let variant = parse_variant(v)?;
    let hz: f64 = f.trim().parse().map_err(|_| format!("`{f}`: expected a frequency in Hz"))?;
    if !(hz > 0.0 && hz.is_finite()) {
        return Err(format!("`{f}`: a frequency must be positive"));
    }
    Ok((variant, hz))
}

/// A whole number in `lo..=hi` (clap names the flag in its message).
fn count_in(s: &str, lo: usize, hi: usize) -> Result<usize, String> {
    let n: i128 = s.trim().parse().map_err(|_| format!("expected a whole number from {lo} to {hi}"))?;
    match usize::try_from(n) {
        Ok(n) if (lo..=hi).contains(&n) => Ok(n),
        _ => Err(format!("{n} is out of range: expected a whole number from {lo} to {hi}")),
    }
}

/// A positive, finite number.
fn positive(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| "expected a positive number".to_string())?;
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{v} is out of range: expected a positive, finite number"))
    }
}

fn parse_variant(s: &str) -> Result<Variant, String> {
    s.parse().map_err(|e: plant::PlantError| e.to_string())
}

fn load(args: &RigArgs) -> anyhow::Result<(Rig, Variant)> {
    let rig = match &args.rig {
        Some(f) => load_rig(f)?,
        None => paper::rig(),
    };
    configure(rig, args)
}

/// `rig` in the variant and with the shaft damping the command line gives.
fn configure(mut rig: Rig, args: &RigArgs) -> anyhow::Result<(Rig, Variant)> {
    let variant = args.variant.unwrap_or(rig.variant);
    if let Some(zeta) = args.damping_ratio {
        rig.model =
            rig.model.with_shaft_damping_ratio(zeta, variant).map_err(|e| anyhow::anyhow!("--damping-ratio: {e}"))?;
    }
    Ok((rig, variant))
}

/// A command's report: the text to standard output unless the JSON goes there, the JSON to its
/// checked target (see `rigtwin::report::json_document` for its one convention).
fn emit<T: serde::Serialize>(json: Option<&Target>, value: &T, text: &str) -> anyhow::Result<()> {
    if json != Some(&Target::Stdout) {
        out!("{text}");
    }
    if let Some(target) = json {
        rigtwin::files::write(target, rigtwin::report::json_document(value)?.as_bytes())?;
    }
    Ok(())
}

/// The checked target of `--json` for a command reading `inputs`.
fn json_target(json: &Option<PathBuf>, inputs: Vec<PathBuf>) -> anyhow::Result<Option<Target>> {
    json.as_ref().map(|f| Outputs::new(&inputs).file(f, "--json")).transpose()
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Modal { rig, model, params, plot } => {
            let inputs: Vec<PathBuf> =
                rig.rig.iter().chain(&params).flat_map(|f| rigtwin::bundle::input_files(f)).collect();
            let mut outs = Outputs::new(&inputs);
            let json = rig.json.as_ref().map(|f| outs.file(f, "--json")).transpose()?;
            let plot = plot.map(|f| outs.svg(&f, "--plot")).transpose()?;
            // --params read once: a drive model, or a rig file that is the rig
            let file = params.as_ref().map(|f| modelfile::read(f).map(|m| (f, m.model))).transpose()?;
            match file {
                Some((f, modelfile::Model::Drive(m))) => {
                    let rep = report::modal_of_line(&f.display().to_string(), &m)?;
                    if let Some(t) = &plot {
                        rep.plot(t)?;
                    }
                    emit(json.as_ref(), &rep, &rep.human())?;
                }
                file => {
                    let (r, variant) = match file {
                        Some((_, modelfile::Model::Rig(r))) => configure(*r, &rig)?,
                        _ => load(&rig)?,
                    };
                    let rep = report::modal(&r, model, variant)?;
                    if let Some(t) = &plot {
                        rep.plot(t)?;
                    }
                    emit(json.as_ref(), &rep, &rep.human(12))?;
                }
            }
        }
        Command::Reduce { rig, masses } => {
            let json = json_target(&rig.json, rig.rig.iter().cloned().collect())?;
            let (r, variant) = load(&rig)?;
            let rep = report::reduction(&r, variant, masses)?;
            emit(json.as_ref(), &rep, &rep.human())?;
        }
        Command::Parametrise { bundles, measured, rig, sigma_hz, model, method, samples, json } => {
            let inputs = bundles.iter().chain(&rig).flat_map(|f| rigtwin::bundle::input_files(f)).collect();
            let json = json_target(&json, inputs)?;
            let source = match (bundles.is_empty(), measured.is_empty()) {
                (false, true) => Source::Bundles(bundles),
                (true, false) => Source::Measured {
                    rig: Box::new(match &rig {
                        Some(f) => load_rig(f)?,
                        None => paper::rig(),
                    }),
                    values: measured,
                    sigma_hz: sigma_hz.unwrap_or(0.005),
                },
                (true, true) => anyhow::bail!("give torsional_sweep bundles, or frequencies with --measured"),
                (false, false) => anyhow::bail!("give either bundles or --measured frequencies, not both"),
            };
            let settings = ParametriseSettings { monte_carlo_samples: samples, ..Default::default() };
            let busy = rigtwin::progress::Progress::start("parametrising");
            let rep = identification::parametrise(source, model.into(), method, sigma_hz, &settings)?;
            drop(busy);
            emit(json.as_ref(), &rep, &rep.human())?;
        }
        Command::Bearing { bundle, structure, coupling, method, plot, json } => {
            let mut outs = Outputs::new(&rigtwin::bundle::input_files(&bundle));
            let plot = plot.map(|p| outs.svg(&p, "--plot")).transpose()?;
            let json = json.map(|f| outs.file(&f, "--json")).transpose()?;
            let b = rigtwin::bundle::load_bearing(&bundle)?;
            let structure = structure.map(|s| match s {
                StructureArg::Kc => ident::Structure::KC,
                StructureArg::Kcm => ident::Structure::KCM,
            });
            let coupling = coupling.map(|c| match c {
                CouplingArg::Direct => ident::Coupling::Direct,
                CouplingArg::Full => ident::Coupling::Full,
            });
            let method = match method {
                MethodArg::Ivfm => ident::Method::Ivfm,
                MethodArg::Direct => ident::Method::Direct,
                MethodArg::LeastSquares => ident::Method::LeastSquares,
            };
            let busy = rigtwin::progress::Progress::start(&format!("identifying {}", bundle.display()));
            let (rep, imp) = rigtwin::bearing::identify(&b, structure, coupling, method)?;
            drop(busy);
            if let Some(p) = &plot {
                let title = format!(
                    "{} — {} {}/{}",
                    bundle.display(),
                    rigtwin::report::words(&rep.method),
                    rigtwin::report::words(&rep.structure),
                    rigtwin::report::words(&rep.coupling)
                );
                rigtwin::bearing::plot(p, &imp, &b.support, &rep.element, &title)?;
            }
            emit(json.as_ref(), &rep, &rep.human())?;
        }
        Command::Fmu { params, out, descriptions, controller, horizon, blocks, plant } => {
            let (mut p, section) = match &params {
                Some(f) => {
                    let (file, note) = rigtwin::control::read_model(f)?;
                    if let (Some(note), true) = (note, controller) {
                        eprintln!("{note}");
                    }
                    (rigtwin::fmu_package::params_of_model(&file.model)?, file.mpc)
                }
                None => (rigtwin_fmu::FmuParams::default(), mpc::MpcSection::default()),
            };
            if controller {
                let spec = rigtwin_fmu::ControllerSpec::of_model(&p, &section, horizon, blocks);
                let named = || params.as_ref().map_or("the embedded rig".into(), |f| f.display().to_string());
                p.controller = Some(spec.map_err(|e| anyhow::anyhow!("--controller: {}: {e}", named()))?);
            }
            // the closed loop's plant is checked before anything is written
            let plant_params = match (&plant, controller) {
                (Some(f), _) => Some(rigtwin::fmu_package::params_of_file(f)?),
                (None, true) => Some(rigtwin_fmu::FmuParams { controller: None, ..p.clone() }),
                (None, false) => None,
            };
            if let Some(pl) = &plant_params {
                rigtwin_fmu::check(pl).map_err(|e| anyhow::anyhow!("--plant: {e}"))?;
                rigtwin::fmu_package::loop_connections(pl, &p).map_err(|e| anyhow::anyhow!("--plant: {e}"))?;
            }
            rigtwin_fmu::check(&p).map_err(|e| anyhow::anyhow!("the parameter set does not describe a model: {e}"))?;
            // every output is checked before the first is written; none may be an input
            let inputs: Vec<PathBuf> =
                params.iter().chain(&plant).flat_map(|f| rigtwin::bundle::input_files(f)).collect();
            let mut outs = Outputs::new(&inputs);
            let fmus = outs.in_folder(&out, "--out", rigtwin::fmu_package::fmu_names(controller))?;
            let ssp = match plant_params {
                Some(_) => Some(outs.in_folder(&out, "--out", [rigtwin::fmu_package::SSP_NAME])?),
                None => None,
            };
            let described =
                descriptions.map(|d| rigtwin::fmu_package::description_targets(&mut outs, &d)).transpose()?;
            let lib = rigtwin::fmu_package::library()?;
            if let Some(targets) = &described {
                rigtwin::fmu_package::write_descriptions(&p, targets)?;
            }
            rigtwin::fmu_package::package(&p, &lib, &fmus)?;
            let [a, b] = rigtwin::fmu_package::fmu_names(controller).map(|n| out.join(n));
            outln!("wrote {} and {} (token {})", a.display(), b.display(), rigtwin_fmu::token(&p));
            if let (Some(pl), Some([target])) = (&plant_params, &ssp) {
                rigtwin::fmu_package::closed_loop_ssp(pl, &p, &lib, target)?;
                outln!(
                    "wrote {} (the plant's and the controller's FMI 2 FMUs, connected)",
                    out.join(rigtwin::fmu_package::SSP_NAME).display()
                );
            }
        }
        Command::Mpc {
            horizon,
            scenario,
            duration,
            blocks,
            formulation,
            params,
            plant,
            time_limit_us,
            json,
            plot,
            export_qp,
        } => {
            // every output is checked before the loop runs; none may be an input
            let inputs: Vec<PathBuf> =
                params.iter().chain(&plant).flat_map(|f| rigtwin::bundle::input_files(f)).collect();
            let mut outs = Outputs::new(&inputs);
            let plot = plot.map(|f| outs.svg(&f, "--plot")).transpose()?;
            let export_qp = export_qp.map(|f| outs.file(&f, "--export-qp")).transpose()?;
            let json = json.map(|f| outs.file(&f, "--json")).transpose()?;
            let model_name = params.as_ref().map_or("the embedded rig".to_string(), |f| f.display().to_string());
            let (p, section) = match &params {
                Some(f) => {
                    let (file, note) = rigtwin::control::read_model(f)?;
                    if let Some(note) = note {
                        eprintln!("{note}");
                    }
                    (rigtwin::fmu_package::params_of_model(&file.model)?, file.mpc)
                }
                None => (rigtwin_fmu::FmuParams::default(), mpc::MpcSection::default()),
            };
            let tuning = rigtwin::control::Tuning {
                blocks,
                formulation: match formulation {
                    FormulationArg::Condensed => mpc::Formulation::Condensed,
                    FormulationArg::Sparse => mpc::Formulation::Sparse,
                },
                time_limit_s: time_limit_us * 1e-6,
            };
            let harness = mpc::closed_loop::HarnessSettings::DEFAULT;
            let allocations = Some(mpc::alloc_counter::allocations as fn() -> u64);
            let design = p.plant.design();
            let (prediction, mut settings) =
                design.controller(&section, horizon).map_err(|e| anyhow::anyhow!("{model_name}: {e}"))?;
            tuning.apply(&mut settings)?;
            let report = if let Some(model) = p.plant.drive() {
                // a drive model: its [mpc] section, a reference step from rest
                let truth = match &plant {
                    Some(f) => rigtwin::fmu_package::params_of_file(f)?.plant.drive().cloned().ok_or_else(|| {
                        anyhow::anyhow!("--plant {}: a rig file; --params is a drive model", f.display())
                    })?,
                    None => model.clone(),
                };
                if export_qp.is_some() {
                    anyhow::bail!(
                        "--export-qp: the QP export compares the paper rig's QPs with OSQP and DAQP; {model_name} is a drive model"
                    );
                }
                if matches!(scenario, ScenarioArg::Sweep) {
                    anyhow::bail!(
                        "--scenario sweep is the paper rig's run; {model_name} is a drive model, whose run is a step of its tracked speeds' references ({} rad/s or {} m/s at {} s, {} s long unless --duration says)",
                        harness.reference_step_radps,
                        harness.reference_step_mps,
                        harness.reference_step_at_s,
                        harness.drive_run_s
                    );
                }
                let harness = match duration {
                    Some(d) => harness.with_drive_run(d).map_err(|e| anyhow::anyhow!("--duration {d} s: {e}"))?,
                    None => harness,
                };
                let (report, run) =
                    mpc::evaluation::drive(model, &prediction, &truth, &settings, &harness, allocations)
                        .map_err(|e| anyhow::anyhow!("{model_name}: {e:#}"))?;
                if let Some(f) = &plot {
                    rigtwin::control::plot_drive(f, &run, model.line.domain)?;
                }
                report
            } else {
                let truth = match &plant {
                    Some(f) => {
                        let t = rigtwin::fmu_package::params_of_file(f)?;
                        if t.plant.drive().is_some() {
                            anyhow::bail!(
                                "--plant {}: a drive model; --params is the paper rig (give a rig file)",
                                f.display()
                            );
                        }
                        t
                    }
                    None => p.clone(),
                };
                let kind = match scenario {
                    ScenarioArg::Step => mpc::closed_loop::ScenarioKind::Step,
                    ScenarioArg::Sweep => mpc::closed_loop::ScenarioKind::Sweep,
                };
                let mut run = mpc::closed_loop::Scenario::new(kind);
                if let Some(d) = duration {
                    run = run.with_duration(d, &harness).map_err(|e| anyhow::anyhow!("--duration {d} s: {e}"))?;
                }
                let mut qps = Vec::new();
                let busy = rigtwin::progress::Progress::start("closing the loop (MPC and PI)");
                let (report, loops) = mpc::evaluation::rig(
                    &design,
                    &prediction,
                    &truth.plant.design(),
                    &settings,
                    &run,
                    &harness,
                    allocations,
                    export_qp.is_some().then_some(&mut qps),
                )?;
                drop(busy);
                if let Some(f) = &export_qp {
                    let text = serde_json::to_string(&serde_json::json!({ "qps": qps }))?;
                    rigtwin::files::write(f, text.as_bytes())?;
                }
                if let Some(f) = &plot {
                    rigtwin::control::plot(f, &prediction, &loops, kind)?;
                }
                report
            };
            emit(json.as_ref(), &report, &rigtwin::control::human(&report))?;
            if let Some(why) = report.invalid() {
                return Err(NotValid(format!("not valid: {why}")).into());
            }
        }
        Command::Diagnose { bundle, json, plot, write_model, save_signals, search_compliance } => {
            // every output is checked before the diagnosis starts, none may be an input
            let mut outs = Outputs::new(&rigtwin::bundle::input_files(&bundle));
            let json = json.map(|f| outs.file(&f, "--json")).transpose()?;
            let write_model = write_model.map(|f| outs.file(&f, "--write-model")).transpose()?;
            let plot = plot.map(|f| outs.svg(&f, "--plot")).transpose()?;
            let save_signals = save_signals.map(|f| outs.file(&f, "--save-signals")).transpose()?;
            let busy = rigtwin::progress::Progress::start(&format!("diagnosing {}", bundle.display()));
            let fitted = std::sync::atomic::AtomicUsize::new(0);
            let progress = |name: &str| {
                let n = fitted.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                busy.say(&format!("{n} fits done, last: {name}"));
            };
            let search = ident::diagnose::drive::SearchSettings { compliance: search_compliance };
            let d = rigtwin::diagnosis::diagnose(&bundle, &progress, &search)?;
            drop(busy);
            let explained = d.report.verdict != ident::diagnose::verdict::Verdict::NotExplained;
            match &write_model {
                // a model with a parameter beyond its bound is no model of the rig
                Some(_) if !explained => eprintln!("--write-model: not written, the record is not explained"),
                Some(f) => rigtwin::files::write(f, d.model_toml.as_bytes())?,
                None => {}
            }
            if let Some(f) = &save_signals {
                rigtwin::files::write(f, d.signals_csv().as_bytes())?;
            }
            if let Some(f) = &plot {
                rigtwin::plot::lines(f, &format!("rigtwin diagnose {}", bundle.display()), &d.panels)?;
            }
            emit(json.as_ref(), &d.report, &rigtwin::diagnosis::human(&d.report))?;
            if !explained {
                return Err(NotValid(format!("not explained: {}", d.report.verdict_reasons.join("; "))).into());
            }
        }
        Command::Check { bundle } => {
            out!("{}", rigtwin::bundle::summary(&bundle)?);
        }
        Command::DesignSpring { rig, sigma_hz, target, model, json } => {
            let json = json_target(&json, rig.iter().cloned().collect())?;
            let r = match &rig {
                Some(f) => load_rig(f)?,
                None => paper::rig(),
            };
            let settings = DesignSettings { sigma_hz, target, ..Default::default() };
            let rep = identification::design(&r, model.into(), &settings)?;
            emit(json.as_ref(), &rep, &rep.human())?;
        }
        Command::Run { rig, out } => {
            let (r, variant) = load(&rig)?;
            let summary = report::summary(&r, variant)?;
            // the FMUs of the same rig, in the variant asked for
            let params = rigtwin::fmu_package::params_of_rig(&Rig { variant, ..r.clone() })?;
            let mut outs = Outputs::new(&rig.rig.iter().cloned().collect::<Vec<_>>());
            let json = rig.json.as_ref().map(|f| outs.file(f, "--json")).transpose()?;
            let fmus = outs.in_folder(&out, "--out", rigtwin::fmu_package::fmu_names(false))?;
            let lib = rigtwin::fmu_package::library()?;
            rigtwin::fmu_package::package(&params, &lib, &fmus)?;
            let [a, b] = rigtwin::fmu_package::fmu_names(false).map(|n| out.join(n));
            let text = format!(
                "{}\n5. FMUs (FMI 3.0 and 2.0, co-simulation and model exchange)\n  {}\n  {}\n",
                summary.human(),
                a.display(),
                b.display()
            );
            emit(json.as_ref(), &summary, &text)?;
        }
    }
    Ok(())
}

/// A result that was computed and printed but is no answer (the MPC ran on its fallback, the
/// diagnosis did not explain the record): exit code [`EXIT_NOT_VALID`].
#[derive(Debug)]
struct NotValid(String);

impl std::fmt::Display for NotValid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for NotValid {}

/// Exit code of a run whose output says it is not a valid result (1: an error, nothing
/// computed; 2: the command line could not be parsed).
const EXIT_NOT_VALID: u8 = 3;

/// Counts heap allocations so that `rigtwin mpc` can report them per controller step.
#[global_allocator]
static ALLOCATOR: mpc::alloc_counter::Counting = mpc::alloc_counter::Counting;

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<NotValid>() => {
            eprintln!("{e:#}");
            ExitCode::from(EXIT_NOT_VALID)
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
