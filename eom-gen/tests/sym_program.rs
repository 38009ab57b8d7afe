//! Lowering: pinned programs, operation counts, the second optimisation
//! round, dead code, and determinism.

use eom_gen::sym::{
    Arena, Axis, Context, Expr, Instr, LowerOptions, Mat3, Op, Operand, Program, Scalar, SymKind,
    Symbol, Vec3,
};

/// Tip of a planar double pendulum: x = l1 sin q1 + l2 sin(q1+q2), y = −l1 cos q1 − l2 cos(q1+q2).
fn double_pendulum(a: &mut Arena) -> Vec<(&'static str, eom_gen::sym::Id)> {
    let x = a
        .parse("(+ (* l1 (sin q1)) (* l2 (sin (+ q1 q2))))")
        .unwrap();
    let y = a
        .parse("(- (+ (* l1 (cos q1)) (* l2 (cos (+ q1 q2)))))")
        .unwrap();
    vec![("x", x), ("y", y)]
}

#[test]
fn double_pendulum_program_is_pinned() {
    let mut a = Arena::new();
    let outs = double_pendulum(&mut a);
    let p = a.lower(&outs, LowerOptions::default());
    // Inputs sorted by kind then name: parameters first, then coordinates.
    let want = "\
inputs: in0=l1 in1=l2 in2=q1 in3=q2
(t0, t1) = sin_cos(in2)
t2 = in0 * t0
t3 = in2 + in3
(t4, t5) = sin_cos(t3)
t6 = in1 * t4
t7 = t2 + t6
t8 = in0 * t1
t9 = in1 * t5
t10 = t8 + t9
t11 = -t10
x = t7
y = t11
";
    assert_eq!(p.to_string(), want, "got\n{p}\nwant\n{want}");
    let c = p.op_count();
    assert_eq!(
        (c.adds, c.muls, c.trig, c.negs, c.total()),
        (3, 4, 2, 1, 10),
        "got {c}"
    );
}

#[test]
fn sin_cos_pair_only_when_both_are_needed() {
    let mut a = Arena::new();
    let s = a.parse("(* l (sin q1))").unwrap();
    let p = a.lower(&[("s", s)], LowerOptions::default());
    assert!(matches!(p.instrs[0].op, Op::Sin(_)), "got\n{p}");
    let c = a.parse("(* l (cos q1))").unwrap();
    let p = a.lower(&[("s", s), ("c", c)], LowerOptions::default());
    assert!(matches!(p.instrs[0].op, Op::SinCos(_)), "got\n{p}");
    assert_eq!(p.op_count().trig, 1);
}

#[test]
fn cse_shares_partial_products_across_outputs() {
    let mut a = Arena::new();
    let e1 = a.parse("(* m l (sin q1))").unwrap();
    let e2 = a.parse("(* 2 m l (sin q1))").unwrap();
    let e3 = a.parse("(+ (* m l (sin q1)) g)").unwrap();
    let p = a.lower(
        &[("e1", e1), ("e2", e2), ("e3", e3)],
        LowerOptions::default(),
    );
    let off = a.lower(&[("e1", e1), ("e2", e2), ("e3", e3)], LowerOptions::PLAIN);
    // m·l·sin once (2 muls + 1 sin), 2·(…) one mul, + g one add.
    assert_eq!(p.op_count().total(), 5, "got {}\n{p}", p.op_count());
    assert!(
        off.op_count().total() > p.op_count().total(),
        "cse off: {}",
        off.op_count()
    );
}

#[test]
fn division_and_powers_lower_to_one_div() {
    let mut a = Arena::new();
    let e = a.parse("(/ (* a (^ x 3)) (* b (^ y 2)))").unwrap();
    let p = a.lower(&[("e", e)], LowerOptions::default());
    let c = p.op_count();
    // x³ = x·x·x (2), a·x³ (1), y² (1), b·y² (1); one division
    assert_eq!((c.muls, c.divs), (5, 1), "got {c}\n{p}");
    let v = a.values(&[("a", 1.5), ("b", -0.5), ("x", 1.2), ("y", 0.7)]);
    let want = a.eval(e, &v);
    let got = p.eval_arena_values(&a, &v)[0];
    assert!(
        (got - want).abs() < 1e-14 * want.abs(),
        "got {got} want {want}"
    );
}

/// The prototype's lesson: terms that are equal only after CSE names them
/// cancel in the second round. Built raw so the arena does not see it.
#[test]
fn second_round_folds_temporaries_that_cancel() {
    let mut a = Arena::with_rules(eom_gen::sym::RuleSet::NONE);
    let e = a.parse("(+ (* (* x y) z) (- (* z (* y x))) w)").unwrap();
    let raw = a.lower(
        &[("e", e)],
        LowerOptions {
            optimize: false,
            second_round: false,
            ..LowerOptions::default()
        },
    );
    let opt = a.lower(
        &[("e", e)],
        LowerOptions {
            second_round: true,
            ..LowerOptions::default()
        },
    );
    assert_eq!(opt.to_string(), "inputs: in0=w\ne = in0\n", "got\n{opt}");
    assert!(raw.op_count().total() > 0, "raw:\n{raw}");
}

#[test]
fn optimize_applies_identities_and_removes_dead_code() {
    let x = Operand::Var(0);
    let t = Operand::Tmp;
    let one = Operand::Const(eom_gen::sym::Num::ONE);
    let mut p = Program {
        inputs: vec![Symbol {
            kind: SymKind::Param,
            name: "x".into(),
        }],
        instrs: vec![
            Instr {
                dst: 0,
                op: Op::Mul(x, one),
            }, // x
            Instr {
                dst: 1,
                op: Op::Sub(t(0), x),
            }, // 0
            Instr {
                dst: 2,
                op: Op::Add(t(1), x),
            }, // x
            Instr {
                dst: 3,
                op: Op::SinCos(t(2)),
            }, // only cos used
            Instr {
                dst: 5,
                op: Op::Neg(t(4)),
            },
            Instr {
                dst: 6,
                op: Op::Neg(t(5)),
            }, // cos x
            Instr {
                dst: 7,
                op: Op::Exp(x),
            }, // dead
        ],
        outputs: vec![("c".into(), t(6))],
        n_tmps: 8,
        products: Vec::new(),
    };
    let removed = p.optimize();
    let want = "inputs: in0=x\nt0 = cos(in0)\nc = t0\n";
    assert_eq!(p.to_string(), want, "got\n{p}");
    assert_eq!(removed, 6);
    assert_eq!(p.eval(&[0.3]), vec![0.3f64.cos()]);
}

/// A 6-link spatial chain built generically on `Expr`: enough to exercise
/// rotations, cross products and CSE.
fn chain_outputs(cx: &Context) -> Vec<(String, Expr<'_>)> {
    let l = cx.param("l").unwrap();
    let mut r = Mat3::<Expr<'_>>::identity();
    let mut p = Vec3::<Expr<'_>>::zero();
    let mut w = Vec3::<Expr<'_>>::zero();
    let mut outs = Vec::new();
    for i in 0..6u32 {
        let axis = [Axis::Z, Axis::Y, Axis::X][i as usize % 3];
        r = r * Mat3::rot(axis, cx.q(i));
        w = w + r.mul_vec(Vec3::unit(axis).scale(cx.u(i)));
        let v = w.cross(r.mul_vec(Vec3::new(l, Expr::zero(), Expr::zero())));
        p = p + r.mul_vec(Vec3::new(l, Expr::zero(), Expr::from_ratio(1, 2)));
        for k in 0..3 {
            outs.push((format!("p{i}_{k}"), p[k]));
            outs.push((format!("v{i}_{k}"), v[k]));
        }
    }
    outs
}

fn build_chain() -> (Program, Vec<String>) {
    let cx = Context::new();
    let outs = chain_outputs(&cx);
    let text: Vec<String> = outs.iter().map(|(_, e)| e.to_string()).collect();
    let named: Vec<(&str, Expr<'_>)> = outs.iter().map(|(n, e)| (n.as_str(), *e)).collect();
    (cx.lower(&named, LowerOptions::default()), text)
}

#[test]
fn building_twice_gives_identical_programs_and_text() {
    let (p1, t1) = build_chain();
    let (p2, t2) = build_chain();
    assert_eq!(t1, t2, "printed expressions differ");
    assert_eq!(p1, p2, "programs differ");
    assert_eq!(p1.to_string(), p2.to_string());
}

#[test]
fn printed_form_does_not_depend_on_construction_order() {
    let srcs = [
        "(+ (* l2 (cos (+ q1 q2))) (* l1 (cos q1)) (sin (- q2 q1)))",
        "(* m (+ a b) (sin c))",
        "(- (* (cos a) (cos b)) (* (sin b) (sin a)))",
    ];
    let mut fwd = Arena::new();
    let show = |a: &mut Arena, s: &str| {
        let id = a.parse(s).unwrap();
        a.to_sexpr_string(id)
    };
    let f: Vec<String> = srcs.iter().map(|s| show(&mut fwd, s)).collect();
    let mut rev = Arena::new();
    // Create the symbols in another order first.
    rev.parse("(+ c b a m l2 l1 q2 q1)").unwrap();
    let mut r: Vec<String> = srcs.iter().rev().map(|s| show(&mut rev, s)).collect();
    r.reverse();
    assert_eq!(f, r);
}

#[test]
fn chain_program_matches_expressions() {
    let cx = Context::new();
    let outs = chain_outputs(&cx);
    let named: Vec<(&str, Expr<'_>)> = outs.iter().map(|(n, e)| (n.as_str(), *e)).collect();
    let p = cx.lower(&named, LowerOptions::default());
    let vals = cx.arena().values_with(|s| 0.1 + 0.37 * s.index() as f64);
    let got = p.eval_arena_values(&cx.arena(), &vals);
    for (i, (name, e)) in outs.iter().enumerate() {
        let want = cx.eval(*e, &vals);
        assert!(
            (got[i] - want).abs() <= 1e-12 * (1.0 + want.abs()),
            "{name}: got {} want {want}",
            got[i]
        );
    }
    // Every rotation angle needs exactly one sin_cos.
    assert_eq!(p.op_count().trig, 6, "got {}", p.op_count());
}

#[test]
fn divisions_by_one_value_share_its_reciprocal() {
    // a/d, b/d, (a+b)/d → r = 1/d and three products; a/e alone stays.
    let (a, b, d, e) = (
        Operand::Var(0),
        Operand::Var(1),
        Operand::Var(2),
        Operand::Var(3),
    );
    let t = Operand::Tmp;
    let sym = |name: &str| Symbol {
        kind: SymKind::Param,
        name: name.into(),
    };
    let mut p = Program {
        inputs: vec![sym("a"), sym("b"), sym("d"), sym("e")],
        instrs: vec![
            Instr {
                dst: 0,
                op: Op::Div(a, d),
            },
            Instr {
                dst: 1,
                op: Op::Div(b, d),
            },
            Instr {
                dst: 2,
                op: Op::Add(a, b),
            },
            Instr {
                dst: 3,
                op: Op::Div(t(2), d),
            },
            Instr {
                dst: 4,
                op: Op::Div(a, e),
            },
        ],
        outputs: vec![
            ("p".into(), t(0)),
            ("q".into(), t(1)),
            ("r".into(), t(3)),
            ("s".into(), t(4)),
        ],
        n_tmps: 5,
        products: Vec::new(),
    };
    let x = [1.5, -2.25, 3.0, 7.0];
    let before = p.eval(&x);
    assert_eq!(p.share_reciprocals(), 3);
    let c = p.op_count();
    assert_eq!((c.divs, c.muls, c.adds), (2, 3, 1), "got\n{p}");
    for (got, want) in p.eval(&x).iter().zip(&before) {
        assert!(
            (got - want).abs() <= 2.0 * f64::EPSILON * want.abs(),
            "{got} vs {want}"
        );
    }
}

#[test]
fn squares_of_one_angle_with_unequal_coefficients_share_pythagoras() {
    // 0.005 cos²q + 0.3775 sin²q + 0.005 = 0.01 + 0.3725 sin²q (issue #28):
    // sin, the square, one multiplication and one addition.
    let mut a = Arena::new();
    let e = a
        .parse("(+ (* 0.005 (^ (cos q) 2)) (* 0.3775 (^ (sin q) 2)) 0.005)")
        .unwrap();
    let p = a.lower(&[("e", e)], LowerOptions::default());
    let c = p.op_count();
    assert_eq!(
        (c.trig, c.muls, c.adds, c.total()),
        (1, 2, 1, 4),
        "got {c}\n{p}"
    );
    for q in [-2.0f64, 0.3, 1.7] {
        let want = 0.005 * q.cos().powi(2) + 0.3775 * q.sin().powi(2) + 0.005;
        let got = p.eval(&[q])[0];
        assert!(
            (got - want).abs() <= 1e-15,
            "q = {q}: got {got} want {want}"
        );
    }
}

#[test]
fn a_difference_and_its_reverse_are_one_subtraction() {
    // x = a − b, y = 0.3 (b − a) = −0.3 (a − b): the negation folds into
    // the constant, bit for bit.
    let (a, b) = (Operand::Var(0), Operand::Var(1));
    let t = Operand::Tmp;
    let sym = |name: &str| Symbol {
        kind: SymKind::Param,
        name: name.into(),
    };
    let mut p = Program {
        inputs: vec![sym("a"), sym("b")],
        instrs: vec![
            Instr {
                dst: 0,
                op: Op::Sub(a, b),
            },
            Instr {
                dst: 1,
                op: Op::Sub(b, a),
            },
            Instr {
                dst: 2,
                op: Op::Mul(Operand::Const(eom_gen::sym::Num::from_f64(0.3)), t(1)),
            },
        ],
        outputs: vec![("x".into(), t(0)), ("y".into(), t(2))],
        n_tmps: 3,
        products: Vec::new(),
    };
    p.optimize();
    let c = p.op_count();
    assert_eq!((c.adds, c.muls, c.negs), (1, 1, 0), "got {c}\n{p}");
    let (va, vb) = (0.7f64, 2.3f64);
    assert_eq!(p.eval(&[va, vb]), vec![va - vb, 0.3 * (vb - va)]);
}

/// Eight products of inputs summed: as lowered, a chain of seven
/// additions (critical path 3 + 7·3 = 24 cycles in the model); rebuilt, a
/// balanced tree of depth 3 (3 + 3·3 = 12), the same seven additions and
/// eight multiplications, and the same value to rounding.
#[test]
fn a_sum_of_terms_ready_at_once_becomes_a_balanced_tree() {
    let mut a = Arena::new();
    let e = a
        .parse("(+ (* a b) (* c d) (* e f) (* g h) (* i j) (* k l) (* m n) (* o p))")
        .unwrap();
    let opts = LowerOptions {
        optimize: false,
        ..LowerOptions::default()
    };
    let chain = a.lower(&[("e", e)], opts);
    assert_eq!(chain.critical_path(), 24, "{chain}");
    let mut tree = chain.clone();
    assert_eq!(tree.balance_sums(), 1);
    assert_eq!(tree.critical_path(), 12, "{tree}");
    assert_eq!(tree.op_count(), chain.op_count());
    let x: Vec<f64> = (0..16).map(|i| 0.37 * i as f64 - 2.1).collect();
    let (want, got) = (chain.eval(&x)[0], tree.eval(&x)[0]);
    assert!((got - want).abs() <= 8.0 * f64::EPSILON * want.abs().max(1.0));
}

/// A term that comes late (a quotient) is added last, after the others
/// are summed while it is computed, and the negated terms become
/// subtractions: `(p/q)/(2 + r²) − x·y − z + w` has no negation left.
#[test]
fn a_late_term_is_added_last_and_negations_become_subtractions() {
    let mut a = Arena::new();
    let e = a
        .parse("(+ (/ (/ p q) (+ 2 (^ r 2))) (- (* x y)) (- z) w)")
        .unwrap();
    let opts = LowerOptions {
        optimize: false,
        ..LowerOptions::default()
    };
    let mut p = a.lower(&[("e", e)], opts);
    p.optimize();
    let before = p.clone();
    p.balance_sums();
    assert_eq!(p.op_count().negs, 0, "{p}");
    assert!(p.op_count().total() <= before.op_count().total());
    assert!(p.critical_path() <= before.critical_path(), "{before}\n{p}");
    // The root reads the division's result directly.
    let Some((_, Operand::Tmp(root))) = p.outputs.first() else {
        panic!("the output is computed: {p}")
    };
    let root = *root;
    let root_op = p.instrs.iter().find(|i| i.dst == root).map(|i| i.op);
    let divs: Vec<u32> = p
        .instrs
        .iter()
        .filter(|i| matches!(i.op, Op::Div(..)))
        .map(|i| i.dst)
        .collect();
    assert!(
        matches!(root_op, Some(Op::Add(x, y) | Op::Sub(x, y)) if [x, y].iter().any(|o| matches!(o, Operand::Tmp(t) if divs.contains(t)))),
        "{p}"
    );
    for pt in [
        [1.5, -0.5, 2.0, 0.25, 3.0, -1.0, 0.7],
        [-2.0, 1.0, 0.1, 0.2, 0.3, 0.4, 0.5],
    ] {
        let (want, got) = (before.eval(&pt)[0], p.eval(&pt)[0]);
        assert!(
            (got - want).abs() <= 1e-14 * want.abs().max(1.0),
            "{got} vs {want}"
        );
    }
}

/// A [`Product`] after the instructions replaces its blocks by `−A B`
/// (here `A` 3 × 3 and two blocks of 2 and 1 columns side by side, the
/// layout of `−M⁻¹ [∂ID/∂q ∂ID/∂u]`), counts `2 n² width` operations,
/// and leaves the other outputs alone (against the same product by
/// nalgebra, to rounding).
#[test]
fn a_product_replaces_its_blocks_by_minus_a_times_b() {
    use eom_gen::sym::Product;
    let (n, c1, c2) = (3usize, 2usize, 1usize);
    // Outputs: B1 (3×2) at 0, A (3×3) at 6, B2 (3×1) at 15, one more at 18.
    let len = n * c1 + n * n + n * c2 + 1;
    let inputs: Vec<Symbol> = (0..len)
        .map(|i| Symbol {
            kind: SymKind::Param,
            name: format!("x{i:02}"),
        })
        .collect();
    let outputs = (0..len)
        .map(|i| (format!("o{i}"), Operand::Var(i as u32)))
        .collect();
    let p = Program {
        inputs,
        instrs: Vec::new(),
        outputs,
        n_tmps: 0,
        products: vec![Product {
            a: 6,
            n,
            blocks: vec![(0, c1), (15, c2)],
        }],
    };
    let x: Vec<f64> = (0..len)
        .map(|i| ((i * 7 + 3) % 11) as f64 / 3.0 - 1.4)
        .collect();
    let y = p.eval(&x);
    let a = nalgebra::DMatrix::from_row_slice(n, n, &x[6..15]);
    let b1 = nalgebra::DMatrix::from_row_slice(n, c1, &x[0..6]);
    let b2 = nalgebra::DMatrix::from_row_slice(n, c2, &x[15..18]);
    let (w1, w2) = (-(&a * &b1), -(&a * &b2));
    for i in 0..n {
        for j in 0..c1 {
            assert!((y[i * c1 + j] - w1[(i, j)]).abs() < 1e-15, "B1 ({i}, {j})");
        }
        assert!((y[15 + i] - w2[(i, 0)]).abs() < 1e-15, "B2 ({i}, 0)");
    }
    assert_eq!(&y[6..15], &x[6..15], "A is read, not written");
    assert_eq!(y[18], x[18], "outputs outside the blocks are left alone");
    assert_eq!(p.op_count().total(), 2 * n * n * (c1 + c2));
}
