//! Generation time and operation counts of the symbolic formulation:
//! bundled tree models and n-link chains (planar and spatial).
//!
//! `cargo bench -p eom-gen --bench generation` prints a Markdown table
//! (medians of 5 runs; the machine is shared, so read ratios, not digits).

use eom_gen::functions::{Function, FunctionSet};
use eom_gen::mech::{Formulation, formulate};
use eom_gen::model::builder::n_link_chain;
use eom_gen::model::{Source, check};
use std::time::Instant;

fn system_from(text: String, name: &str) -> eom_gen::System {
    match check(&Source::new(name, text)) {
        Ok(c) => c.system,
        Err(r) => panic!("{r}"),
    }
}

fn median_formulation(sys: &eom_gen::System, runs: usize) -> (f64, Formulation) {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..runs {
        let start = Instant::now();
        let f = formulate(sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
        times.push(start.elapsed().as_secs_f64());
        last = Some(f);
    }
    times.sort_by(f64::total_cmp);
    (
        times[times.len() / 2],
        last.unwrap_or_else(|| unreachable!("runs > 0")),
    )
}

fn ops(p: Option<&eom_gen::sym::Program>) -> String {
    p.map_or("—".into(), |p| p.op_count().total().to_string())
}

fn row(name: &str, nu: usize, secs: f64, f: &Formulation) {
    let cand: Vec<String> = f
        .fd_candidates
        .iter()
        .map(|(form, c)| format!("{form:?} {}", c.total()))
        .collect();
    println!(
        "| {name} | {nu} | {:.1} | {} ({:?}) | {} | {} | {} | {} |",
        secs * 1e3,
        ops(f.program(Function::ForwardDynamics)),
        f.fd_form,
        cand.join(", "),
        ops(f.program(Function::InverseDynamics)),
        ops(f.program(Function::MassMatrix)),
        ops(f.program(Function::Bias)),
    );
}

fn main() {
    // `cargo bench` passes `--bench`; nothing else is accepted.
    println!(
        "| model | nu | generation ms (median of 5) | FD ops (form) | FD candidates | ID ops | M ops | b ops |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for name in [
        "pendulum",
        "double_pendulum",
        "arm7",
        "heavy_top",
        "free_body",
    ] {
        let path = format!("{}/../models/{name}.ron", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
        let sys = system_from(text, name);
        eprintln!("… {name}");
        let (secs, f) = median_formulation(&sys, 5);
        row(name, sys.nu(), secs, &f);
    }
    for spatial in [false, true] {
        for n in [10, 50, 100, 200] {
            let name = format!("{} chain {n}", if spatial { "spatial" } else { "planar" });
            eprintln!("… {name}");
            let sys = system_from(n_link_chain(n, spatial).to_ron(), &name);
            let (secs, f) = median_formulation(&sys, if n >= 100 { 3 } else { 5 });
            row(&name, sys.nu(), secs, &f);
        }
    }
}
