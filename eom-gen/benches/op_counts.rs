//! Operation counts of the generated programs next to the same recursive
//! algorithms run generically (`eom_gen::mech::count`: every operation of
//! the textbook code counted, no structural zeros), per call and per added
//! body.
//!
//! `cargo bench -p eom-gen --bench op_counts` prints Markdown tables.

use eom_gen::functions::{Function, FunctionSet};
use eom_gen::mech::count::{AlgorithmCounts, textbook_counts};
use eom_gen::mech::{Formulation, formulate};
use eom_gen::model::builder::n_link_chain;
use eom_gen::model::{Source, check};

fn system_from(text: String, name: &str) -> eom_gen::System {
    match check(&Source::new(name, text)) {
        Ok(c) => c.system,
        Err(r) => panic!("{r}"),
    }
}

fn ops(p: Option<&eom_gen::sym::Program>) -> u64 {
    p.map_or(0, |p| p.op_count().total() as u64)
}

fn measure(sys: &eom_gen::System) -> (AlgorithmCounts, Formulation) {
    let counts = textbook_counts(sys).unwrap_or_else(|e| panic!("{e}"));
    let f = formulate(sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    (counts, f)
}

fn main() {
    println!(
        "| model | nu | ABA textbook (mul / add / total) | FD generated | ratio | RNEA textbook | ID generated | ratio | CRBA textbook | M generated | ratio |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let mut chains = Vec::new();
    let arm7 = format!("{}/../models/arm7.ron", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&arm7).unwrap_or_else(|e| panic!("{arm7}: {e}"));
    let mut models = vec![("arm7".to_string(), system_from(text, "arm7"))];
    for spatial in [false, true] {
        for n in [10, 50] {
            let name = format!("{} chain {n}", if spatial { "spatial" } else { "planar" });
            models.push((
                name.clone(),
                system_from(n_link_chain(n, spatial).to_ron(), &name),
            ));
        }
    }
    for (name, sys) in &models {
        eprintln!("… {name}");
        let (c, f) = measure(sys);
        let (fd, id, m) = (
            ops(f.program(Function::ForwardDynamics)),
            ops(f.program(Function::InverseDynamics)),
            ops(f.program(Function::MassMatrix)),
        );
        let ratio = |a: u64, b: u64| a as f64 / b.max(1) as f64;
        println!(
            "| {name} | {} | {} / {} / {} | {fd} | {:.1} | {} | {id} | {:.1} | {} | {m} | {:.1} |",
            sys.nu(),
            c.aba.mul,
            c.aba.add,
            c.aba.total(),
            ratio(c.aba.total(), fd),
            c.rnea.total(),
            ratio(c.rnea.total(), id),
            c.crba.total(),
            ratio(c.crba.total(), m),
        );
        chains.push((name.clone(), sys.nu() as u64, c, fd, id));
    }
    println!();
    println!("Per added body (chain 50 minus chain 10, over 40 bodies):");
    println!();
    println!(
        "| chain | ABA textbook mul / add | FD generated | RNEA textbook mul / add | ID generated |"
    );
    println!("|---|---|---|---|---|");
    for kind in ["planar", "spatial"] {
        let pick = |n: u64| {
            chains
                .iter()
                .find(|(name, nu, ..)| name.starts_with(kind) && *nu == n)
                .unwrap_or_else(|| panic!("{kind} chain {n}"))
        };
        let (a, b) = (pick(10), pick(50));
        let per = |x: u64, y: u64| (y as f64 - x as f64) / 40.0;
        println!(
            "| {kind} | {} / {} | {} | {} / {} | {} |",
            per(a.2.aba.mul, b.2.aba.mul),
            per(a.2.aba.add, b.2.aba.add),
            per(a.3, b.3),
            per(a.2.rnea.mul, b.2.rnea.mul),
            per(a.2.rnea.add, b.2.rnea.add),
            per(a.4, b.4),
        );
    }
}
