//! `situate`: check and run robot files.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::Context as _;
use clap::{Parser, Subcommand};
use situate::manager::{ClockKind, ExecutorKind, Manager, RobotFile, RobotSpec};
use situate::manager::{Control, ManagerStats, SkillInfo};

#[derive(Parser)]
#[command(name = "situate", version, about = "The reactive layer of a robot: check and run robot files")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Check a robot file statically; every problem is reported as FILE:LINE:COL.
    Check { file: PathBuf },
    /// Run a robot file and print a summary.
    Run {
        file: PathBuf,
        /// Stop after this many cycles (default: run until interrupted).
        #[arg(long)]
        cycles: Option<u64>,
        /// Override the file's executor.
        #[arg(long, value_parser = ["serial", "parallel"])]
        executor: Option<String>,
        /// Override the file's clock.
        #[arg(long, value_parser = ["wall", "simulated"])]
        clock: Option<String>,
    },
    /// List the skill types this program knows, with their declarations.
    Types,
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()))
        .with_writer(std::io::stderr)
        .init();
    match run(Cli::parse()) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn load(file: &std::path::Path) -> Result<RobotSpec, ExitCode> {
    match RobotFile::load(file) {
        Ok(f) => Ok(RobotSpec::from_file(&f)),
        Err(errors) => {
            for e in errors {
                eprintln!("{e}");
            }
            Err(ExitCode::FAILURE)
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    let registry = situate_toys::registry();
    match cli.command {
        Command::Check { file } => {
            let spec = match load(&file) {
                Ok(s) => s,
                Err(code) => return Ok(code),
            };
            match situate::manager::Graph::build(&spec, &registry) {
                Ok(graph) => {
                    for w in &graph.warnings {
                        eprintln!("{w}");
                    }
                    println!(
                        "{}: ok — robot `{}`, {} skills, {} signals",
                        file.display(),
                        graph.robot,
                        graph.instances.len(),
                        graph.leaves.len()
                    );
                    Ok(ExitCode::SUCCESS)
                }
                Err(e) => {
                    for d in &e.diagnostics {
                        eprintln!("{d}");
                    }
                    let n = e.diagnostics.iter().filter(|d| d.is_error()).count();
                    eprintln!("{}: {n} error{}", file.display(), if n == 1 { "" } else { "s" });
                    Ok(ExitCode::FAILURE)
                }
            }
        }
        Command::Run { file, cycles, executor, clock } => {
            let mut spec = match load(&file) {
                Ok(s) => s,
                Err(code) => return Ok(code),
            };
            if let Some(e) = executor {
                spec.executor = if e == "parallel" { ExecutorKind::Parallel } else { ExecutorKind::Serial };
            }
            if let Some(c) = clock {
                spec.clock = if c == "simulated" { ClockKind::Simulated } else { ClockKind::Wall };
            }
            let mut manager = match Manager::build(&spec, &registry) {
                Ok(m) => m,
                Err(e) => {
                    eprintln!("{e}");
                    return Ok(ExitCode::FAILURE);
                }
            };
            for w in &manager.graph().warnings {
                eprintln!("{w}");
            }
            let interrupted = Arc::new(AtomicBool::new(false));
            let flag = Arc::clone(&interrupted);
            ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst)).context("installing the Ctrl-C handler")?;
            let faults = manager.events();
            let chunk = 10;
            let mut done = 0u64;
            while !interrupted.load(Ordering::SeqCst) && cycles.is_none_or(|n| done < n) {
                let n = cycles.map_or(chunk, |n| chunk.min(n - done));
                manager.run_cycles(n);
                done += n;
                for event in faults.try_iter() {
                    if let situate::manager::Event::SkillFaulted { skill, cause, cycle } = event {
                        eprintln!("cycle {cycle}: skill `{skill}` faulted: {cause}");
                    }
                }
            }
            let stats = manager.stats().map_err(anyhow::Error::msg)?;
            let skills = manager.skills().map_err(anyhow::Error::msg)?;
            print_summary(&stats, &skills);
            Ok(ExitCode::SUCCESS)
        }
        Command::Types => {
            for name in registry.names() {
                if let Some(t) = registry.get(name) {
                    let d = &t.decl;
                    println!("{name} ({}, priority {})", d.kind, d.priority);
                    if !d.doc.is_empty() {
                        println!("    {}", d.doc.lines().next().unwrap_or(""));
                    }
                    for p in &d.inputs {
                        println!("    in  {}: {}{}", p.name, p.ty, if p.optional { " (optional)" } else { "" });
                    }
                    for p in &d.outputs {
                        println!("    out {}: {}", p.name, p.ty);
                    }
                    for p in &d.params {
                        println!("    param {}: {} = {} ({})", p.name, p.ty.name(), p.default, p.expectation());
                    }
                }
            }
            Ok(ExitCode::SUCCESS)
        }
    }
}

fn print_summary(stats: &ManagerStats, skills: &[SkillInfo]) {
    println!("robot `{}`: {} cycles, {:.3} s on its clock", stats.robot, stats.cycle, stats.time_s);
    println!(
        "cycle time: mean {:.1} µs, max {:.1} µs; period {:.1} ms; overruns {}",
        stats.mean_cycle_ns / 1e3,
        stats.max_cycle_ns as f64 / 1e3,
        stats.period_s * 1e3,
        stats.overruns
    );
    println!(
        "{:<16} {:<8} {:>8} {:>10} {:>10} {:>10}  state",
        "skill", "kind", "runs", "mean µs", "max µs", "total ms"
    );
    for s in skills {
        let state = match (&s.faulted, s.active) {
            (Some(cause), _) => format!("faulted: {cause}"),
            (None, true) => "active".to_string(),
            (None, false) => "inactive".to_string(),
        };
        println!(
            "{:<16} {:<8} {:>8} {:>10.2} {:>10.2} {:>10.3}  {state}",
            s.name,
            s.kind.name(),
            s.timing.runs,
            s.timing.mean_ns() / 1e3,
            s.timing.max_ns as f64 / 1e3,
            s.timing.total_ns as f64 / 1e6
        );
    }
}
