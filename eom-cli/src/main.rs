//! The `eom-gen` command-line tool: the application on top of the
//! generator library (`eom_gen`) and the runtime (`eom_sim`). Each command
//! is a file of `cmd/`; the arguments several share are declared once in
//! `args`; a model is read and checked once (`open`) and handed down.

mod ancf;
mod animate;
mod args;
mod bench;
mod cable_report;
mod cable_sweep;
mod cmd;
mod compiled;
mod dae;
mod ensemble;
mod error;
mod history;
mod lanes;
mod linearize_sweep;
mod mesh;
mod open;
mod output;
mod plot;
mod report;
mod study;
mod summary;
mod sweep;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Symbolic equation-of-motion generator for multibody systems.
#[derive(Parser)]
#[command(name = "eom-gen", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    #[command(flatten)]
    urdf: args::UrdfArgs,
}

#[derive(Subcommand)]
enum Command {
    Check(cmd::check::CheckArgs),
    Dump(cmd::dump::DumpArgs),
    Eval(cmd::eval::EvalArgs),
    Simulate(cmd::simulate::SimulateArgs),
    Import(cmd::import::ImportArgs),
    Bench(cmd::bench::BenchArgs),
    SolveStatic(cmd::solve_static::SolveStaticArgs),
    Stats(cmd::stats::StatsArgs),
    Linearize(cmd::linearize::LinearizeArgs),
    Plot(cmd::plot::PlotArgs),
    Sweep(cmd::sweep::SweepArgs),
    Animate(cmd::animate::AnimateArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let urdf = cli.urdf.options();
    match cli.command {
        Command::Check(a) => cmd::check::run(&a, &urdf),
        Command::Dump(a) => cmd::dump::run(&a, &urdf),
        Command::Eval(a) => cmd::eval::run(&a, &urdf),
        Command::Simulate(a) => cmd::simulate::run(a, &urdf),
        Command::Import(a) => cmd::import::run(&a, &urdf),
        Command::Bench(a) => cmd::bench::run(a, &urdf),
        Command::SolveStatic(a) => cmd::solve_static::run(&a, &urdf),
        Command::Stats(a) => cmd::stats::run(&a, &urdf),
        Command::Linearize(a) => cmd::linearize::run(&a, &urdf),
        Command::Plot(a) => cmd::plot::run(&a, &urdf),
        Command::Sweep(a) => cmd::sweep::run(&a, &urdf),
        Command::Animate(a) => cmd::animate::run(a, &urdf),
    }
}
