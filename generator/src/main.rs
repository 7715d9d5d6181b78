//! `scatter-gen`: emits the kernels of one or more variants as WGSL, GLSL, SPIR-V (HLSL,
//! MSL) plus `manifest.json` and the uniform structs as C and Rust. `--help` lists the
//! knobs; `scatter-gen list` the families, kernels, knobs and targets.
//!
//! Exit codes: 0 success; 1 `--check` found stale files, or the run failed (a file it may
//! not overwrite, an I/O error, a back-end error); 2 bad input (a knob, the command line,
//! the config file). Errors are one line on stderr; nothing is written on bad input.

use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Arg, ArgMatches, Args, Command, FromArgMatches, Parser, Subcommand};
use scatter_gen::family::KnobInfo;
use scatter_gen::{Family, FamilyCli, GenError, Request, Target, generate, output};

/// Every knob of every family, deduplicated by name: the default family (`prefiltered`)
/// first, whose help text and default win; a family that allows other values adds them
/// (`directional | spot; area_ivsv: area`).
fn all_knobs() -> Vec<(KnobInfo, Vec<Family>)> {
    let mut out: Vec<(KnobInfo, Vec<Family>)> = Vec::new();
    let first = Family::Prefiltered;
    let order = std::iter::once(first).chain(Family::ALL.iter().copied().filter(|&f| f != first));
    for f in order {
        for k in f.knobs() {
            match out.iter_mut().find(|(e, _)| e.name == k.name) {
                Some((e, families)) => {
                    if !e.allowed.split("; ").any(|a| a == k.allowed) {
                        e.allowed = format!("{}; {f}: {}", e.allowed, k.allowed);
                    }
                    families.push(f);
                }
                None => out.push((k, vec![f])),
            }
        }
    }
    out
}

/// The knob flags, built from the family registry so a new family's knobs appear without
/// touching the CLI. Values are kept as text and validated by the family, so a bad value
/// gets the variant's own one-line message.
#[derive(Clone, Debug, Default)]
struct KnobArgs {
    /// `(knob, value)` in registry order.
    values: Vec<(String, String)>,
}

impl FromArgMatches for KnobArgs {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let mut values = Vec::new();
        for (k, _) in all_knobs() {
            if let Some(v) = matches.get_one::<String>(k.name) {
                values.push((k.name.to_owned(), v.clone()));
            }
        }
        Ok(Self { values })
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(matches)?;
        Ok(())
    }
}

impl Args for KnobArgs {
    fn augment_args(mut cmd: Command) -> Command {
        for (k, families) in all_knobs() {
            let families: Vec<_> = families.iter().map(|f| f.name()).collect();
            cmd = cmd.arg(
                Arg::new(k.name)
                    .long(&*Box::leak(k.flag().into_boxed_str()))
                    .value_name(k.value_name)
                    .help(format!(
                        "{}: {} [default (paper): {}] [family: {}]",
                        capitalise(k.help),
                        k.allowed,
                        k.default,
                        families.join(", ")
                    ))
                    .help_heading("Knobs")
                    .conflicts_with("config"),
            );
        }
        cmd
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    c.next()
        .map(|f| f.to_uppercase().collect::<String>() + c.as_str())
        .unwrap_or_default()
}

/// Generates drop-in volumetric-scattering shaders (Klehm et al. 2014 and other families)
/// for one variant or a config file of variants: one file per kernel and target, each
/// validated by naga, plus manifest.json (bindings, struct layouts, resources, pass order,
/// dispatch formulas, hashes) and the uniform structs as a C header and a Rust module.
#[derive(Debug, Parser)]
#[command(
    name = "scatter-gen",
    version,
    args_conflicts_with_subcommands = true,
    after_help = "Examples:\n  scatter-gen --bases 32 --regions 3 --out shaders/\n  \
                  scatter-gen --config variants.toml --target wgsl,spirv --out shaders/\n  \
                  scatter-gen --config variants.toml --out shaders/ --check\n\n\
                  Exit codes: 0 ok; 1 --check found stale files or the run failed; 2 bad input."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Cmd>,
    #[command(flatten)]
    args: GenArgs,
}

#[derive(Debug, Subcommand)]
enum Cmd {
    /// Lists the families, their kernels (in pass order), knobs with allowed values and
    /// defaults, and the targets.
    List,
}

#[derive(Debug, clap::Args)]
struct GenArgs {
    /// Kernel family [default: prefiltered] (`scatter-gen list` shows them).
    #[arg(long, value_name = "NAME", conflicts_with = "config")]
    family: Option<String>,
    #[command(flatten)]
    knobs: KnobArgs,
    /// Output languages, comma-separated: wgsl, glsl, spirv, hlsl, msl [default:
    /// wgsl,glsl,spirv].
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    target: Vec<String>,
    /// TOML file listing the variants to emit ([[variant]] tables of knobs, optional
    /// `targets`); emits exactly those.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Write nothing: compare DIR with what would be generated; exit 1 naming the stale
    /// files.
    #[arg(long)]
    check: bool,
    /// Overwrite files in DIR that scatter-gen did not write (not in its manifest.json).
    #[arg(long, conflicts_with = "check")]
    force: bool,
}

fn list() -> String {
    let mut s = format!(
        "scatter-gen {}: families, kernels, knobs and targets\n",
        env!("CARGO_PKG_VERSION")
    );
    for &f in Family::ALL {
        s.push_str(&format!("\nfamily {f}: {}\n", f.summary()));
        let kernels: Vec<_> = f.kernels().iter().map(|k| k.name()).collect();
        s.push_str(&format!("  kernels (pass order): {}\n", kernels.join(", ")));
        s.push_str("  knobs:\n");
        for k in f.knobs() {
            s.push_str(&format!(
                "    --{:<18} {:<38} default {:<12} {}\n",
                k.flag(),
                k.allowed,
                k.default,
                k.help
            ));
        }
    }
    s.push_str("\ntargets:\n");
    for &t in Target::ALL {
        let default = if Target::DEFAULT.contains(&t) {
            " (default)"
        } else {
            ""
        };
        s.push_str(&format!(
            "  {:<6} .{:<6} {}{default}\n",
            t.name(),
            t.extension(),
            t.description()
        ));
    }
    s.push_str(
        "\nfiles: <kernel>.<variant-id>.<ext> per kernel and target, manifest.json, \
         scatter_uniforms.h, scatter_uniforms.rs\n",
    );
    s
}

/// Runs one generation; `Ok(true)` when `--check` found the directory up to date (or
/// after a write), `Ok(false)` when it found stale files.
fn run(args: GenArgs) -> Result<bool, GenError> {
    let out = args.out.ok_or_else(|| {
        GenError::Usage("--out DIR is required (or run `scatter-gen list`)".into())
    })?;
    let cli_targets = if args.target.is_empty() {
        None
    } else {
        Some(Target::parse_list(&args.target)?)
    };
    let (variants, config_targets) = match &args.config {
        Some(path) => {
            let c = scatter_gen::config::load(path)?;
            (c.variants, c.targets)
        }
        None => {
            let family: Family = args.family.as_deref().unwrap_or("prefiltered").parse()?;
            (vec![family.variant(&args.knobs.values)?], None)
        }
    };
    let targets = cli_targets
        .or(config_targets)
        .unwrap_or_else(|| Target::DEFAULT.to_vec());
    let generated = generate(&Request { variants, targets })?;
    if args.check {
        let stale = output::check(&out, &generated)?;
        if stale.is_empty() {
            println!(
                "{}: up to date ({} files)",
                out.display(),
                generated.files.len() + 1
            );
            return Ok(true);
        }
        let mut stdout = std::io::stdout().lock();
        for s in &stale {
            let _ = writeln!(
                stdout,
                "stale: {} ({})",
                output::display_path(&out, &s.path).display(),
                s.why
            );
        }
        return Ok(false);
    }
    let report = output::write(&out, &generated, args.force)?;
    println!(
        "{}: {} written, {} unchanged, {} removed",
        out.display(),
        report.written.len(),
        report.unchanged.len(),
        report.removed.len()
    );
    Ok(true)
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                e.exit();
            }
            // clap's report is several lines (usage, tips); keep the one that says what
            // is wrong.
            let text = e.to_string();
            let line = text
                .lines()
                .find(|l| !l.trim().is_empty())
                .unwrap_or("error: invalid command line");
            eprintln!("{line}");
            return ExitCode::from(2);
        }
    };
    if let Some(Cmd::List) = cli.command {
        print!("{}", list());
        return ExitCode::SUCCESS;
    }
    match run(cli.args) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            let text = e.to_string();
            eprintln!("error: {}", text.trim_end());
            ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(1))
        }
    }
}
