//! Property tests: every rewrite preserves values, CSE on equals CSE off,
//! derivatives match central differences, s-expressions round-trip.
//!
//! Random expressions are drawn as s-expression text from a grammar biased
//! towards the patterns the rules look for (`sin²·R + cos²·R`, angle sums,
//! like terms, `x − x`, `x/x`). Denominators, `sqrt` and `ln` arguments are
//! kept away from zero (`2 + a²`), so every expression is defined at every
//! point drawn. Inputs are uniform in [-2, 2]. Values are compared with
//! `|got − want| ≤ 1e-9 · (1 + |want|)` unless stated otherwise.

use eom_gen::sym::{
    Arena, Context, Expr, LowerOptions, Mat3, RuleSet, Runner, Scalar, SymId, TimeDerivative, Vec3,
};
use proptest::collection::vec;
use proptest::prelude::*;

const VARS: [&str; 5] = ["x", "y", "z", "q1", "q2"];
const TOL: f64 = 1e-9;

fn leaf() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => proptest::sample::select(VARS.to_vec()),
        1 => proptest::sample::select(vec!["0", "1", "2", "-1", "1/2", "3", "0.25", "-1.5", "1/3"]),
    ]
    .prop_map(String::from)
}

/// Random expressions; `smooth` leaves out `abs`, `select` and `sqrt(a²)`.
fn expr(smooth: bool) -> impl Strategy<Value = String> {
    leaf().prop_recursive(4, 40, 4, move |inner| {
        let i = || inner.clone();
        let mut arms: Vec<BoxedStrategy<String>> = vec![
            vec(i(), 2..4)
                .prop_map(|v| format!("(+ {})", v.join(" ")))
                .boxed(),
            vec(i(), 2..4)
                .prop_map(|v| format!("(* {})", v.join(" ")))
                .boxed(),
            (i(), i()).prop_map(|(a, b)| format!("(- {a} {b})")).boxed(),
            i().prop_map(|a| format!("(- {a})")).boxed(),
            (i(), i())
                .prop_map(|(a, b)| format!("(/ {a} (+ 2 (^ {b} 2)))"))
                .boxed(),
            (i(), 0..4i32)
                .prop_map(|(a, n)| format!("(^ {a} {n})"))
                .boxed(),
            i().prop_map(|a| format!("(^ (+ 3/2 (^ {a} 2)) -2)"))
                .boxed(),
            i().prop_map(|a| format!("(sin {a})")).boxed(),
            i().prop_map(|a| format!("(cos {a})")).boxed(),
            i().prop_map(|a| format!("(tan (* 1/4 (sin {a})))")).boxed(),
            i().prop_map(|a| format!("(sqrt (+ 1 (^ {a} 2)))")).boxed(),
            i().prop_map(|a| format!("(^ (sqrt (+ 1 (^ {a} 2))) 2)"))
                .boxed(),
            i().prop_map(|a| format!("(exp (sin {a}))")).boxed(),
            i().prop_map(|a| format!("(ln (+ 1 (^ {a} 2)))")).boxed(),
            i().prop_map(|a| format!("(exp (ln (+ 1 (^ {a} 2))))"))
                .boxed(),
            (i(), i())
                .prop_map(|(a, b)| format!("(atan2 {a} (+ 1/2 (^ {b} 2)))"))
                .boxed(),
            // patterns
            (i(), i(), i())
                .prop_map(|(k, x, r)| {
                    format!("(+ (* {k} (^ (sin {x}) 2) {r}) (* {r} (^ (cos {x}) 2) {k}))")
                })
                .boxed(),
            (i(), i())
                .prop_map(|(k, x)| format!("(- {k} (* {k} (^ (cos {x}) 2)))"))
                .boxed(),
            (i(), i(), i(), any::<bool>())
                .prop_map(|(a, b, r, p)| {
                    let op = if p { "+" } else { "-" };
                    format!("({op} (* {r} (cos {a}) (cos {b})) (* (sin {a}) {r} (sin {b})))")
                })
                .boxed(),
            (i(), i(), i(), any::<bool>())
                .prop_map(|(a, b, r, p)| {
                    let op = if p { "+" } else { "-" };
                    format!("({op} (* 2 {r} (sin {a}) (cos {b})) (* (cos {a}) 2 {r} (sin {b})))")
                })
                .boxed(),
            i().prop_map(|a| format!("(- {a} {a})")).boxed(),
            i().prop_map(|a| format!("(/ (+ 2 (^ {a} 2)) (+ (^ {a} 2) 2))"))
                .boxed(),
            (i(), i())
                .prop_map(|(a, b)| format!("(+ (* 2 {a} {b}) (* {b} 3 {a}))"))
                .boxed(),
            (i(), i(), i())
                .prop_map(|(a, b, c)| format!("(+ (* {a} {c}) (* {b} {c}))"))
                .boxed(),
        ];
        if !smooth {
            arms.push(i().prop_map(|a| format!("(abs {a})")).boxed());
            arms.push(i().prop_map(|a| format!("(sqrt (^ {a} 2))")).boxed());
            arms.push(
                (proptest::sample::select(VARS.to_vec()), i(), i())
                    .prop_map(|(c, a, b)| format!("(select {c} {a} {b})"))
                    .boxed(),
            );
        }
        proptest::strategy::Union::new(arms)
    })
}

fn point() -> impl Strategy<Value = [f64; 5]> {
    [
        -2.0..2.0f64,
        -2.0..2.0f64,
        -2.0..2.0f64,
        -2.0..2.0f64,
        -2.0..2.0f64,
    ]
}

fn values(a: &Arena, p: &[f64; 5]) -> Vec<f64> {
    let named: Vec<(&str, f64)> = VARS.iter().copied().zip(p.iter().copied()).collect();
    a.values(&named)
}

fn close(got: f64, want: f64, tol: f64) -> bool {
    (got - want).abs() <= tol * (1.0 + want.abs())
}

/// Build `src` raw, simplify with `runner`, compare values at `p`.
fn check_rewrite(src: &str, p: &[f64; 5], runner: &Runner) -> Result<(), TestCaseError> {
    let mut a = Arena::with_rules(RuleSet::NONE);
    let e = a.parse(src).unwrap();
    let vals = values(&a, p);
    let before = a.eval(e, &vals);
    prop_assume!(before.is_finite() && before.abs() < 1e6);
    let r = runner.run(&mut a, &[e]);
    let after = a.eval(r.roots[0], &values(&a, p));
    prop_assert!(
        close(after, before, TOL),
        "{src}\n  simplified to {}\n  got {after} want {before}",
        a.display(r.roots[0])
    );
    Ok(())
}

/// The rules a given rule needs to act at all.
fn rule_with_deps(name: &str) -> RuleSet {
    let (_, r) = RuleSet::NAMED
        .iter()
        .find(|(n, _)| *n == name)
        .copied()
        .unwrap();
    match name {
        "sign" => r | RuleSet::FOLD | RuleSet::DISTRIBUTE | RuleSet::COLLECT,
        "pythagoras" | "angle_sum" => r | RuleSet::COLLECT,
        _ => r,
    }
}

fn check_rule(name: &str, src: &str, p: &[f64; 5]) -> Result<(), TestCaseError> {
    check_rewrite(src, p, &Runner::with_rules(rule_with_deps(name)))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn fold_preserves_value(src in expr(false), p in point()) { check_rule("fold", &src, &p)?; }
    #[test]
    fn identity_preserves_value(src in expr(false), p in point()) { check_rule("identity", &src, &p)?; }
    #[test]
    fn collect_preserves_value(src in expr(false), p in point()) { check_rule("collect", &src, &p)?; }
    #[test]
    fn powers_preserve_value(src in expr(false), p in point()) { check_rule("powers", &src, &p)?; }
    #[test]
    fn distribute_preserves_value(src in expr(false), p in point()) { check_rule("distribute", &src, &p)?; }
    #[test]
    fn sign_preserves_value(src in expr(false), p in point()) { check_rule("sign", &src, &p)?; }
    #[test]
    fn sin2_cos2_is_one(src in expr(false), p in point()) { check_rule("pythagoras", &src, &p)?; }
    #[test]
    fn angle_sum_preserves_value(src in expr(false), p in point()) { check_rule("angle_sum", &src, &p)?; }
    #[test]
    fn elementary_preserves_value(src in expr(false), p in point()) { check_rule("elementary", &src, &p)?; }
    #[test]
    fn all_rules_and_rewrites_preserve_value(src in expr(false), p in point()) {
        check_rewrite(&src, &p, &Runner::default())?;
    }

    /// Parsing with every rule on equals parsing raw then running the runner.
    #[test]
    fn construction_equals_runner(src in expr(false), p in point()) {
        let mut a = Arena::new();
        let e = a.parse(&src).unwrap();
        let vals = values(&a, &p);
        let direct = a.eval(e, &vals);
        let mut raw = Arena::with_rules(RuleSet::NONE);
        let r = raw.parse(&src).unwrap();
        let before = raw.eval(r, &values(&raw, &p));
        prop_assume!(before.is_finite() && before.abs() < 1e6);
        prop_assert!(close(direct, before, TOL), "{src}: got {direct} want {before}");
    }

    /// Lowering with CSE and the second round equals lowering without either,
    /// and both equal the expression evaluator.
    #[test]
    fn cse_on_equals_cse_off(srcs in vec(expr(false), 1..4), p in point()) {
        let mut a = Arena::new();
        let ids: Vec<_> = srcs.iter().map(|s| a.parse(s).unwrap()).collect();
        let vals = values(&a, &p);
        let want = a.eval_many(&ids, &vals);
        prop_assume!(want.iter().all(|w| w.is_finite() && w.abs() < 1e6));
        let names: Vec<String> = (0..ids.len()).map(|i| format!("out{i}")).collect();
        let outs: Vec<(&str, _)> = names.iter().map(|n| n.as_str()).zip(ids.iter().copied()).collect();
        let on = a.lower(&outs, LowerOptions::default());
        let off = a.lower(&outs, LowerOptions::PLAIN);
        let got_on = on.eval_arena_values(&a, &vals);
        let got_off = off.eval_arena_values(&a, &vals);
        prop_assert!(on.op_count().total() <= off.op_count().total());
        for i in 0..ids.len() {
            prop_assert!(close(got_on[i], want[i], TOL), "{}: cse on got {} want {}\n{on}", srcs[i], got_on[i], want[i]);
            prop_assert!(close(got_off[i], want[i], TOL), "{}: cse off got {} want {}", srcs[i], got_off[i], want[i]);
        }
    }

    /// The second round (program → fresh arena → program) and the peephole
    /// optimiser preserve values, starting from raw (unsimplified) graphs.
    #[test]
    fn second_round_preserves_value(srcs in vec(expr(false), 1..4), p in point()) {
        let mut a = Arena::with_rules(RuleSet::NONE);
        let ids: Vec<_> = srcs.iter().map(|s| a.parse(s).unwrap()).collect();
        let vals = values(&a, &p);
        let want = a.eval_many(&ids, &vals);
        prop_assume!(want.iter().all(|w| w.is_finite() && w.abs() < 1e6));
        let names: Vec<String> = (0..ids.len()).map(|i| format!("out{i}")).collect();
        let outs: Vec<(&str, _)> = names.iter().map(|n| n.as_str()).zip(ids.iter().copied()).collect();
        let plain = a.lower(&outs, LowerOptions { second_round: false, optimize: false, ..LowerOptions::default() });
        let mut opt = plain.clone();
        opt.optimize();
        let second = plain.resimplify();
        for prog in [&plain, &opt, &second] {
            let got = prog.eval_arena_values(&a, &vals);
            for i in 0..ids.len() {
                prop_assert!(close(got[i], want[i], TOL), "{}: got {} want {}\n{prog}", srcs[i], got[i], want[i]);
            }
        }
    }

    /// Sharing reciprocals keeps every value (up to one rounding per
    /// division) and leaves at most one division per divisor: each
    /// expression divided by the same random divisor `d`, plus the
    /// expressions themselves.
    #[test]
    fn shared_reciprocals_preserve_value(srcs in vec(expr(false), 1..4), d in expr(false), p in point()) {
        let mut a = Arena::new();
        let mut ids: Vec<_> = srcs.iter().map(|s| a.parse(s).unwrap()).collect();
        let den = a.parse(&d).unwrap();
        let quotients: Vec<_> = ids.iter().map(|&e| a.div(e, den)).collect();
        ids.extend(quotients);
        let vals = values(&a, &p);
        let want = a.eval_many(&ids, &vals);
        prop_assume!(want.iter().all(|w| w.is_finite() && w.abs() < 1e6));
        let names: Vec<String> = (0..ids.len()).map(|i| format!("out{i}")).collect();
        let outs: Vec<(&str, _)> = names.iter().map(|n| n.as_str()).zip(ids.iter().copied()).collect();
        let mut p0 = a.lower(&outs, LowerOptions { optimize: false, ..LowerOptions::default() });
        p0.optimize();
        let divisions = p0.op_count().divs;
        let mut shared = p0.clone();
        let replaced = shared.share_reciprocals();
        // Each shared divisor had two or more divisions and keeps one.
        prop_assert!(shared.op_count().divs <= divisions);
        prop_assert!(replaced == 0 || shared.op_count().divs < divisions);
        let got = shared.eval_arena_values(&a, &vals);
        for i in 0..ids.len() {
            prop_assert!(close(got[i], want[i], TOL), "got {} want {}\n{shared}", got[i], want[i]);
        }
    }

    /// Factoring common multipliers out of sums (`a·x + a·y → a·(x + y)`)
    /// keeps every value and never adds an operation: each expression
    /// plus its multiples by a random factor `k`, summed in pairs, so
    /// shared factors are there to find.
    #[test]
    fn factoring_sums_preserves_value(srcs in vec(expr(false), 2..5), k in expr(false), p in point()) {
        let mut a = Arena::new();
        let mut ids: Vec<_> = srcs.iter().map(|s| a.parse(s).unwrap()).collect();
        let f = a.parse(&k).unwrap();
        let scaled: Vec<_> = ids.iter().map(|&e| a.mul(&[f, e])).collect();
        for w in scaled.windows(2) {
            let s = a.add(&[w[0], w[1]]);
            ids.push(s);
        }
        let vals = values(&a, &p);
        let want = a.eval_many(&ids, &vals);
        prop_assume!(want.iter().all(|w| w.is_finite() && w.abs() < 1e6));
        let names: Vec<String> = (0..ids.len()).map(|i| format!("out{i}")).collect();
        let outs: Vec<(&str, _)> = names.iter().map(|n| n.as_str()).zip(ids.iter().copied()).collect();
        let mut p0 = a.lower(&outs, LowerOptions { optimize: false, ..LowerOptions::default() });
        p0.optimize();
        let mut factored = p0.clone();
        factored.factor_sums();
        factored.optimize();
        let got = factored.eval_arena_values(&a, &vals);
        for i in 0..ids.len() {
            prop_assert!(close(got[i], want[i], TOL), "got {} want {}\n{factored}", got[i], want[i]);
        }
        // Through `lower` it is kept only where it lowers the count.
        let full = a.lower(&outs, LowerOptions::default());
        let mut reference = p0.clone();
        reference.share_reciprocals();
        prop_assert!(full.op_count().total() <= reference.op_count().total());
    }

    /// Sums and products rebuilt as trees of least latency keep every
    /// value and never add an operation or lengthen the critical path;
    /// the instructions written as late as their readers allow (in blocks
    /// of any size), or depth first from the outputs, give the same values
    /// bit for bit.
    #[test]
    fn balanced_and_scheduled_programs_keep_their_values(srcs in vec(expr(false), 1..5), p in point(), window in 1usize..40) {
        let mut a = Arena::new();
        let ids: Vec<_> = srcs.iter().map(|s| a.parse(s).unwrap()).collect();
        let vals = values(&a, &p);
        let want = a.eval_many(&ids, &vals);
        prop_assume!(want.iter().all(|w| w.is_finite() && w.abs() < 1e6));
        let names: Vec<String> = (0..ids.len()).map(|i| format!("out{i}")).collect();
        let outs: Vec<(&str, _)> = names.iter().map(|n| n.as_str()).zip(ids.iter().copied()).collect();
        let mut p0 = a.lower(&outs, LowerOptions { optimize: false, ..LowerOptions::default() });
        p0.optimize();
        let mut b = p0.clone();
        b.balance_products();
        b.balance_sums();
        prop_assert!(b.op_count().total() <= p0.op_count().total(), "{p0}\n{b}");
        prop_assert!(b.critical_path() <= p0.critical_path(), "{p0}\n{b}");
        let got = b.eval_arena_values(&a, &vals);
        for i in 0..ids.len() {
            prop_assert!(close(got[i], want[i], TOL), "got {} want {}\n{b}", got[i], want[i]);
        }
        for late in [b.scheduled_late(window), b.scheduled_depth_first()] {
            prop_assert_eq!(late.op_count(), b.op_count());
            let (x, y) = (b.eval_arena_values(&a, &vals), late.eval_arena_values(&a, &vals));
            for i in 0..ids.len() {
                prop_assert!(x[i].to_bits() == y[i].to_bits() || (x[i].is_nan() && y[i].is_nan()), "{b}\n{late}");
            }
        }
    }

    /// ∂e/∂v against a central difference with step 1e-5 (error ~1e-10
    /// truncation + 1e-11 rounding); tolerance 1e-5 relative.
    #[test]
    fn derivative_matches_central_difference(src in expr(true), p in point(), k in 0usize..5) {
        let mut a = Arena::new();
        let e = a.parse(&src).unwrap();
        let vals = values(&a, &p);
        let f0 = a.eval(e, &vals);
        prop_assume!(f0.is_finite() && f0.abs() < 1e4);
        let Some(v) = a.find_symbol(VARS[k]) else { return Ok(()) };
        let d = a.diff(e, v);
        let got = a.eval(d, &values(&a, &p));
        let h = 1e-5;
        let (mut pp, mut pm) = (p, p);
        pp[k] += h;
        pm[k] -= h;
        let want = (a.eval(e, &values(&a, &pp)) - a.eval(e, &values(&a, &pm))) / (2.0 * h);
        prop_assume!(want.abs() < 1e4);
        prop_assert!(close(got, want, 1e-5), "d/d{} {src}\n  = {}\n  got {got} want {want}", VARS[k], a.display(d));
    }

    /// d/dt f(q1(t), q2(t)) along q̇ = (v1, v2) equals Σ ∂f/∂q_i v_i.
    #[test]
    fn time_derivative_is_chain_rule(src in expr(true), p in point(), v in [-1.0..1.0f64, -1.0..1.0f64]) {
        let mut a = Arena::new();
        let e = a.parse(&src).unwrap();
        let (q1, q2) = (a.q(1), a.q(2));
        let qd = [a.qd(1), a.qd(2)];
        let dt = TimeDerivative::new().apply(&mut a, e).unwrap();
        let s1 = a.as_sym(q1).unwrap();
        let s2 = a.as_sym(q2).unwrap();
        let (d1, d2) = (a.diff(e, s1), a.diff(e, s2));
        let mut vals = values(&a, &p);
        for (i, &q) in qd.iter().enumerate() {
            vals[a.as_sym(q).unwrap().index()] = v[i];
        }
        let got = a.eval(dt, &vals);
        let want = a.eval(d1, &vals) * v[0] + a.eval(d2, &vals) * v[1];
        prop_assume!(want.is_finite() && want.abs() < 1e6);
        prop_assert!(close(got, want, TOL), "{src}: got {got} want {want}");
    }

    /// print → parse gives the same node in the same arena, and the same
    /// text in a fresh arena; raw arenas round-trip too.
    #[test]
    fn sexpr_round_trip(src in expr(false)) {
        for rules in [RuleSet::ALL, RuleSet::NONE] {
            let mut a = Arena::with_rules(rules);
            let e = a.parse(&src).unwrap();
            let text = a.to_sexpr_string(e);
            let again = a.parse(&text).unwrap();
            prop_assert_eq!(again, e, "{} printed as {} parsed as {}", src, text, a.display(again));
            let mut b = Arena::with_rules(rules);
            let e2 = b.parse(&text).unwrap();
            prop_assert_eq!(b.to_sexpr_string(e2), text);
        }
    }

    /// Substituting constants for some variables, then evaluating, equals
    /// evaluating at those values.
    #[test]
    fn substitution_preserves_value(src in expr(false), p in point(), mask in 0u8..32) {
        let mut a = Arena::new();
        let e = a.parse(&src).unwrap();
        let want = a.eval(e, &values(&a, &p));
        prop_assume!(want.is_finite() && want.abs() < 1e6);
        let mut map = rustc_hash::FxHashMap::default();
        for (k, name) in VARS.iter().enumerate() {
            if mask & (1 << k) != 0 && let Some(s) = a.find_symbol(name) {
                map.insert(s, a.constant(p[k]));
            }
        }
        let got_id = a.substitute(&[e], |s| map.get(&s).copied())[0];
        let got = a.eval(got_id, &values(&a, &p));
        prop_assert!(close(got, want, TOL), "{src} → {}: got {got} want {want}", a.display(got_id));
    }

    /// Multiplying out preserves values.
    #[test]
    fn expand_preserves_value(src in expr(false), p in point()) {
        let mut a = Arena::new();
        let e = a.parse(&src).unwrap();
        let want = a.eval(e, &values(&a, &p));
        prop_assume!(want.is_finite() && want.abs() < 1e6);
        let x = a.expand(&[e], 32)[0];
        let got = a.eval(x, &values(&a, &p));
        prop_assert!(close(got, want, TOL), "{src} → {}: got {got} want {want}", a.display(x));
    }

    /// Canonical forms are fixed points: re-running the rules changes nothing.
    #[test]
    fn canonical_form_is_a_fixed_point(src in expr(false)) {
        let mut a = Arena::new();
        let e = a.parse(&src).unwrap();
        let r = Runner::with_rules(RuleSet::ALL).run(&mut a, &[e]);
        prop_assert_eq!(r.roots[0], e, "{} → {} → {}", src, a.display(e), a.display(r.roots[0]));
    }
}

/// A generic forward-kinematics routine (planar-ish 3D chain), run on f64
/// and on Expr: the numeric twin must agree.
fn chain_tip<S: Scalar>(q: &[S], l: S) -> Vec3<S> {
    let mut r = Mat3::<S>::identity();
    let mut p = Vec3::<S>::zero();
    for (i, &qi) in q.iter().enumerate() {
        let axis = if i % 2 == 0 {
            eom_gen::sym::Axis::Z
        } else {
            eom_gen::sym::Axis::Y
        };
        r = r * Mat3::rot(axis, qi);
        p = p + r.mul_vec(Vec3::new(l, S::zero(), S::from_ratio(1, 2)));
    }
    p
}

proptest! {
    #[test]
    fn scalar_twin_agrees(q in vec(-3.0..3.0f64, 1..5), l in 0.1..2.0f64) {
        let want = chain_tip(&q, l);
        let cx = Context::new();
        let qs: Vec<Expr<'_>> = (0..q.len() as u32).map(|i| cx.q(i)).collect();
        let tip = chain_tip(&qs, cx.param("l").unwrap());
        let vals = {
            let a = cx.arena();
            a.values_with(|s: SymId| {
                let name = &a.symbol(s).name;
                if name == "l" { l } else { q[name[1..].parse::<usize>().unwrap()] }
            })
        };
        for i in 0..3 {
            let got = cx.eval(tip[i], &vals);
            prop_assert!(close(got, want[i], 1e-12), "tip[{i}]: got {got} want {}", want[i]);
        }
    }
}
