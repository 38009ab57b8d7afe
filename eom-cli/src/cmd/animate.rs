//! `eom-gen animate MODEL [run options] -o run.html`: a run of `simulate`
//! written as its animation page (`crate::animate`): `simulate --html`
//! with frames every 10 ms unless `--every` says otherwise.

use crate::cmd::simulate::SimulateArgs;
use crate::error::Error;
use crate::output::fail;
use clap::Args;
use std::process::ExitCode;

/// Simulate the model and write its motion as one self-contained HTML
/// page (3-D, orbit, zoom, play/pause, time slider, speed).
#[derive(Args)]
pub struct AnimateArgs {
    #[command(flatten)]
    pub run: SimulateArgs,
    /// The HTML file to write.
    #[arg(short, long)]
    pub output: String,
}

pub fn run(a: AnimateArgs, urdf: &eom_gen::urdf::Options) -> ExitCode {
    let mut run = a.run;
    if run.html.is_some() {
        return fail(&Error::Usage(vec![
            "--html is the output of `simulate`; `animate` writes its page to -o/--output".into(),
        ]));
    }
    run.html = Some(a.output);
    // Frames every 10 ms: smooth at any speed the page offers, small.
    run.every = run.every.or(Some(0.01));
    crate::cmd::simulate::run(run, urdf)
}
