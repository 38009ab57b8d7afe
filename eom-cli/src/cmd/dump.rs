//! `eom-gen dump`: the generated Rust source of a model.

use crate::args::Vary;
use clap::Args;
use std::process::ExitCode;

/// Print the generated Rust source of a model.
#[derive(Args)]
pub struct DumpArgs {
    /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`).
    pub model: String,
    /// Write to this file instead of standard output.
    #[arg(short, long)]
    pub output: Option<String>,
    /// Emit `f64::mul_add` for `a·b + c` (compile with FMA enabled).
    #[arg(long)]
    pub fma: bool,
    /// Also emit every function over SIMD lanes (`NAME_lanes::<W>`: `W`
    /// states per call; `eom_sim::Batched`, `eom_sim::OdeLanes`).
    #[arg(long)]
    pub lanes: bool,
}

pub fn run(a: &DumpArgs, urdf: &eom_gen::urdf::Options) -> ExitCode {
    let vary = Vary::default();
    let opened = match crate::open::open(&a.model, urdf, &vary) {
        Ok(o) => o,
        Err(code) => return code,
    };
    let options = eom_gen::EmitOptions {
        fma: a.fma,
        lanes: a.lanes,
        ..Default::default()
    };
    let g = match crate::open::generate(&opened, &vary, &options) {
        Ok(g) => g,
        Err(code) => return code,
    };
    eprint!("{}", g.checked.render_warnings());
    eprint!("{}", crate::cable_report::dump_note(&g.checked.system));
    crate::output::emit(&g.source, a.output.as_deref())
}
