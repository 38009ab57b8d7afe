//! Builds an n-link chain with the Rust builder API, writes it as RON and
//! checks it — the way to make parameterised models (a chain of any length,
//! a robot from a table) without writing the file by hand.
//!
//! `cargo run --example build_chain -- 10 [out.ron] [--planar]`: spatial
//! (axes alternating z, y) unless `--planar` (every axis y).

use eom_gen::model::builder::n_link_chain;
use eom_gen::model::{Source, check};
use std::process::ExitCode;

fn main() -> ExitCode {
    let (flags, rest): (Vec<String>, Vec<String>) =
        std::env::args().skip(1).partition(|a| a.starts_with("--"));
    let planar = match flags.as_slice() {
        [] => false,
        [f] if f == "--planar" => true,
        _ => {
            eprintln!("usage: build_chain [LINKS (a positive integer)] [OUT.ron] [--planar]");
            return ExitCode::from(2);
        }
    };
    let mut args = rest.into_iter();
    let n: usize = match args.next().map(|a| a.parse()) {
        None => 5,
        Some(Ok(n)) if n > 0 => n,
        Some(_) => {
            eprintln!("usage: build_chain [LINKS (a positive integer)] [OUT.ron] [--planar]");
            return ExitCode::from(2);
        }
    };
    let text = n_link_chain(n, !planar).to_ron();
    match check(&Source::new("<builder>", text.clone())) {
        Ok(checked) => {
            let sys = &checked.system;
            eprintln!(
                "{}: {} bodies, nq = {}, nu = {} ({})",
                sys.name,
                sys.bodies.len() - 1,
                sys.nq(),
                sys.nu(),
                sys.coordinate_names().join(", ")
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
