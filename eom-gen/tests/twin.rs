//! Numeric twins: every generated program, run by the evaluator, equals the
//! `f64` run of the same algorithm at random states, for every bundled
//! model (closed loops as their spanning trees). Also: the chosen forward
//! dynamics form is the cheaper one, and op counts grow linearly with the
//! number of bodies.

use eom_gen::mech::{FdForm, Numeric, Request, formulate};
use eom_gen::model::builder::n_link_chain;
use eom_gen::model::{Source, check};
use eom_gen::sym::{Program, SymKind};
use eom_gen::{System, check_file};

fn system(name: &str) -> System {
    let path = format!("{}/../models/{name}.ron", env!("CARGO_MANIFEST_DIR"));
    check_file(&path).unwrap_or_else(|r| panic!("{r}")).system
}

const MODELS: [&str; 13] = [
    "pendulum",
    "double_pendulum",
    "arm7",
    "heavy_top",
    "free_body",
    "fourbar",
    "slider_crank",
    "slider_crank_driven",
    "andrews",
    "bricard",
    "stewart",
    "stewart_driven",
    "rolling_disk",
];

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

struct Point {
    q: Vec<f64>,
    u: Vec<f64>,
    ud: Vec<f64>,
    tau: Vec<f64>,
    t: f64,
}

fn random_point(sys: &System, rng: &mut Rng) -> Point {
    let mut q: Vec<f64> = sys.q0().iter().map(|q| q + 0.8 * rng.next()).collect();
    for j in sys.free_joints() {
        let at = match j.kind.name() {
            "spherical" => Some(j.q_index),
            "free" => Some(j.q_index + 3),
            _ => None,
        };
        if let Some(a) = at {
            let n = q[a..a + 4].iter().map(|x| x * x).sum::<f64>().sqrt();
            q[a..a + 4].iter_mut().for_each(|x| *x /= n);
        }
    }
    let nu = sys.nu();
    Point {
        q,
        u: (0..nu).map(|_| 1.5 * rng.next()).collect(),
        ud: (0..nu).map(|_| rng.next()).collect(),
        tau: (0..nu).map(|_| rng.next()).collect(),
        t: rng.next().abs(),
    }
}

/// Runs a program with its inputs taken from the state.
fn run(p: &Program, sys: &System, x: &Point) -> Vec<f64> {
    let inputs: Vec<f64> = p
        .inputs
        .iter()
        .map(|s| match s.kind {
            SymKind::Coord(i) => x.q[i as usize],
            SymKind::Speed(i) => x.u[i as usize],
            SymKind::SpeedRate(i) => x.ud[i as usize],
            SymKind::Time => x.t,
            SymKind::Input => s
                .name
                .strip_prefix("tau")
                .and_then(|k| k.parse::<usize>().ok())
                .map_or(0.0, |k| x.tau[k]),
            SymKind::Param => sys
                .parameters
                .iter()
                .find(|p| p.name == s.name)
                .map_or(f64::NAN, |p| p.value.value),
            SymKind::CoordRate(_) => f64::NAN,
        })
        .collect();
    p.eval(&inputs)
}

fn assert_close(what: &str, got: &[f64], want: &[f64]) {
    assert_eq!(got.len(), want.len(), "{what}: lengths");
    let scale = want.iter().map(|x| x.abs()).fold(1.0, f64::max);
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= 1e-10 * scale,
            "{what}[{k}]: generated {g}, f64 algorithm {w}"
        );
    }
}

#[test]
fn generated_programs_equal_the_f64_algorithms() {
    let mut rng = Rng(0x1234_5678_9ABC_DEF1);
    for name in MODELS {
        let sys = system(name);
        let f = formulate(&sys, Request::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let num = Numeric::new(&sys).expect("numeric");
        for _ in 0..4 {
            let x = random_point(&sys, &mut rng);
            let what = |s: &str| format!("{name} {s}");
            let fd = num
                .forward_dynamics(&x.q, &x.u, x.t, &x.tau, &[])
                .expect("fd");
            assert_close(
                &what("forward dynamics"),
                &run(f.forward_dynamics.as_ref().expect("fd"), &sys, &x),
                &fd,
            );
            let terms = num.terms(&x.q, &x.u, x.t, &[]).expect("terms");
            let lower: Vec<f64> = (0..sys.nu())
                .flat_map(|i| (0..=i).map(move |j| (i, j)))
                .map(|(i, j)| terms.mass_matrix[i][j])
                .collect();
            assert_close(
                &what("mass matrix"),
                &run(f.mass_matrix.as_ref().expect("M"), &sys, &x),
                &lower,
            );
            assert_close(
                &what("bias"),
                &run(f.bias.as_ref().expect("b"), &sys, &x),
                &terms.bias,
            );
            let id = num
                .inverse_dynamics(&x.q, &x.u, &x.ud, x.t, &[])
                .expect("id");
            assert_close(
                &what("inverse dynamics"),
                &run(f.inverse_dynamics.as_ref().expect("id"), &sys, &x),
                &id,
            );
            assert_close(
                &what("qdot"),
                &run(&f.qdot, &sys, &x),
                &num.qdot(&x.q, &x.u),
            );
            let (t, v) = num.energy(&x.q, &x.u, x.t).expect("energy");
            assert_close(
                &what("energy"),
                &run(f.energy.as_ref().expect("E"), &sys, &x),
                &[t, v],
            );
            let h = num.momentum(&x.q, &x.u, x.t).expect("momentum");
            let want = [h.n.0[0], h.n.0[1], h.n.0[2], h.f.0[0], h.f.0[1], h.f.0[2]];
            assert_close(
                &what("momentum"),
                &run(f.momentum.as_ref().expect("h"), &sys, &x),
                &want,
            );
        }
    }
}

#[test]
fn the_cheaper_forward_dynamics_form_is_chosen() {
    for name in ["pendulum", "arm7", "heavy_top", "stewart"] {
        let f = formulate(&system(name), Request::default()).expect("formulates");
        let chosen = f
            .fd_candidates
            .iter()
            .find(|(form, _)| *form == f.fd_form)
            .map(|(_, c)| c.total());
        let best = f.fd_candidates.iter().map(|(_, c)| c.total()).min();
        assert_eq!(chosen, best, "{name}: {:?}", f.fd_candidates);
        assert_eq!(f.fd_candidates.len(), 2);
        let _ = FdForm::Aba;
    }
}
