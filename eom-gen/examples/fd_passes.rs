//! Forward dynamics' operations pass by pass (articulated bodies, rigid
//! trees): `cargo run --release -p eom-gen --example fd_passes -- MODEL…`;
//! with `--program` first, both forms' counts and the lowered
//! forward-dynamics program too; with `--derivatives` first, the parts of
//! the derivatives `−M⁻¹ ∂ID/∂x` instead (`u̇`, `M⁻¹`, the recursion's
//! `∂ID/∂(q, u)`). `chain:N:planar` and `chain:N:spatial` name the
//! builder's chains (`n_link_chain`).

use eom_gen::mech::passes::{aba_pass_counts, derivative_part_counts};
use eom_gen::model::{Source, check};

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let listing = args.first().is_some_and(|a| a == "--program");
    if listing {
        args.remove(0);
    }
    let derivatives = args.first().is_some_and(|a| a == "--derivatives");
    if derivatives {
        args.remove(0);
    }
    for path in args {
        // `chain:N:planar` or `chain:N:spatial`: the builder's chains.
        let chain = path.strip_prefix("chain:").and_then(|rest| {
            let (n, kind) = rest.split_once(':')?;
            Some((n.parse::<usize>().ok()?, kind == "spatial"))
        });
        let text = match chain {
            Some((n, spatial)) => eom_gen::model::builder::n_link_chain(n, spatial).to_ron(),
            None => match std::fs::read_to_string(&path) {
                Ok(t) => t,
                Err(e) => {
                    eprintln!("{path}: {e}");
                    std::process::exit(2);
                }
            },
        };
        let sys = match check(&Source::new(&path, text)) {
            Ok(c) => c.system,
            Err(r) => {
                eprintln!("{r}");
                std::process::exit(1);
            }
        };
        println!("{path}");
        if listing {
            use eom_gen::functions::{Function, FunctionSet};
            match eom_gen::mech::formulate(&sys, FunctionSet::default()) {
                Ok(f) => {
                    for (form, c) in &f.fd_candidates {
                        println!("  forward dynamics as {form:?}: {c}");
                    }
                    if let Some(p) = f.program(Function::ForwardDynamics) {
                        println!("{p}");
                    }
                }
                Err(e) => println!("  {e}"),
            }
        }
        let counts = if derivatives {
            derivative_part_counts(&sys)
        } else {
            aba_pass_counts(&sys)
        };
        match counts {
            Ok(Some(passes)) => {
                let mut total = 0;
                for (name, c) in passes {
                    total += c.total();
                    println!("  {:>5}  {name}  ({c})", c.total());
                }
                println!("  {total:>5}  total");
            }
            Ok(None) => println!("  (not a rigid tree of free joints)"),
            Err(e) => println!("  {e}"),
        }
    }
}
