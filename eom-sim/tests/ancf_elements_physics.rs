//! The ANCF elements other than `Cable2D` at system level (chains built by
//! the large-model runtime, solved by its Newton and generalized-α), each
//! against physics it must reproduce:
//!
//! - **Small deflection** (`Cable2D`, `Cable2DGreen`, `Cable3D` bent in
//!   `y` and in `z`): a cantilever under a tip force deflects
//!   `PL³/(3EI)` and under a uniform load `wL⁴/(8EI)` (Euler–Bernoulli;
//!   the cubic Hermite element is nodally exact for both, so already one
//!   element must match, to the geometric nonlinearity `(δ/L)²`).
//! - **`Cable2DGreen` at large deflection**: its strains (`ε_G = ½(r'·r' −
//!   1)`, `κ = r' × r''`) are rotation-invariant, so for a nearly
//!   inextensible cable it follows Mattiasson's elastica at PL²/EI up to
//!   10 as `Cable2D` does. Where it departs is finite stretch: a pull `P`
//!   stretches it to `λ` with `EA λ(λ² − 1)/2 = P` (not `λ − 1 = P/EA`),
//!   and its curvature counts `λ²` times the rotation rate, so a cantilever
//!   that stretches by a few per cent bends less than the extensible
//!   elastica; both are checked and measured here.
//! - **`Cable3D`**: bent out of plane it is the planar cable (tip in `z`
//!   equals tip in `y` to round-off, and Mattiasson's elastica); loaded
//!   along a diagonal of the `y–z` plane it bends as the planar elastica
//!   in the plane of the load; the whole static problem turned by a
//!   rotation gives the turned solution (objectivity), and a deformed chain
//!   turned rigidly keeps its strain energy and turns its elastic forces; a
//!   falling 3D rope (Berzeri and Shabana's pendulum, pinned, released
//!   horizontal with a spin about the vertical) keeps its energy to the
//!   integrator's O(h²).
//! - **`Beam2D`** (with its locking remedy: ν = 0 in the normal-strain
//!   terms, Cowper's shear correction): the clamped cantilever under a tip
//!   force converges with the mesh to Timoshenko's `PL³/(3EI) +
//!   PL/(k_s G A)` at second order (constant bending strain per element),
//!   for ν = 0 and 0.3 alike (no Poisson locking), at L/h = 10 and 100 (no
//!   shear locking); at large deflection (PL²/EI = 3, L/h = 100) it
//!   converges to Mattiasson's elastica.
//! - **Distributed load** (`StructuralModel::add_distributed_load`, the
//!   model's `distributed_load`): `wL⁴/(8EI)` at small load, and at
//!   wL³/EI = 1, 3, 10 the extensible elastica under the same load
//!   (shooting, `large::elastica::extensible_cantilever_distributed`).

use eom_sim::elements::{Cable2D, Cable2DGreen, ElementKernel};
use eom_sim::large::ancf::{Chain, ChainSpec, Section, Support, chain};
use eom_sim::large::elastica::{
    extensible_cantilever, extensible_cantilever_distributed, mattiasson,
};
use eom_sim::large::{
    AlphaOptions, Elements, GeneralizedAlpha, ModelBuilder, State, StaticOptions, solve_static,
};

fn spec(kernel: &str, elements: usize, end: [f64; 3], section: Section) -> ChainSpec {
    ChainSpec {
        kernel: kernel.parse().unwrap_or_else(|e| panic!("{e}")),
        start: [0.0; 3],
        end,
        elements,
        section,
        start_support: Support::Clamped,
        end_support: Support::Free,
        end_force: [0.0; 3],
        end_mass: 0.0,
        gravity: [0.0; 3],
    }
}

fn build(spec: &ChainSpec) -> Chain {
    chain(spec).unwrap_or_else(|e| panic!("{e}"))
}

/// Static equilibrium; the tip and the full solution.
fn solve(ch: &Chain, load_steps: usize) -> ([f64; 3], Vec<f64>) {
    let opts = StaticOptions {
        load_steps,
        ..StaticOptions::default()
    };
    let sol = solve_static(&ch.model, &opts).unwrap_or_else(|e| panic!("{e}"));
    (ch.node_position(&sol.q, ch.nodes - 1), sol.q)
}

/// A cable section with `EI = 1`, `EA = ea`, mass per length `rhoA = 1`.
fn cable_section(ea: f64) -> Section {
    Section {
        e: 1.0,
        rho: 1.0 / ea,
        area: ea,
        inertia: 1.0,
        ..Section::default()
    }
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

#[test]
fn small_deflection_cantilevers_are_euler_bernoulli() {
    // L = 1.5 m, EI = 1, EA = 1e4: a tip force P = 1e-5 N and a uniform
    // load w = 1e-5 N/m (as gravity on rhoA = 1) deflect by 1e-6 of L, so
    // the geometric nonlinearity is 1e-12 relative.
    let l: f64 = 1.5;
    let (p, w) = (1e-5, 1e-5);
    let tip_eb = p * l.powi(3) / 3.0;
    let uni_eb = w * l.powi(4) / 8.0;
    for (kernel, dir) in [
        ("Cable2D", 1),
        ("Cable2DGreen", 1),
        ("Cable3D", 1),
        ("Cable3D", 2),
    ] {
        for n in [1usize, 2, 5] {
            let mut s = spec(kernel, n, [l, 0.0, 0.0], cable_section(1e4));
            s.end_force[dir] = -p;
            let (tip, _) = solve(&build(&s), 1);
            let r1 = -tip[dir] / tip_eb - 1.0;
            let mut s = spec(kernel, n, [l, 0.0, 0.0], cable_section(1e4));
            // rhoA = 1 kg/m: gravity g is the load w per length.
            s.gravity[dir] = -w;
            let (tip_u, _) = solve(&build(&s), 1);
            let r2 = -tip_u[dir] / uni_eb - 1.0;
            println!(
                "{kernel} (bent along axis {dir}), {n} elements: tip force / EB − 1 = {r1:.1e}, uniform load / EB − 1 = {r2:.1e}"
            );
            assert!(
                r1.abs() < 1e-6 && r2.abs() < 1e-6,
                "{kernel} {dir} {n}: {r1} {r2}"
            );
            // Nothing moves out of the plane of the load.
            let other = 3 - dir;
            assert!(tip[other].abs() < 1e-15 && tip_u[other].abs() < 1e-15);
        }
    }
}

#[test]
fn green_cable_follows_the_elastica_while_the_strain_is_small() {
    // Nearly inextensible (EI = 1, EA = 1e6, L = 1), 32 elements: the
    // Green cable against Mattiasson's inextensible elastica at PL²/EI = 1
    // … 10, to the same bound as Gerstmayr and Irschik's cable
    // (`ancf_cable.rs`): the strain measures differ at O(ε) = P/EA = 1e-5.
    for alpha in [1.0, 2.0, 3.0, 5.0, 7.0, 10.0] {
        let mut s = spec("Cable2DGreen", 32, [1.0, 0.0, 0.0], cable_section(1e6));
        s.end_force = [0.0, -alpha, 0.0];
        let (tip, _) = solve(&build(&s), 20);
        let (u, w, _) = mattiasson(alpha);
        let (u_h, w_h) = (1.0 - tip[0], -tip[1]);
        println!(
            "Cable2DGreen PL²/EI = {alpha:>4}: u/L {u_h:.7} (Mattiasson {u:.7}), w/L {w_h:.7} (Mattiasson {w:.7})"
        );
        assert!(
            (u_h - u).abs() < 3e-5 && (w_h - w).abs() < 3e-5,
            "alpha {alpha}"
        );
    }
}

/// A planar cable of `n` elements of kernel `E` (parameters `EA`, `EI`)
/// along x from the origin, held there in position and in the direction of
/// its gradient (`r'_y = 0`) but not in the gradient's length: the ANCF
/// clamp holding the whole gradient also holds the axial strain at the
/// root at zero, which neither the elastica nor the pulled bar has (a
/// boundary layer that only the mesh resolves). Solves for the dead force
/// `f` on the free end and returns the tip.
fn sliding_clamp<E: ElementKernel<8, 6> + 'static>(
    n: usize,
    l: f64,
    ea: f64,
    ei: f64,
    f: [f64; 2],
) -> [f64; 2] {
    let le = l / n as f64;
    let nodes = n + 1;
    let mut q0 = vec![0.0; 4 * nodes];
    for j in 0..nodes {
        q0[4 * j] = j as f64 * le;
        q0[4 * j + 2] = 1.0;
    }
    let mut els = Elements::<E, 8, 6>::new();
    for e in 0..n {
        let conn: [usize; 8] = std::array::from_fn(|i| 4 * e + i);
        let reference = conn.map(|c| q0[c]);
        els.push(conn, [le, ea, ei, 1.0, 0.0, 0.0], reference);
    }
    let model = ModelBuilder::new(q0)
        .fix(0)
        .fix(1)
        .fix(3)
        .point_load(4 * n, f[0])
        .point_load(4 * n + 1, f[1])
        .elements(els)
        .build();
    let opts = StaticOptions {
        load_steps: 20,
        ..StaticOptions::default()
    };
    let sol = solve_static(&model, &opts).unwrap_or_else(|e| panic!("{e}"));
    [sol.q[4 * n], sol.q[4 * n + 1]]
}

#[test]
fn green_cable_departs_from_the_elastica_under_finite_stretch() {
    // Pure pull P on a bar of EA = 1 (EI = 1e-2): the Green cable
    // stretches to λ with λ(λ² − 1)/2 = P/EA (its axial force is
    // EA ε_G ∂ε_G/∂λ), Gerstmayr and Irschik's to λ = 1 + P/EA.
    let (l, ea) = (1.0, 1.0);
    for load in [0.01, 0.1, 0.3] {
        let mut lam: f64 = 1.0 + load;
        for _ in 0..50 {
            lam -= (0.5 * lam * (lam * lam - 1.0) - load) / (0.5 * (3.0 * lam * lam - 1.0));
        }
        let green = sliding_clamp::<Cable2DGreen>(4, l, ea, 1e-2, [load, 0.0])[0];
        let gi = sliding_clamp::<Cable2D>(4, l, ea, 1e-2, [load, 0.0])[0];
        println!(
            "pull P/EA = {load}: Green λ = {green:.12} (closed form {lam:.12}), Gerstmayr–Irschik λ = {gi:.12} (closed form {:.12})",
            1.0 + load
        );
        assert!((green - lam * l).abs() < 1e-10, "{green} {lam}");
        assert!((gi - (1.0 + load) * l).abs() < 1e-10, "{gi}");
    }
    // Bending with stretch: EI = 1, EA = 100 N (a rubber-like cord),
    // L = 1, |P|L²/EI = 5 at 45° below the axis (tension and bending
    // together): the extensible elastica of the same EA, EI against both
    // cables at 64 elements. Gerstmayr and Irschik's cable has the
    // elastica's strain measures and converges to it; the Green one stays
    // off by the stretch's effect on its strain measures (measured:
    // 9.3e-11 m and 1.31e-2 m, 1.3 % of L, at a stretch of about 3 %).
    let f = [5.0 / 2f64.sqrt(), -5.0 / 2f64.sqrt()];
    let ext = extensible_cantilever(1.0, 100.0, 1.0, f)
        .unwrap_or_else(|| panic!("the elastica reference failed"));
    let mut errors = Vec::new();
    for (kernel, tip) in [
        ("Cable2D", sliding_clamp::<Cable2D>(64, 1.0, 100.0, 1.0, f)),
        (
            "Cable2DGreen",
            sliding_clamp::<Cable2DGreen>(64, 1.0, 100.0, 1.0, f),
        ),
    ] {
        let e = ((tip[0] - ext.x).powi(2) + (tip[1] - ext.y).powi(2)).sqrt();
        println!(
            "{kernel}: tip ({:.9}, {:.9}) vs extensible elastica ({:.9}, {:.9}): {e:.2e} m",
            tip[0], tip[1], ext.x, ext.y
        );
        errors.push(e);
    }
    assert!(errors[0] < 1e-9, "{errors:?}");
    assert!(errors[1] > 1e-2, "{errors:?}");
}

/// Rotation by angle `a` about the unit axis `k` (Rodrigues).
fn rotation(k: [f64; 3], a: f64) -> [[f64; 3]; 3] {
    let (s, c) = a.sin_cos();
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = k[i] * k[j] * (1.0 - c) + if i == j { c } else { 0.0 };
        }
    }
    r[0][1] -= s * k[2];
    r[0][2] += s * k[1];
    r[1][0] += s * k[2];
    r[1][2] -= s * k[0];
    r[2][0] -= s * k[1];
    r[2][1] += s * k[0];
    r
}

fn apply(r: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| (0..3).map(|j| r[i][j] * v[j]).sum())
}

#[test]
fn cable3d_bent_out_of_plane_is_the_planar_elastica() {
    // Nearly inextensible (EI = 1, EA = 1e6, L = 1), 32 elements, PL²/EI = 3:
    // bent in x–y and in x–z the tips agree to round-off and both are
    // Mattiasson's elastica; loaded along the diagonal (0, −1, −1)/√2 the
    // tip stays in the plane of the load (y = z) and is the same elastica
    // there.
    let alpha = 3.0;
    let (u, w, _) = mattiasson(alpha);
    let mut tips = Vec::new();
    for f in [
        [0.0, -alpha, 0.0],
        [0.0, 0.0, -alpha],
        [0.0, -alpha / 2f64.sqrt(), -alpha / 2f64.sqrt()],
    ] {
        let mut s = spec("Cable3D", 32, [1.0, 0.0, 0.0], cable_section(1e6));
        s.end_force = f;
        let (tip, _) = solve(&build(&s), 10);
        println!("Cable3D, tip force {f:?}: tip {tip:?}");
        tips.push(tip);
    }
    let (ty, tz, td) = (tips[0], tips[1], tips[2]);
    assert!((ty[0] - tz[0]).abs() < 1e-12 && (ty[1] - tz[2]).abs() < 1e-12);
    assert!(ty[2].abs() < 1e-14 && tz[1].abs() < 1e-14);
    assert!((td[1] - td[2]).abs() < 1e-12, "{td:?}");
    let w_d = (td[1] * td[1] + td[2] * td[2]).sqrt();
    assert!((td[0] - ty[0]).abs() < 1e-10 && (w_d + ty[1]).abs() < 1e-10);
    println!("Mattiasson u/L {u:.7}, w/L {w:.7}");
    assert!((1.0 - ty[0] - u).abs() < 3e-5 && (-ty[1] - w).abs() < 3e-5);
}

#[test]
fn cable3d_is_objective() {
    // The whole static problem turned by a rotation R (the clamped axis
    // along R x, the tip force R f) has the turned solution: every node
    // at R times its place in the unturned problem, to round-off of the
    // Newton tolerance. A general load (f has components along all three
    // axes) and a general rotation make the test fully spatial.
    let k = {
        let v: [f64; 3] = [0.3, -0.5, 0.81];
        let n = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        v.map(|x| x / n.sqrt())
    };
    let r = rotation(k, 1.1);
    let l = 1.0;
    let f = [-0.5, -2.0, 1.2];
    let n = 16;
    let mut s0 = spec("Cable3D", n, [l, 0.0, 0.0], cable_section(1e3));
    s0.end_force = f;
    let c0 = build(&s0);
    let (_, q0) = solve(&c0, 10);
    let mut s1 = spec("Cable3D", n, apply(&r, [l, 0.0, 0.0]), cable_section(1e3));
    s1.end_force = apply(&r, f);
    let c1 = build(&s1);
    let (_, q1) = solve(&c1, 10);
    let mut worst: f64 = 0.0;
    for node in 0..c0.nodes {
        let p0 = apply(&r, c0.node_position(&q0, node));
        let p1 = c1.node_position(&q1, node);
        worst = worst.max(dist(p0, p1));
    }
    let tip = c0.node_position(&q0, n);
    println!("unturned tip {tip:?}; turned problem vs turned solution: {worst:.2e} m");
    assert!(tip.iter().all(|x| x.abs() > 0.05), "a fully spatial tip");
    assert!(worst < 1e-10, "{worst}");

    // A deformed state turned rigidly: the same strain energy, the
    // elastic forces turned (per node, position and gradient rows alike),
    // and nothing at all at the rigidly turned reference.
    let m = &c0.model;
    let qr: Vec<f64> = q0
        .chunks(3)
        .flat_map(|v| apply(&r, [v[0], v[1], v[2]]))
        .collect();
    let (u0, u1) = (m.strain_energy(&q0), m.strain_energy(&qr));
    println!("strain energy {u0:.12e}, turned {u1:.12e}");
    assert!((u0 - u1).abs() < 1e-12 * u0.abs(), "{u0} {u1}");
    let zero = vec![0.0; m.n_full()];
    let mut scratch = vec![0.0; m.n_full()];
    let forces = |q: &[f64], scratch: &mut Vec<f64>| {
        scratch.fill(0.0);
        for g in m.groups() {
            g.add_internal(q, &zero, scratch);
        }
        scratch.clone()
    };
    let f0 = forces(&q0, &mut scratch);
    let f1 = forces(&qr, &mut scratch);
    let scale = f0.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let f0r: Vec<f64> = f0
        .chunks(3)
        .flat_map(|v| apply(&r, [v[0], v[1], v[2]]))
        .collect();
    let d = f0r
        .iter()
        .zip(&f1)
        .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
    assert!(d < 1e-9 * scale, "{d} of {scale}");
    let ref_turned: Vec<f64> = m
        .q0()
        .chunks(3)
        .flat_map(|v| apply(&r, [v[0], v[1], v[2]]))
        .collect();
    let fr = forces(&ref_turned, &mut scratch);
    let d = fr.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    assert!(d < 1e-9, "turned reference: force {d}");
}

/// Berzeri and Shabana's pendulum as a 3D rope: pinned at the origin,
/// horizontal along x, gravity along −z, spinning about z at `omega`.
fn rope(elements: usize) -> Chain {
    let (a, i) = (0.0018, 1.215e-8);
    let mut s = spec(
        "Cable3D",
        elements,
        [1.2, 0.0, 0.0],
        Section {
            e: 0.7e6,
            rho: 5540.0,
            area: a,
            inertia: i,
            ..Section::default()
        },
    );
    s.start_support = Support::Pinned;
    s.gravity = [0.0, 0.0, -9.81];
    build(&s)
}

/// Runs the rope to `t_end`; the tip there and the largest energy change
/// relative to `m g L`.
fn fall(ch: &Chain, omega: f64, h: f64, t_end: f64) -> ([f64; 3], f64) {
    let m = &ch.model;
    // Rigid spin about z: position rates ω ẑ × r, gradient rates ω ẑ × t.
    let mut vfull = vec![0.0; m.n_full()];
    let q0 = m.q0();
    for node in 0..ch.nodes {
        for block in 0..2 {
            let at = node * 6 + 3 * block;
            vfull[at] = -omega * q0[at + 1];
            vfull[at + 1] = omega * q0[at];
        }
    }
    let state = State {
        t: 0.0,
        q: m.restrict(q0),
        v: m.restrict(&vfull),
    };
    let opts = AlphaOptions {
        h,
        ..AlphaOptions::default()
    };
    let e0 = m.energy(q0, &state.v);
    let scale = 5540.0 * 0.0018 * 1.2 * 9.81 * 1.2;
    let mut ga = GeneralizedAlpha::new(m, state, opts).unwrap_or_else(|e| panic!("{e}"));
    let mut worst: f64 = 0.0;
    ga.run_to(t_end, |s, q| {
        worst = worst.max((m.energy(q, &s.v) - e0).abs() / scale);
    })
    .unwrap_or_else(|e| panic!("{e}"));
    (ch.node_position(ga.q_full(), ch.nodes - 1), worst)
}

#[test]
fn falling_3d_rope_keeps_its_energy() {
    // Generalized-α with ρ∞ = 1 (no numerical damping) keeps the energy
    // to O(h²): the error falls by 4 when h halves.
    let ch = rope(8);
    let (tip1, e1) = fall(&ch, 2.0, 1e-3, 1.0);
    let (tip2, e2) = fall(&ch, 2.0, 5e-4, 1.0);
    println!(
        "3D rope energy error: h = 1e-3: {e1:.3e}, h = 5e-4: {e2:.3e}; tip at 1 s {tip1:?} / {tip2:?}"
    );
    // The motion is spatial: the tip has left the x–z plane and fallen
    // (the spin keeps it from falling far).
    assert!(tip2[1].abs() > 0.1 && tip2[2] < -0.05, "{tip2:?}");
    assert!(e1 < 1e-3, "{e1}");
    let order = (e1 / e2).log2();
    assert!(order > 1.7, "energy error order {order}");
}

#[test]
fn beam2d_cantilever_converges_to_timoshenko() {
    // L = 1 m, b = 0.1 m, E = 1e3 Pa, tip force P = 1e-9 · E b h (linear
    // range), h = 0.1 and 0.01 m (L/h = 10 and 100), ν = 0 and 0.3.
    // Reference: Timoshenko's cantilever with Cowper's k_s for a rectangle.
    let (l, young, b): (f64, f64, f64) = (1.0, 1.0e3, 0.1);
    for h in [0.1f64, 0.01] {
        for nu in [0.0, 0.3] {
            let (area, inertia) = (b * h, b * h.powi(3) / 12.0);
            let p = 1e-9 * young * area;
            let g = young / (2.0 * (1.0 + nu));
            let ks = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu);
            let timo = p * l.powi(3) / (3.0 * young * inertia) + p * l / (ks * g * area);
            let section = Section {
                e: young,
                nu,
                rho: 1.0,
                area,
                inertia,
                b,
                h,
                ..Section::default()
            };
            let mut errors = Vec::new();
            for n in [1usize, 2, 4, 8, 16, 32] {
                let mut s = spec("Beam2D", n, [l, 0.0, 0.0], section.clone());
                s.end_force = [0.0, -p, 0.0];
                let (tip, _) = solve(&build(&s), 1);
                errors.push((-tip[1] / timo - 1.0).abs());
            }
            let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
            println!(
                "Beam2D L/h = {:.0}, nu = {nu}: |tip/Timoshenko − 1| {errors:?}, orders {orders:.3?}",
                l / h
            );
            for &o in &orders {
                assert!((o - 2.0).abs() < 0.05, "order {o}: {errors:?}");
            }
            assert!(errors[5] < 3e-4, "{errors:?}");
        }
    }
}

/// Static tip under a distributed load `w` (N/m, world axes) added after
/// building the chain.
fn distributed_tip(mut ch: Chain, w: [f64; 3], load_steps: usize) -> [f64; 3] {
    ch.model.add_distributed_load(w);
    solve(&ch, load_steps).0
}

#[test]
fn uniformly_loaded_cantilever_small_and_large_deflection() {
    // Small: w = 1e-5 N/m on L = 1.5 m, EI = 1 (δ/L = 6e-6): Euler–
    // Bernoulli's wL⁴/(8EI), already with one element (the consistent load
    // makes the Hermite element nodally exact), in-plane and (Cable3D)
    // out of plane.
    let l: f64 = 1.5;
    let w = 1e-5;
    let eb = w * l.powi(4) / 8.0;
    for (kernel, dir) in [("Cable2D", 1), ("Cable2DGreen", 1), ("Cable3D", 2)] {
        for n in [1usize, 3] {
            let ch = build(&spec(kernel, n, [l, 0.0, 0.0], cable_section(1e4)));
            let mut load = [0.0; 3];
            load[dir] = -w;
            let tip = distributed_tip(ch, load, 1);
            let r = -tip[dir] / eb - 1.0;
            println!("{kernel}, {n} elements, uniform load: tip / (wL⁴/8EI) − 1 = {r:.1e}");
            assert!(r.abs() < 1e-6, "{kernel} {n}: {r}");
        }
    }
    // Large: wL³/EI = 1 … 10 on L = 1, EI = 1, EA = 1e6 (nearly
    // inextensible), against the extensible elastica under the same load
    // (shooting, `extensible_cantilever_distributed`); the mesh (4 … 64
    // elements) converges to it.
    for wl in [10.0, 1.0, 3.0] {
        let reference = extensible_cantilever_distributed(1.0, 1e6, 1.0, [0.0, -wl])
            .unwrap_or_else(|| panic!("the elastica reference failed at {wl}"));
        let mut errors = Vec::new();
        for n in [4usize, 8, 16, 32, 64] {
            let ch = build(&spec("Cable2D", n, [1.0, 0.0, 0.0], cable_section(1e6)));
            let tip = distributed_tip(ch, [0.0, -wl, 0.0], 20);
            errors.push(dist(tip, [reference.x, reference.y, 0.0]));
        }
        let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        println!(
            "wL³/EI = {wl:>4}: elastica tip ({:.9}, {:.9}), errors {errors:?}, orders {orders:?}",
            reference.x, reference.y
        );
        // Pre-asymptotic on coarse meshes at the larger loads (measured
        // orders 2.4, 3.0, 5.2, … at wL³/EI = 10); the last two
        // refinements at order above 3.5, and 64 elements within 1e-6 m.
        assert!(errors[4] < 1e-6, "{errors:?}");
        for &o in &orders[2..] {
            assert!(o > 3.5, "{orders:?}");
        }
    }
}

#[test]
fn beam2d_large_deflection_converges_to_the_elastica() {
    // A slender strip (L = 1 m, b = h = 0.01 m, E = 1.2e9 Pa: EI = 1 N m²,
    // EA = 1.2e5 N, ν = 0.3) under the tip force PL²/EI = 3: Mattiasson's
    // inextensible elastica, up to shear and stretch (P/(k_s G A) and P/EA,
    // 6e-5 and 2.5e-5 here), the tip turning by 1.2 rad. Measured: errors
    // 7.9e-2, 7.8e-3, 4.9e-4 m for 8, 16, 32 elements (orders 3.3, 4.0:
    // at this load the coarse meshes' error converges faster than the
    // second order of the small-deflection case, which is its asymptotic
    // order and what is asserted).
    let (l, b, h) = (1.0, 0.01, 0.01);
    let section = Section {
        e: 1.2e9,
        nu: 0.3,
        rho: 1.0,
        area: b * h,
        inertia: b * h * h * h / 12.0,
        b,
        h,
        ..Section::default()
    };
    let alpha = 3.0;
    let (u, w, _) = mattiasson(alpha);
    let mut errors = Vec::new();
    for n in [8usize, 16, 32] {
        let mut s = spec("Beam2D", n, [l, 0.0, 0.0], section.clone());
        s.end_force = [0.0, -alpha, 0.0];
        let (tip, _) = solve(&build(&s), 10);
        let e = ((l - tip[0] - u).powi(2) + (-tip[1] - w).powi(2)).sqrt();
        println!(
            "Beam2D, {n} elements: u/L {:.7}, w/L {:.7} (Mattiasson {u:.7}, {w:.7}), error {e:.2e}",
            l - tip[0],
            -tip[1]
        );
        errors.push(e);
    }
    let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    println!("orders {orders:?}");
    for &o in &orders {
        assert!(o > 1.8, "{orders:?}");
    }
    assert!(errors[2] < 6e-4, "{errors:?}");
}
