//! Pinned examples: one or more per construction-time simplification rule.
//! Each case parses the left side with every rule on and checks the printed
//! canonical form (`got … want …`).

use eom_gen::sym::{Arena, RuleSet};

/// Parse `src` and `want` in one arena; they must be the same node.
fn check(src: &str, want: &str) {
    let mut a = Arena::new();
    let got = a.parse(src).unwrap();
    let w = a.parse(want).unwrap();
    assert_eq!(
        got,
        w,
        "{src}: got {} want {}",
        a.display(got),
        a.display(w)
    );
}

/// The printed form of `src` after construction with every rule on.
fn show(src: &str) -> String {
    let mut a = Arena::new();
    let id = a.parse(src).unwrap();
    a.to_sexpr_string(id)
}

#[test]
fn fold_constants() {
    check("(+ 1 2 x)", "(+ 3 x)");
    check("(* 1/2 4 x)", "(* 2 x)");
    check("(+ 1/3 1/6)", "1/2");
    check("(* 1/12 12)", "1");
    check("(sin 0)", "0");
    check("(cos 0)", "1");
    check("(^ 2 -2)", "1/4");
    check("(sqrt 9/4)", "3/2");
    check("(exp 0)", "1");
    check("(ln 1)", "0");
    check("(select 1 a b)", "a");
    check("(select -1 a b)", "b");
}

#[test]
fn no_nonfinite_from_folding() {
    assert_eq!(show("(/ 1 0)"), "(^ 0 -1)");
    assert_eq!(show("(sqrt -4)"), "(sqrt -4)");
    assert_eq!(show("(ln 0)"), "(ln 0)");
    assert_eq!(show("(ln -1)"), "(ln -1)");
}

#[test]
fn zero_and_one_identities() {
    check("(+ x 0)", "x");
    check("(* x 1)", "x");
    check("(* x 0)", "0");
    check("(^ x 0)", "1");
    check("(^ x 1)", "x");
    check("(select c a a)", "a");
}

#[test]
fn x_minus_x_and_x_over_x() {
    check("(- x x)", "0");
    check("(- (* 2 (sin q1) l) (* (sin q1) l 2))", "0");
    check("(/ x x)", "1");
    check("(/ (* a b) (* b a))", "1");
    check("(- (+ a b) (+ b a))", "0");
}

#[test]
fn like_terms_collect() {
    check("(+ (* 2 x) (* 3 x))", "(* 5 x)");
    check("(+ x x x)", "(* 3 x)");
    check("(+ (* 1/2 m l) (* 1/2 l m))", "(* l m)");
    check("(+ (* 0.1 x) (* 0.2 x))", "(* 0.30000000000000004 x)");
}

#[test]
fn powers() {
    check("(* x x)", "(^ x 2)");
    check("(* x (^ x 2))", "(^ x 3)");
    check("(^ (^ x 2) 3)", "(^ x 6)");
    check("(^ (* 2 x) 2)", "(* 4 (^ x 2))");
    check("(^ (sqrt x) 2)", "x");
    check("(sqrt (^ x 2))", "(abs x)");
    check("(sqrt (^ x 4))", "(^ x 2)");
    check("(/ (^ x 3) x)", "(^ x 2)");
}

#[test]
fn distribute_numeric_coefficients() {
    check("(* 2 (+ a b))", "(+ (* 2 a) (* 2 b))");
    check("(- (- a b))", "(+ b (* -1 a))");
    check("(- a (- a b))", "b");
}

#[test]
fn sign_normalisation() {
    check("(sin (- x))", "(- (sin x))");
    check("(cos (- x))", "(cos x)");
    check("(tan (- x))", "(- (tan x))");
    check("(abs (- x))", "(abs x)");
    check("(cos (- a b))", "(cos (- b a))");
    check("(+ (sin (- a b)) (sin (- b a)))", "0");
    check("(sin (* -2 x))", "(* -1 (sin (* 2 x)))");
}

#[test]
fn sin2_cos2_is_one() {
    check("(+ (^ (sin x) 2) (^ (cos x) 2))", "1");
    check("(+ (* k (^ (sin x) 2) r) (* k (^ (cos x) 2) r))", "(* k r)");
    check(
        "(+ (* 3 (^ (sin x) 2) r) (* 3 (^ (cos x) 2) r) y)",
        "(+ (* 3 r) y)",
    );
    // nested: the argument is itself a sum, and the factor R a product
    check(
        "(+ (* (^ (sin (+ q1 q2)) 2) m (^ l 2)) (* m (^ l 2) (^ (cos (+ q2 q1)) 2)))",
        "(* m (^ l 2))",
    );
    // built up from products rather than powers
    check("(+ (* (sin x) (sin x) a) (* a (cos x) (cos x)))", "a");
    check("(- 1 (^ (sin x) 2))", "(^ (cos x) 2)");
    check("(- 2 (* 2 (^ (cos x) 2)))", "(* 2 (^ (sin x) 2))");
    // unequal coefficients are left alone
    assert_eq!(show("(+ (* 2 (^ (sin x) 2)) (^ (cos x) 2))"), {
        let mut a = Arena::with_rules(RuleSet::ALL.without(RuleSet::PYTHAGORAS));
        let id = a.parse("(+ (* 2 (^ (sin x) 2)) (^ (cos x) 2))").unwrap();
        a.to_sexpr_string(id)
    });
}

#[test]
fn angle_sums_contract() {
    check(
        "(- (* (cos a) (cos b)) (* (sin a) (sin b)))",
        "(cos (+ a b))",
    );
    check(
        "(+ (* (cos a) (cos b)) (* (sin a) (sin b)))",
        "(cos (- a b))",
    );
    check(
        "(+ (* (sin a) (cos b)) (* (cos a) (sin b)))",
        "(sin (+ a b))",
    );
    check(
        "(- (* (sin a) (cos b)) (* (cos a) (sin b)))",
        "(sin (- a b))",
    );
    check(
        "(- (* 2 l (cos a) (cos b)) (* 2 l (sin a) (sin b)))",
        "(* 2 l (cos (+ a b)))",
    );
    // chained: three parallel-axis rotations collapse to one angle
    check(
        "(- (* (cos (+ q1 q2)) (cos q3)) (* (sin (+ q1 q2)) (sin q3)))",
        "(cos (+ q1 q2 q3))",
    );
}

#[test]
fn elementary() {
    check("(exp (ln x))", "x");
    check("(ln (exp x))", "x");
    check("(abs (abs x))", "(abs x)");
    check("(abs (sqrt x))", "(sqrt x)");
    check("(abs (^ x 2))", "(^ x 2)");
}

#[test]
fn canonical_order_is_commutative() {
    check("(+ a b c)", "(+ c b a)");
    check("(* a (+ b c))", "(* (+ c b) a)");
    check("(+ a (+ b c))", "(+ (+ a b) c)");
}

#[test]
fn long_sums_stay_one_shared_child() {
    // Sums longer than the flatten limit (8) are not copied into an
    // enclosing sum: recursively built quantities grow linearly.
    let mut a = Arena::new();
    let long = a.parse("(+ a b c d e f g h i)").unwrap();
    let x = a.parse("x").unwrap();
    let s = a.add2(long, x);
    assert_eq!(
        a.to_sexpr_string(s).matches('(').count(),
        2,
        "got {}",
        a.display(s)
    );
    let short = a.parse("(+ a b c)").unwrap();
    let s = a.add2(short, x);
    assert_eq!(
        a.to_sexpr_string(s).matches('(').count(),
        1,
        "got {}",
        a.display(s)
    );
    // with the limit lifted, everything flattens
    a.set_flatten_limit(usize::MAX);
    let s = a.add2(long, x);
    assert_eq!(
        a.to_sexpr_string(s).matches('(').count(),
        1,
        "got {}",
        a.display(s)
    );
}

#[test]
fn op_estimate_counts_like_lowering() {
    let mut a = Arena::new();
    // 2 products (1 mul each), 1 addition, one sin/cos pair
    let e = a.parse("(+ (* l (sin q)) (* m (cos q)))").unwrap();
    assert_eq!(a.op_estimate(&[e]), 4);
    let mut raw = Arena::with_rules(RuleSet::NONE);
    let e = raw.parse("(* -1 -1 x)").unwrap();
    assert_eq!(raw.op_estimate(&[e]), 0);
}

/// Mass matrix of a planar double pendulum with point masses at the link
/// ends, as M = Σ m_k J_kᵀ J_k from the Jacobians of the mass positions.
/// Analytic answer (e.g. any textbook): M11 = m1 l1² + m2 (l1² + l2² + 2 l1 l2 cos q2),
/// M12 = m2 (l2² + l1 l2 cos q2), M22 = m2 l2². Reaching it needs expansion,
/// like-term collection, sin²+cos² = 1, angle-difference contraction and
/// cos(−x) = cos x together.
#[test]
fn double_pendulum_mass_matrix_simplifies_to_the_textbook_form() {
    let mut a = Arena::new();
    let p1 = [
        a.parse("(* l1 (sin q1))").unwrap(),
        a.parse("(- (* l1 (cos q1)))").unwrap(),
    ];
    let p2 = [
        a.parse("(+ (* l1 (sin q1)) (* l2 (sin (+ q1 q2))))")
            .unwrap(),
        a.parse("(- (+ (* l1 (cos q1)) (* l2 (cos (+ q1 q2)))))")
            .unwrap(),
    ];
    let qs = [a.q(1), a.q(2)].map(|q| a.as_sym(q).unwrap());
    let (j1, j2) = (a.jacobian(&p1, &qs), a.jacobian(&p2, &qs));
    let (m1, m2) = (a.param("m1").unwrap(), a.param("m2").unwrap());
    let mut m = [[a.constant(0.0); 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            let mut terms = Vec::new();
            for k in 0..2 {
                let t1 = a.mul(&[m1, j1[k][i], j1[k][j]]);
                let t2 = a.mul(&[m2, j2[k][i], j2[k][j]]);
                terms.extend([t1, t2]);
            }
            let s = a.add(&terms);
            m[i][j] = a.expand(&[s], 64)[0];
        }
    }
    let want = [
        "(+ (* m1 (^ l1 2)) (* m2 (^ l1 2)) (* m2 (^ l2 2)) (* 2 m2 l1 l2 (cos q2)))",
        "(+ (* m2 (^ l2 2)) (* m2 l1 l2 (cos q2)))",
        "(* m2 (^ l2 2))",
    ];
    for (got, want) in [m[0][0], m[0][1], m[1][1]].into_iter().zip(want) {
        let w = a.parse(want).unwrap();
        assert_eq!(got, w, "got {} want {}", a.display(got), a.display(w));
    }
    assert_eq!(m[0][1], m[1][0], "M is symmetric");
}

#[test]
fn structural_zeros_and_ones_reach_the_program_as_constants() {
    use eom_gen::sym::{Context, LowerOptions, Mat3, Op, Operand};
    let cx = Context::new();
    let r = Mat3::rot(eom_gen::sym::Axis::Z, cx.q(1))
        * Mat3::rot(eom_gen::sym::Axis::Z, cx.q(2))
        * Mat3::rot(eom_gen::sym::Axis::Z, cx.q(3));
    let names: Vec<String> = (0..9).map(|k| format!("r{}{}", k / 3, k % 3)).collect();
    let outs: Vec<(&str, _)> = (0..9)
        .map(|k| (names[k].as_str(), r.0[k / 3][k % 3]))
        .collect();
    let p = cx.lower(&outs, LowerOptions::default());
    let consts: Vec<&str> = p
        .outputs
        .iter()
        .filter(|(_, o)| matches!(o, Operand::Const(_)))
        .map(|(n, _)| n.as_str())
        .collect();
    assert_eq!(consts, ["r02", "r12", "r20", "r21", "r22"], "got\n{p}");
    // q1 + q2 + q3 (2 adds), one sin_cos, one negation
    let c = p.op_count();
    assert_eq!(
        (c.adds, c.trig, c.negs, c.total()),
        (2, 1, 1, 4),
        "got {c}\n{p}"
    );
    assert!(p.instrs.iter().any(|i| matches!(i.op, Op::SinCos(_))));
}
