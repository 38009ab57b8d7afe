//! Long chains as loops (`eom_gen::mech::looped`): forward dynamics, the
//! mass matrix, the bias and inverse dynamics of a serial chain computed
//! body by body by generated body steps must equal the straight-line
//! programs and the `f64` algorithms (ABA, CRBA, RNEA, Featherstone
//! ch. 5–7) at random states — the same recursions cut at the bodies, so
//! they agree to rounding. The loops are run in process by
//! `Loop::run`, which calls the steps as the emitted code does.

use eom_gen::functions::{Function, FunctionSet};
use eom_gen::mech::looped::{ChainLoops, LOOP_MIN_OPS};
use eom_gen::mech::{Formulation, Numeric, formulate};
use eom_gen::model::builder::{ModelBuilder, n_link_chain};
use eom_gen::model::spec::{Body, Joint, JointKind};
use eom_gen::model::{Source, check};
use eom_gen::sym::{Program, SymKind};
use eom_gen::testkit::{Rng, random_state};
use eom_gen::{EmitOptions, LoopChoice, System};

fn system(text: String) -> System {
    check(&Source::new("chain", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

fn chain(n: usize, spatial: bool) -> System {
    system(n_link_chain(n, spatial).to_ron())
}

/// A chain whose links differ: lengths, masses and axes vary from link to
/// link, every fourth joint is prismatic, and the joints are offset off
/// the links' axes.
fn mixed_chain(n: usize) -> System {
    let mut b = ModelBuilder::new("mixed_chain").gravity((0.3, -1.0, -9.81));
    for k in 1..=n {
        let (link, parent) = (
            format!("link{k}"),
            if k == 1 {
                "ground".to_string()
            } else {
                format!("link{}", k - 1)
            },
        );
        let len = 0.3 + 0.05 * (k % 3) as f64;
        let body = Body::new(link.clone(), 1.0 + 0.25 * (k % 4) as f64)
            .com((0.01 * k as f64, 0.0, len / 2.0))
            .inertia_diag(0.02 + 0.001 * k as f64, 0.025, 0.01);
        let kind = match k % 4 {
            0 => JointKind::prismatic((0.0, 0.0, 1.0)),
            1 => JointKind::revolute((0.0, 0.0, 1.0)),
            2 => JointKind::revolute((0.0, 1.0, 0.0)),
            _ => JointKind::revolute((1.0, 0.0, 0.0)),
        };
        let joint = Joint::new(format!("j{k}"), kind, parent, link)
            .at_parent((0.0, 0.02 * (k % 2) as f64, if k == 1 { 0.0 } else { len }))
            .coordinates([format!("q{k}")])
            .q0([0.1]);
        b = b.body(body).joint(joint);
    }
    system(b.build().to_ron())
}

/// Runs a straight-line program with the state's values.
fn run(p: &Program, q: &[f64], u: &[f64], tau: &[f64], udot: &[f64]) -> Vec<f64> {
    let ins: Vec<f64> = p
        .inputs
        .iter()
        .map(|s| match s.kind {
            SymKind::Coord(i) => q[i as usize],
            SymKind::Speed(i) => u[i as usize],
            SymKind::Tau(i) => tau[i as usize],
            SymKind::SpeedRate(i) => udot[i as usize],
            SymKind::Time => 0.0,
            _ => f64::NAN,
        })
        .collect();
    p.eval(&ins)
}

fn assert_close(what: &str, got: &[f64], want: &[f64]) {
    assert_eq!(got.len(), want.len(), "{what}: lengths");
    let scale = want.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= 1e-10 * scale,
            "{what}[{k}]: got {g} want {w} (scale {scale})"
        );
    }
}

/// The loops of `sys` against the straight-line programs of `f` and the
/// numeric twin at three random states.
#[allow(clippy::needless_range_loop)]
fn check_loops(name: &str, sys: &System, f: &Formulation) {
    let n = sys.nu();
    let loops = ChainLoops::build(sys, FunctionSet::all_requested())
        .expect("builds")
        .expect("a chain the loops handle");
    let twin = Numeric::new(sys).expect("twin");
    let mut rng = Rng(7 + n as u64);
    for _ in 0..3 {
        let (q, u) = random_state(sys, &mut rng);
        let tau = rng.vec(n, 1.0);
        let udot = rng.vec(n, 1.0);
        let program = |g: Function| f.program(g).expect("generated");

        // Forward dynamics: u̇ from the third pass.
        let st = loops
            .get(Function::ForwardDynamics)
            .expect("fd")
            .run(&q, &u, &tau);
        let fd: Vec<f64> = st[2].iter().map(|s| s[0]).collect();
        let want = twin
            .forward_dynamics(&q, &u, 0.0, &tau, &[])
            .expect("twin fd");
        assert_close(&format!("{name} u̇ against the twin"), &fd, &want);
        let straight = run(program(Function::ForwardDynamics), &q, &u, &tau, &udot);
        assert_close(&format!("{name} u̇ against straight-line"), &fd, &straight);

        // Inverse dynamics and bias: τ from the second pass.
        let st = loops
            .get(Function::InverseDynamics)
            .expect("id")
            .run(&q, &u, &udot);
        let id: Vec<f64> = st[1].iter().map(|s| s[0]).collect();
        let want = twin
            .inverse_dynamics(&q, &u, &udot, 0.0, &[])
            .expect("twin id");
        assert_close(&format!("{name} τ against the twin"), &id, &want);
        let straight = run(program(Function::InverseDynamics), &q, &u, &tau, &udot);
        assert_close(&format!("{name} τ against straight-line"), &id, &straight);
        let st = loops.get(Function::Bias).expect("bias").run(&q, &u, &[]);
        let b: Vec<f64> = st[1].iter().map(|s| s[0]).collect();
        let terms = twin.terms(&q, &u, 0.0, &[]).expect("twin terms");
        assert_close(&format!("{name} b against the twin"), &b, &terms.bias);
        let straight = run(program(Function::Bias), &q, &u, &tau, &udot);
        assert_close(&format!("{name} b against straight-line"), &b, &straight);

        // Mass matrix, lower triangle by rows: M_ii from the second pass,
        // M_ij (j < i) from the third.
        let st = loops
            .get(Function::MassMatrix)
            .expect("m")
            .run(&q, &[], &[]);
        let mut m = Vec::new();
        let mut want = Vec::new();
        for i in 0..n {
            for j in 0..=i {
                m.push(if i == j { st[1][i][6] } else { st[2][i][j] });
                want.push(terms.mass_matrix[i][j]);
            }
        }
        assert_close(&format!("{name} M against the twin"), &m, &want);
        let straight = run(program(Function::MassMatrix), &q, &u, &tau, &udot);
        assert_close(&format!("{name} M against straight-line"), &m, &straight);
    }
}

#[test]
fn looped_chains_match_straight_line_and_twin() {
    for (n, spatial) in [(5, true), (10, true), (50, true), (5, false), (10, false)] {
        let sys = chain(n, spatial);
        let f = formulate(&sys, FunctionSet::all_requested()).expect("formulates");
        check_loops(
            &format!("{}{n}", if spatial { "spatial" } else { "planar" }),
            &sys,
            &f,
        );
    }
}

#[test]
fn looped_chain_of_unequal_links_matches() {
    let sys = mixed_chain(9);
    let f = formulate(&sys, FunctionSet::all_requested()).expect("formulates");
    check_loops("mixed9", &sys, &f);
}

#[test]
fn code_stops_growing_with_the_number_of_links() {
    // Links of one structure share their body steps: the 10- and 50-link
    // spatial chains have the same steps, so the same code.
    let steps = |n: usize| {
        let l = ChainLoops::build(&chain(n, true), FunctionSet::all_requested())
            .expect("builds")
            .expect("a chain");
        l.loops
            .values()
            .map(|lp| (lp.steps(), lp.code_ops()))
            .collect::<Vec<_>>()
    };
    let (a, b) = (steps(10), steps(50));
    assert_eq!(
        a, b,
        "distinct steps and their operations, 10 against 50 links"
    );
    // A chain whose links all differ gets one step per body and pass.
    let mixed = ChainLoops::build(&mixed_chain(9), FunctionSet::all_requested())
        .expect("builds")
        .expect("a chain");
    let fd = mixed.get(Function::ForwardDynamics).expect("fd");
    assert!(
        fd.steps() > 3 * 4,
        "unequal links share few steps: {}",
        fd.steps()
    );
}

#[test]
fn loops_are_chosen_for_long_chains_only() {
    // The rule: straight-line code of at least LOOP_MIN_OPS operations,
    // loop code a quarter of it at most, at most 1.5× its operations.
    let f5 = formulate(&chain(5, true), FunctionSet::all_requested()).expect("5");
    assert!(
        f5.loops.is_none(),
        "5 links: every program below {LOOP_MIN_OPS} ops"
    );
    let f50 = formulate(&chain(50, true), FunctionSet::all_requested()).expect("50");
    let loops = f50.loops.as_ref().expect("50 links: loops offered");
    let fd_ops = f50
        .program(Function::ForwardDynamics)
        .expect("fd")
        .op_count()
        .total();
    assert!(
        loops.pays(Function::ForwardDynamics, fd_ops),
        "50-link FD loops"
    );
    // arm7 is a chain of hinges too: loops can be built for it (and are
    // not chosen, its programs being short).
    let arm7 = eom_gen::check_file(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/arm7.ron"))
        .map(|c| c.system)
        .expect("arm7");
    let a = ChainLoops::build(&arm7, FunctionSet::all_requested()).expect("builds");
    assert!(a.is_some(), "arm7 is a chain of hinges: loops can be built");
}

#[test]
fn emitted_loops_are_formatted_and_deterministic() {
    let sys = chain(5, true);
    let f = formulate(&sys, FunctionSet::all_requested()).expect("formulates");
    let opts = EmitOptions {
        loops: LoopChoice::Always,
        ..Default::default()
    };
    let a = eom_gen::emit::emit_with(&sys, &f, "", &opts);
    let b = eom_gen::emit::emit_with(&sys, &f, "", &opts);
    assert_eq!(a, b, "byte-identical for identical input");
    assert!(!a.contains("formatting failed"), "parses and formats");
    for name in [
        "fn forward_dynamics_p0_s0(",
        "fn mass_matrix_p2_s0(",
        "fn inverse_dynamics_p1_s0(",
        "fn bias_p0_s0(",
    ] {
        assert!(a.contains(name), "{name} emitted");
    }
    let straight = eom_gen::emit::emit_with(&sys, &f, "", &EmitOptions::default());
    assert!(
        !straight.contains("_p0_s0("),
        "5 links stay straight by default"
    );
}

#[test]
#[ignore = "prints the loops' operation counts; run with --ignored --nocapture"]
fn print_loop_counts() {
    for n in [10, 50, 200] {
        let sys = chain(n, true);
        let f = formulate(&sys, FunctionSet::all_requested()).expect("formulates");
        let loops = ChainLoops::build(&sys, FunctionSet::all_requested())
            .expect("builds")
            .expect("a chain");
        for (g, l) in &loops.loops {
            let straight = f.program(*g).map_or(0, |p| p.op_count().total());
            println!(
                "| spatial {n} | {} | {straight} | {} | {} | {} | {} |",
                g.name(),
                l.ops(),
                l.steps(),
                l.code_ops(),
                loops.pays(*g, straight)
            );
        }
    }
}

#[test]
#[ignore = "prints the forward dynamics' steps of the 50-link chain; run with --ignored --nocapture"]
fn print_forward_dynamics_steps() {
    let sys = chain(50, true);
    let loops = ChainLoops::build(&sys, FunctionSet::all_requested())
        .expect("builds")
        .expect("a chain");
    let Some(l) = loops.get(Function::ForwardDynamics) else {
        return;
    };
    for (p, pass) in l.passes.iter().enumerate() {
        for (k, s) in pass.steps.iter().enumerate() {
            let bodies = pass.class.iter().filter(|&&c| c == k).count();
            println!(
                "| pass {p} | step {k} | bodies {bodies} | inputs {} | {} |",
                s.inputs.len(),
                s.op_count()
            );
        }
    }
}
