//! The `strike` command line: run, check, sweep, validate, bench, materials.

use clap::{Parser, Subcommand};
use miette::{miette, LabeledSpan, NamedSource, Report};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use strike::{case::Case, check, deck, ranks::Ranks, run, Error};

#[derive(Parser)]
#[command(
    name = "strike",
    version,
    about = "SPH for solid bodies under impact, with frictionless particle contact"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a case deck: snapshots, history, pictures and a summary in the output directory.
    Run {
        /// The case deck (TOML).
        case: PathBuf,
        /// Output directory (default: runs/<case name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Stop after this many steps (in all, a resumed run's earlier steps included).
        #[arg(long)]
        max_steps: Option<u64>,
        /// Go on from a checkpoint (`checkpoint.bin` in an earlier run's output directory,
        /// written with every snapshot and when a run stops); history and snapshots continue
        /// in the output directory.
        #[arg(long)]
        resume: Option<PathBuf>,
        /// Replace an earlier run's files in the output directory (its snapshots, history,
        /// pictures, summary and checkpoint; nothing else). Without it such a directory is
        /// refused.
        #[arg(long)]
        overwrite: bool,
    },
    /// Benchmark built-in cases (1 thread and all cores) and write bench.json.
    Bench {
        /// Fewer steps and a smaller large case (a smoke test).
        #[arg(long)]
        quick: bool,
        /// Where to write the JSON report.
        #[arg(long, default_value = "bench.json")]
        json: PathBuf,
        /// Run only these cases (repeatable): large, scaling, cubes_3d, cubes_3d_cn, cubes_3d_vm,
        /// cubes_3d_jc, sphere_plate, plates_2d.
        #[arg(long = "case", value_name = "NAME")]
        cases: Vec<String>,
    },
    /// List the library materials: every model, value and source.
    Materials {
        /// Only this material (a library name or alias).
        name: Option<String>,
    },
    /// Run a deck at many values of its numeric keys, or find a projectile's ballistic limit:
    /// a table (CSV) and plots of each run's outcome (residual velocity and mass behind the
    /// target, perforation, peak pressure, failed particles).
    Sweep {
        /// The case deck (TOML).
        case: PathBuf,
        /// A key and its values (repeatable; every combination runs): KEY=a,b,c or
        /// KEY=start:stop:count, the key by its path, e.g. body.sphere.velocity (a number for a
        /// vector sets its magnitude), body[1].spacing, materials.al.density.
        #[arg(long = "set", value_name = "KEY=VALUES")]
        set: Vec<String>,
        /// Find the impact speed at which this body (or its debris) perforates the target,
        /// between the speeds given by --speeds, to --tolerance.
        #[arg(long, value_name = "BODY")]
        ballistic_limit: Option<String>,
        /// The bracket for --ballistic-limit: LOW:HIGH (m/s); LOW must not perforate, HIGH must.
        #[arg(long, value_name = "LOW:HIGH")]
        speeds: Option<String>,
        /// Width of the final bracket (m/s).
        #[arg(long, default_value_t = 10.0)]
        tolerance: f64,
        /// The body whose residual velocity and mass are measured (default: the fastest).
        #[arg(long)]
        projectile: Option<String>,
        /// Runs at once (they share the threads).
        #[arg(long, default_value_t = 1)]
        jobs: usize,
        /// Worker threads in all (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Output directory (default: runs/<case name>_sweep or _ballistic).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Replace an earlier sweep's files in the output directory.
        #[arg(long)]
        overwrite: bool,
    },
    /// Run the verification cases against their references and write a report (Markdown with
    /// plots, and one self-contained HTML page); exit non-zero if any case fails.
    Validate {
        /// The README's resolutions (slower) instead of the coarse ones.
        #[arg(long)]
        fine: bool,
        /// Only these cases (repeatable): kernel, consistency, contact_direction, elastic_wave,
        /// hel, energy, planar_impact, bars, slow_bars, striker, sliding, incline, rubber_rings,
        /// hertz, planar_7kms, sphere_plate, crater, spall, shocked_strength, taylor,
        /// taylor_ofhc, taylor_walls.
        #[arg(long = "case", value_name = "NAME")]
        cases: Vec<String>,
        /// Output directory (default: runs/validate).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Scale every tolerance by this factor (e.g. 0.5: what passes at half the tolerance).
        #[arg(long, default_value_t = 1.0)]
        tolerance_factor: f64,
        /// Write the table into this README, between its `strike validate` markers.
        #[arg(long)]
        readme: Option<PathBuf>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Read and validate a deck without running it: particles, h, first time step, memory and
    /// run-time estimates, warnings.
    Check {
        /// The case deck (TOML).
        case: PathBuf,
    },
}

/// Print a line on stdout; a closed pipe (`strike bench | head`) is not an error.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write;
        let _ = writeln!(std::io::stdout().lock(), $($arg)*);
    }};
}

/// Exit status of a run stopped by SIGINT or SIGTERM (after its checkpoint): 128 + SIGINT,
/// the shell's convention.
const EXIT_INTERRUPTED: u8 = 130;

fn main() -> std::process::ExitCode {
    strike::machine::map_large_allocations();
    // MPI first (where started by a launcher): the other ranks only log warnings and errors.
    let _mpi = strike::ranks::start();
    let ranks = Ranks::world();
    // Colour only on a terminal (and never with NO_COLOR set): logs and files get plain text.
    let colour = std::io::stderr().is_terminal()
        && std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty());
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| {
                tracing_subscriber::EnvFilter::new(if ranks.is_root() { "info" } else { "warn" })
            }),
        )
        .with_writer(std::io::stderr)
        .with_ansi(colour)
        .with_target(false)
        .init();
    let _ = miette::set_hook(Box::new(move |_| {
        Box::new(miette::MietteHandlerOpts::new().color(colour).build())
    }));
    match main_inner(ranks) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err((report, interrupted)) => {
            // Every rank takes the same steps on the same data, so an error of another rank is
            // the root's too, and the root reports it; the root's own (a file it could not
            // write) must stop the other ranks.
            if ranks.is_root() {
                eprintln!("{report:?}");
                if !interrupted {
                    ranks.abort(1);
                }
            }
            if interrupted {
                std::process::ExitCode::from(EXIT_INTERRUPTED)
            } else {
                std::process::ExitCode::FAILURE
            }
        }
    }
}

/// A flag raised by the first SIGINT or SIGTERM (the run then ends after its current step with
/// a checkpoint); a second one ends the process at once.
fn stop_flag() -> Result<Arc<AtomicBool>, Report> {
    let flag = Arc::new(AtomicBool::new(false));
    let raised = flag.clone();
    ctrlc::set_handler(move || {
        if raised.swap(true, Ordering::SeqCst) {
            std::process::exit(EXIT_INTERRUPTED.into());
        }
        eprintln!("strike: stopping after this step (a checkpoint is written); signal again to quit at once");
    })
    .map_err(|e| miette!("cannot install the SIGINT/SIGTERM handler: {e}"))?;
    Ok(flag)
}

/// The command's work; an error comes with whether the run was interrupted.
fn main_inner(ranks: Ranks) -> Result<(), (Report, bool)> {
    let cli = Cli::parse();
    let plain = |r: Report| (r, false);
    if ranks.size() > 1 && !matches!(cli.command, Command::Run { .. } | Command::Bench { .. }) {
        return Err(plain(miette!(
            help = "start the other commands without mpirun",
            "only `strike run` and `strike bench` run on several MPI ranks ({} here)",
            ranks.size()
        )));
    }
    match cli.command {
        Command::Run {
            case,
            out,
            threads,
            max_steps,
            resume,
            overwrite,
        } => {
            set_threads(threads).map_err(plain)?;
            let c = load(&case).map_err(plain)?;
            // A resumed run continues in its checkpoint's directory unless told otherwise.
            let out_dir = out.unwrap_or_else(|| match resume.as_deref().and_then(Path::parent) {
                Some(dir) if !dir.as_os_str().is_empty() => dir.to_path_buf(),
                _ => Path::new("runs").join(&c.name),
            });
            tracing::info!(
                "running {} ({}D) into {} on {} threads{}",
                case.display(),
                c.dimension,
                out_dir.display(),
                rayon::current_num_threads(),
                if ranks.size() > 1 {
                    format!(" on each of {} MPI ranks", ranks.size())
                } else {
                    String::new()
                }
            );
            let opts = run::RunOptions {
                out_dir: out_dir.clone(),
                progress: ranks.is_root() && std::io::stderr().is_terminal(),
                max_steps,
                write_fields: true,
                resume,
                overwrite,
                stop: Some(stop_flag().map_err(plain)?),
                ranks,
            };
            // The run's own thread is one of the pool's workers, so that each parallel pass
            // starts from inside the pool: from outside it, each pass handed its work to the
            // pool and slept on a futex until woken (5 % of a run's time, in system calls, by
            // `perf`). Where MPI takes calls from the main thread only (it did not grant
            // `Threading::Serialized`), the main thread keeps the run (`ranks::steps_in_pool`).
            #[allow(clippy::result_large_err)] // the run's own error, passed on as it is
            let summary = if strike::ranks::steps_in_pool(ranks) {
                rayon::scope(|_| run::run(&c, &opts))
            } else {
                run::run(&c, &opts)
            };
            let summary = summary.map_err(|e| {
                let interrupted = matches!(e, Error::Interrupted { .. });
                (report(e, &case), interrupted)
            })?;
            if ranks.is_root() {
                say!("{}", check::summary_text(&summary));
                say!("output in {}", out_dir.display());
            }
            Ok(())
        }
        Command::Bench { quick, json, cases } => {
            let report = strike::bench::run_all(quick, &cases, ranks, |c| {
                if ranks.is_root() {
                    say!("{}", strike::bench::line(c));
                }
            })
            .map_err(|e| plain(miette!("{e}")))?;
            if ranks.is_root() {
                let text =
                    serde_json::to_string_pretty(&report).map_err(|e| plain(miette!("{e}")))?;
                strike::output::atomic::write(&json, (text + "\n").as_bytes())
                    .map_err(|e| plain(miette!("cannot write {}: {e}", json.display())))?;
                say!("written to {}", json.display());
            }
            Ok(())
        }
        Command::Materials { name } => {
            use strike::deck::library;
            let entries = library::entries();
            let chosen: Vec<&library::Entry> = match &name {
                Some(n) => {
                    let canonical = library::canonical_name(n).ok_or_else(|| {
                        miette!(
                            help = format!(
                                "the library materials are {}",
                                library::library_names().join(", ")
                            ),
                            "unknown library material `{n}`"
                        )
                    });
                    let canonical = canonical.map_err(plain)?;
                    entries.iter().filter(|e| e.name == canonical).collect()
                }
                None => entries.iter().collect(),
            };
            for e in chosen {
                say!("{}", library::describe(e));
            }
            say!("References:");
            for r in library::REFERENCES {
                say!("  {r}");
            }
            Ok(())
        }
        Command::Sweep {
            case,
            set,
            ballistic_limit,
            speeds,
            tolerance,
            projectile,
            jobs,
            threads,
            out,
            overwrite,
        } => {
            use strike::sweep;
            let c = load(&case).map_err(plain)?;
            let text = std::fs::read_to_string(&case)
                .map_err(|e| plain(miette!("cannot read {}: {e}", case.display())))?;
            let file = case.display().to_string();
            if jobs == 0 {
                return Err(plain(miette!(
                    help = "e.g. --jobs 2",
                    "--jobs must be at least 1"
                )));
            }
            let threads = threads
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
            let suffix = if ballistic_limit.is_some() {
                "ballistic"
            } else {
                "sweep"
            };
            let opts = sweep::SweepOptions {
                out_dir: out
                    .unwrap_or_else(|| Path::new("runs").join(format!("{}_{suffix}", c.name))),
                jobs,
                threads: threads.max(1),
                projectile,
                overwrite,
            };
            let fail = |e: Error| plain(miette!("{e}"));
            match (ballistic_limit, set.is_empty()) {
                (Some(body), true) => {
                    let Some(range) = speeds else {
                        return Err(plain(miette!(
                            help = "e.g. --speeds 300:1200 (m/s): the low speed must not perforate, the high one must",
                            "--ballistic-limit needs --speeds LOW:HIGH"
                        )));
                    };
                    let bracket = range
                        .split_once(':')
                        .and_then(|(a, b)| Some((a.trim().parse::<f64>().ok()?, b.trim().parse::<f64>().ok()?)))
                        .ok_or_else(|| plain(miette!(help = "e.g. --speeds 300:1200", "--speeds {range}: expected LOW:HIGH in m/s")))?;
                    let limit = sweep::ballistic(&text, &file, &body, bracket, tolerance, &opts).map_err(fail)?;
                    say!(
                        "ballistic limit of '{body}': between {:.1} m/s (held) and {:.1} m/s (perforated), after {} runs{}",
                        limit.below,
                        limit.above,
                        limit.runs.len(),
                        if limit.non_monotonic { "; a slower run perforated where a faster one held: see the table" } else { "" }
                    );
                }
                (Some(_), false) => {
                    return Err(plain(miette!(
                        help = "run one command per value, each with --ballistic-limit",
                        "--ballistic-limit and --set cannot be combined"
                    )))
                }
                (None, true) => {
                    return Err(plain(miette!(
                        help = "e.g. --set body.sphere.velocity=5000:7000:3, or --ballistic-limit BODY --speeds LOW:HIGH",
                        "nothing to sweep"
                    )))
                }
                (None, false) => {
                    let settings = set
                        .iter()
                        .map(String::as_str)
                        .map(sweep::parse_setting)
                        .collect::<Result<Vec<_>, _>>()
                        .map_err(fail)?;
                    let rows = sweep::sweep(&text, &file, &settings, &opts).map_err(fail)?;
                    let perforated = rows.iter().filter(|r| r.1.perforated).count();
                    say!("{} runs, {perforated} perforated", rows.len());
                }
            }
            say!("output in {}", opts.out_dir.display());
            Ok(())
        }
        Command::Validate {
            fine,
            cases,
            out,
            tolerance_factor,
            readme,
            threads,
        } => {
            use strike::validate;
            set_threads(threads).map_err(plain)?;
            if !(tolerance_factor > 0.0 && tolerance_factor.is_finite()) {
                return Err(plain(miette!(
                    help = "e.g. --tolerance-factor 0.5",
                    "--tolerance-factor must be a positive number"
                )));
            }
            let out_dir = out.unwrap_or_else(|| Path::new("runs").join("validate"));
            let fail = |e: Error| plain(miette!("{e}"));
            // A README without the markers is refused before anything runs.
            let readme_text = match &readme {
                Some(path) => {
                    let text = std::fs::read_to_string(path)
                        .map_err(|e| plain(miette!("cannot read {}: {e}", path.display())))?;
                    validate::replace_readme_block(&text, "", "").map_err(fail)?;
                    Some(text)
                }
                None => None,
            };
            let reports = validate::run(&cases, fine, &out_dir).map_err(fail)?;
            validate::write_report(&reports, fine, tolerance_factor, &out_dir).map_err(fail)?;
            say!("{}", validate::table(&reports, tolerance_factor));
            if let (Some(path), Some(text)) = (readme, readme_text) {
                let note = format!(
                    "Written by `strike validate{}` (strike {}); the full report, each setting's figure on its own row with its source and the plots, is in `{}`.",
                    if fine { " --fine" } else { "" },
                    env!("CARGO_PKG_VERSION"),
                    out_dir.join("report.html").display()
                );
                let table = validate::summary(&reports, tolerance_factor);
                let new = validate::replace_readme_block(&text, &table, &note).map_err(fail)?;
                strike::output::atomic::write(&path, new.as_bytes())
                    .map_err(|e| plain(miette!("cannot write {}: {e}", path.display())))?;
                say!("table written into {}", path.display());
            }
            say!("report in {}", out_dir.join("report.html").display());
            let failed: Vec<&str> = reports
                .iter()
                .filter(|r| !r.passes(tolerance_factor))
                .map(|r| r.name)
                .collect();
            if failed.is_empty() {
                Ok(())
            } else {
                Err(plain(miette!(
                    "{} of {} cases failed: {}",
                    failed.len(),
                    reports.len(),
                    failed.join(", ")
                )))
            }
        }
        Command::Check { case } => {
            let c = load(&case).map_err(plain)?;
            let text = check::check(&c).map_err(|e| plain(report(e, &case)))?;
            say!("{text}");
            Ok(())
        }
    }
}

fn set_threads(threads: Option<usize>) -> Result<(), Report> {
    if let Some(n) = threads {
        if n == 0 {
            return Err(miette!(
                help = "give a positive number of threads, e.g. --threads 2",
                "--threads must be at least 1"
            ));
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| miette!("cannot start {n} threads: {e}"))?;
    }
    Ok(())
}

fn load(path: &Path) -> Result<Case, Report> {
    deck::load(path).map_err(|e| report(e, path))
}

/// A library error as a miette report; deck errors show the offending line of the deck.
fn report(e: Error, path: &Path) -> Report {
    match e {
        Error::Deck {
            location,
            key,
            message,
            help,
        } => {
            let header = format!(
                "{}:{}:{}: `{key}`: {message}",
                location.file, location.line, location.column
            );
            let source = std::fs::read_to_string(path).unwrap_or_default();
            let mut diag = miette::MietteDiagnostic::new(header).with_code("strike::deck");
            if let Some(h) = help {
                diag = diag.with_help(h);
            }
            if location.length > 0 && location.offset + location.length <= source.len() {
                diag = diag.with_label(LabeledSpan::at(
                    location.offset..location.offset + location.length,
                    key,
                ));
            } else if location.line > 0 {
                // Point at the start of the line named.
                let offset: usize = source
                    .lines()
                    .take(location.line - 1)
                    .map(|l| l.len() + 1)
                    .sum();
                let len = source.lines().nth(location.line - 1).map_or(0, str::len);
                if offset + len <= source.len() {
                    diag = diag.with_label(LabeledSpan::at(offset..offset + len, key));
                }
            }
            Report::new(diag).with_source_code(NamedSource::new(location.file, source))
        }
        other => miette!("{other}"),
    }
}
