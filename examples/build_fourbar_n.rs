//! Builds the N-four-bar of IFToMM benchmark A02 (N + 1 cranks, N couplers;
//! `eom_gen::model::builder::n_fourbar`), writes it as RON with its header
//! comment and checks it. `models/fourbar_n2.ron` and `models/fourbar_n4.ron`
//! are made by it:
//!
//! `cargo run --example build_fourbar_n -- 2 models/fourbar_n2.ron`

use eom_gen::model::builder::n_fourbar;
use eom_gen::model::{Source, check};
use std::process::ExitCode;

/// The header comment of a bundled model: source and physics.
fn header(n: usize) -> String {
    let nf = n as f64;
    format!(
        "// N-four-bar — IFToMM benchmark A02 with N = {n} (library of computational\n\
         // benchmark problems, IFToMM Technical Committee for Multibody Dynamics; the\n\
         // benchmark itself uses N = 40). {c} cranks pinned to ground one link length\n\
         // apart along +x, at x = 0, L, …, {n}L, and {n} coupler(s) joining their tips;\n\
         // every rod uniform, 1 m and 1 kg (inertia m L²/12 about the centre), hinges\n\
         // about z, gravity 9.81 m/s² along −y (as models/fourbar.ron, which is N = 1).\n\
         // Starts with the cranks vertical and every crank tip moving at +1 m/s along x:\n\
         // cranks at −1 rad/s, couplers at +1 rad/s relative to their crank. Mobility 1\n\
         // (Grübler and the rank of J agree), but twice a turn all {links} links are\n\
         // collinear and the mobility jumps to {n1}: {n} loop(s) singular at once. On\n\
         // the parallelogram branch all cranks share one angle φ (from +x) and the\n\
         // couplers translate: J φ̈ = −G cos φ with J = ((N+1)/3 + N) m L² = {jj:.6} kg m²,\n\
         // G = ((N+1)/2 + N) m g L = {gg:.4} N m.\n\
         //\n\
         // Made by `cargo run --example build_fourbar_n -- {n} models/fourbar_n{n}.ron`\n\
         // (eom_gen::model::builder::n_fourbar). Tree: ground → crank0 → coupler1,\n\
         // ground → crank1 → coupler2, …, ground → crank{n}; the joints c1 … c{n} between\n\
         // coupler j and the tip of crank j are cut and close the loops.\n",
        c = n + 1,
        links = 2 * n + 1,
        n1 = n + 1,
        jj = (nf + 1.0) / 3.0 + nf,
        gg = ((nf + 1.0) / 2.0 + nf) * 9.81,
    )
}

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let n: usize = match args.next().map(|a| a.parse()) {
        None => 2,
        Some(Ok(n)) if n > 0 => n,
        Some(_) => {
            eprintln!("usage: build_fourbar_n [N (a positive integer)] [OUT.ron]");
            return ExitCode::from(2);
        }
    };
    let text = format!("{}{}\n", header(n), n_fourbar(n).to_ron());
    match check(&Source::new("<builder>", text.clone())) {
        Ok(checked) => {
            let sys = &checked.system;
            eprintln!(
                "{}: {} bodies, nq = {}, nu = {}",
                sys.name,
                sys.bodies.len() - 1,
                sys.nq(),
                sys.nu(),
            );
        }
        Err(report) => {
            eprint!("{report}");
            return ExitCode::from(1);
        }
    }
    match args.next() {
        Some(path) => {
            if let Err(e) = std::fs::write(&path, &text) {
                eprintln!("cannot write {path}: {e}");
                return ExitCode::from(1);
            }
        }
        None => print!("{text}"),
    }
    ExitCode::SUCCESS
}
