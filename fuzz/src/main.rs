//! `sornav-fuzz`: runs the fuzz targets and prints one JSON line per target.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::Parser;
use sornav_fuzz::{run, targets};

/// Mutation-fuzz sornav's parsers and decoders (stable toolchain).
#[derive(Debug, Parser)]
#[command(name = "sornav-fuzz")]
struct Args {
    /// Target name, or `all` (see `--list`).
    #[arg(long, default_value = "all")]
    target: String,
    /// Seconds per target.
    #[arg(long, default_value_t = 60.0)]
    seconds: f64,
    /// Seed of the mutator.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Time bound per input (milliseconds).
    #[arg(long, default_value_t = 2000)]
    timeout_ms: u64,
    /// Peak resident memory bound of the worker process (MiB; 0: none);
    /// its address space is capped at four times this.
    #[arg(long, default_value_t = 512)]
    memory_mb: u64,
    /// Run inputs in this process (catch_unwind and a time check only; no
    /// memory bound, and a hang or abort ends the run).
    #[arg(long)]
    in_process: bool,
    /// Write the grown corpus to DIR/<target>/.
    #[arg(long, value_name = "DIR")]
    corpus_out: Option<PathBuf>,
    /// Write crashing inputs to DIR/<target>/.
    #[arg(long, value_name = "DIR", default_value = "fuzz-crashes")]
    crashes: PathBuf,
    /// List the targets and exit.
    #[arg(long)]
    list: bool,
    /// Internal: serve inputs of TARGET on stdin (the worker process).
    #[arg(long, hide = true, value_name = "TARGET")]
    worker: Option<String>,
}

fn main() -> ExitCode {
    let args = Args::parse();
    if let Some(name) = &args.worker {
        let Some(target) = targets::find(name) else {
            eprintln!("unknown target {name}");
            return ExitCode::from(2);
        };
        return match run::serve_worker(&target, args.memory_mb) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("worker: {e}");
                ExitCode::from(2)
            }
        };
    }
    if args.list {
        for t in targets::all() {
            println!("{:16} {}", t.name, t.about);
        }
        return ExitCode::SUCCESS;
    }
    let chosen: Vec<targets::Target> = if args.target == "all" {
        targets::all()
    } else {
        match targets::find(&args.target) {
            Some(t) => vec![t],
            None => {
                eprintln!("unknown target {} (see --list)", args.target);
                return ExitCode::from(2);
            }
        }
    };
    if !(args.seconds.is_finite() && args.seconds >= 0.0 && args.seconds <= 1e7) {
        eprintln!("--seconds must be a finite number in [0, 1e7]");
        return ExitCode::from(2);
    }
    let worker_exe = if args.in_process {
        None
    } else {
        match std::env::current_exe() {
            Ok(p) => Some(p),
            Err(e) => {
                eprintln!("cannot locate this binary for the worker: {e}");
                return ExitCode::from(2);
            }
        }
    };
    let options = run::Options {
        duration: Duration::from_secs_f64(args.seconds),
        seed: args.seed,
        timeout: Duration::from_millis(args.timeout_ms),
        memory_mb: args.memory_mb,
        worker_exe,
        corpus_out: args.corpus_out,
        crashes: Some(args.crashes),
    };
    let mut crashed = false;
    for t in &chosen {
        match run::run(t, &options) {
            Ok(report) => {
                crashed |= report.crashes > 0;
                println!(
                    "{}",
                    serde_json::to_string(&report).expect("a report serialises")
                );
            }
            Err(e) => {
                eprintln!("{}: {e}", t.name);
                return ExitCode::from(2);
            }
        }
    }
    if crashed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}
