//! The element definitions: shape functions, strain measures, energies.
//!
//! All elements use the cubic Hermite polynomials in `ξ = x/L ∈ [0, 1]`
//! along the axis (Shabana 2013, ch. 7):
//! `h₁ = 1 − 3ξ² + 2ξ³`, `h₂ = ξ − 2ξ² + ξ³`, `h₃ = 3ξ² − 2ξ³`,
//! `h₄ = −ξ² + ξ³`, so that `r(x) = h₁ r₁ + L h₂ r₁' + h₃ r₂ + L h₄ r₂'`.

use super::{Definition, Point, Symbols, gauss_legendre, symbols};
use crate::sym::{Arena, Id, SymId};

/// Integer coefficients (ascending powers of ξ) of `h₁ … h₄`.
const HERMITE: [[i64; 4]; 4] = [[1, 0, -3, 2], [0, 1, -2, 1], [0, 0, 3, -2], [0, 0, -1, 1]];
/// `1 − ξ` and `ξ` (the beam's linear interpolation of `r_y`).
const LINEAR: [[i64; 4]; 2] = [[1, -1, 0, 0], [0, 1, 0, 0]];

/// Value, first and second derivative in ξ of an integer polynomial.
fn eval(p: &[i64; 4], xi: f64) -> [f64; 3] {
    let c = p.map(|c| c as f64);
    [
        c[0] + xi * (c[1] + xi * (c[2] + xi * c[3])),
        c[1] + xi * (2.0 * c[2] + xi * 3.0 * c[3]),
        2.0 * c[2] + 6.0 * xi * c[3],
    ]
}

/// `∫₀¹ p q dξ` as a reduced fraction.
fn integral(p: &[i64; 4], q: &[i64; 4]) -> (i64, i64) {
    let (mut num, mut den) = (0i128, 1i128);
    for (i, &a) in p.iter().enumerate() {
        for (j, &b) in q.iter().enumerate() {
            let (n2, d2) = ((a * b) as i128, (i + j + 1) as i128);
            num = num * d2 + n2 * den;
            den *= d2;
            let g = gcd(num.abs(), den);
            if g > 1 {
                num /= g;
                den /= g;
            }
        }
    }
    (num as i64, den as i64)
}

/// `∫₀¹ p dξ` as a reduced fraction.
fn integral1(p: &[i64; 4]) -> (i64, i64) {
    integral(p, &[1, 0, 0, 0])
}

fn gcd(a: i128, b: i128) -> i128 {
    if b == 0 { a.max(1) } else { gcd(b, a % b) }
}

/// One coordinate slot of a node: shape polynomial along the axis times
/// `L^l_pow`, and (beam only) the polynomial multiplying `y`.
#[derive(Clone, Copy)]
struct Slot {
    axis: Option<(&'static [i64; 4], i32)>,
    transverse: Option<&'static [i64; 4]>,
}

/// Mass matrix and uniform-load force from the slots, integrated exactly.
/// Slot `k` of node `a` owns coordinates `a·nc + k·dim + c`, `c < dim`.
/// `m_axis` multiplies `L ∫ S₀ᵀS₀ dξ`, `m_transverse` `L ∫ S₁ᵀS₁ dξ`
/// (the section's `∫ y² dA` times the density).
fn mass_and_load(
    a: &mut Arena,
    s: &Symbols,
    slots: &[[Slot; 3]; 2],
    (nslots, dim): (usize, usize),
    l: Id,
    m_axis: Id,
    m_transverse: Option<Id>,
) -> (Vec<Vec<Id>>, Vec<Id>) {
    let nc = nslots * dim;
    let n = 2 * nc;
    let zero = a.constant(0.0);
    let mut m = vec![vec![zero; n]; n];
    let mut f = vec![zero; n];
    let coord = |node: usize, k: usize, c: usize| node * nc + k * dim + c;
    for na in 0..2 {
        for ka in 0..nslots {
            let sa = slots[na][ka];
            if let Some((pa, ea)) = sa.axis {
                let (num, den) = integral1(pa);
                for c in 0..dim {
                    let r = a.ratio(num, den);
                    let lp = a.pow(l, ea + 1);
                    f[coord(na, ka, c)] = a.mul(&[r, lp, s.w[c]]);
                }
            }
            for nb in 0..2 {
                for kb in 0..nslots {
                    let sb = slots[nb][kb];
                    let mut terms = Vec::new();
                    if let (Some((pa, ea)), Some((pb, eb))) = (sa.axis, sb.axis) {
                        let (num, den) = integral(pa, pb);
                        let r = a.ratio(num, den);
                        let lp = a.pow(l, ea + eb + 1);
                        terms.push(a.mul(&[r, lp, m_axis]));
                    }
                    if let (Some(pa), Some(pb), Some(mt)) =
                        (sa.transverse, sb.transverse, m_transverse)
                    {
                        let (num, den) = integral(pa, pb);
                        let r = a.ratio(num, den);
                        terms.push(a.mul(&[r, l, mt]));
                    }
                    let v = a.add(&terms);
                    for c in 0..dim {
                        m[coord(na, ka, c)][coord(nb, kb, c)] = v;
                    }
                }
            }
        }
    }
    (m, f)
}

/// The cable slots: position (`h₁`, `h₃`) and slope (`L h₂`, `L h₄`).
fn cable_slots() -> [[Slot; 3]; 2] {
    let none = Slot {
        axis: None,
        transverse: None,
    };
    let s = |i: usize, e: i32| Slot {
        axis: Some((&HERMITE[i], e)),
        transverse: None,
    };
    [[s(0, 0), s(1, 1), none], [s(2, 0), s(3, 1), none]]
}

/// A shared linear combination of `q`: a symbol `pa<k>` standing for `e`.
fn pre(a: &mut Arena, pre: &mut Vec<(SymId, Id)>, e: Id) -> Id {
    let id = a.input(&format!("pa{}", pre.len())).expect("identifier");
    pre.push((a.as_sym(id).expect("symbol"), e));
    id
}

/// The shared combinations of a cable, per component `c`: the chord
/// `Δ = (r₂ − r₁)/L` (`h₁' = −h₃'`, so positions enter `r'` and `r''` only
/// through it), and the reciprocal length.
struct CablePre {
    chord: Vec<Id>,
    slope: [Vec<Id>; 2],
    il: Id,
}

fn cable_pre(
    a: &mut Arena,
    s: &Symbols,
    dim: usize,
    l: Id,
    out: &mut Vec<(SymId, Id)>,
) -> CablePre {
    let il = a.pow(l, -1);
    let mut p = CablePre {
        chord: vec![],
        slope: [vec![], vec![]],
        il,
    };
    for c in 0..dim {
        let d = a.sub(s.q[2 * dim + c], s.q[c]);
        let e = a.mul2(il, d);
        p.chord.push(pre(a, out, e));
        for node in 0..2 {
            p.slope[node].push(s.q[node * 2 * dim + dim + c]);
        }
    }
    p
}

/// `r'` and `r''` (derivatives in the reference arc length `x`) of a
/// cable at `ξ`, components `0..dim`: `r' = h₃'Δ + h₂'r₁' + h₄'r₂'`,
/// `r'' = (h₃''Δ + h₂''r₁' + h₄''r₂'')/L` (ξ-derivatives of the `h`).
fn cable_derivatives(a: &mut Arena, p: &CablePre, dim: usize, xi: f64) -> (Vec<Id>, Vec<Id>) {
    let h3 = eval(&HERMITE[2], xi);
    let h2 = eval(&HERMITE[1], xi);
    let h4 = eval(&HERMITE[3], xi);
    let mut d1 = Vec::with_capacity(dim);
    let mut d2 = Vec::with_capacity(dim);
    for c in 0..dim {
        let lin = |a: &mut Arena, k: usize, x: [Id; 3]| {
            let t: Vec<Id> = [h3[k], h2[k], h4[k]]
                .iter()
                .zip(x)
                .map(|(&w, v)| {
                    let w = a.constant(w);
                    a.mul2(w, v)
                })
                .collect();
            a.add(&t)
        };
        let x = [p.chord[c], p.slope[0][c], p.slope[1][c]];
        d1.push(lin(a, 1, x));
        let t = lin(a, 2, x);
        d2.push(a.mul2(p.il, t));
    }
    (d1, d2)
}

fn dot(a: &mut Arena, x: &[Id], y: &[Id]) -> Id {
    let t: Vec<Id> = x.iter().zip(y).map(|(&u, &v)| a.mul2(u, v)).collect();
    a.add(&t)
}

fn square(a: &mut Arena, x: Id) -> Id {
    a.pow(x, 2)
}

/// Gauss points for the axial and the bending term of the cables.
pub const CABLE_AXIAL_POINTS: usize = 5;
/// See [`CABLE_AXIAL_POINTS`].
pub const CABLE_BENDING_POINTS: usize = 4;

/// Planar cable: Gerstmayr–Irschik (`green = false`) or Green strain.
pub(super) fn cable2d(a: &mut Arena, green: bool) -> Definition {
    let params = vec![
        ("L", "reference length [m]"),
        ("EA", "axial stiffness [N]"),
        ("EI", "bending stiffness [N m²]"),
        ("rhoA", "mass per unit reference length [kg/m]"),
        (
            "d_a",
            "axial Kelvin–Voigt damping: force per unit axial strain rate [N s]",
        ),
        (
            "d_b",
            "bending Kelvin–Voigt damping: moment per unit curvature rate [N m² s]",
        ),
    ];
    let s = symbols(a, 8, &params);
    let [l, ea, ei, rho_a, da, db] = [s.p[0], s.p[1], s.p[2], s.p[3], s.p[4], s.p[5]];
    let half = a.ratio(1, 2);
    let one = a.constant(1.0);
    let mut pre_defs = Vec::new();
    let cp = cable_pre(a, &s, 2, l, &mut pre_defs);
    let mut points = Vec::new();
    for (xi, w) in gauss_legendre(CABLE_AXIAL_POINTS) {
        let (d1, _) = cable_derivatives(a, &cp, 2, xi);
        let c = a.constant(w);
        let wt = a.mul2(c, l);
        let mut pt = Point::new(a, points.len(), wt, d1);
        let z = pt.z_nodes(a);
        let ss = dot(a, &z, &z);
        let eps = if green {
            let t = a.sub(ss, one);
            a.mul2(half, t)
        } else {
            let t = a.sqrt(ss);
            a.sub(t, one)
        };
        let epsd = pt.rate(a, eps);
        let e2 = square(a, eps);
        pt.phi = a.mul(&[half, ea, e2]);
        let e2 = square(a, epsd);
        pt.psi = a.mul(&[half, da, e2]);
        points.push(pt);
    }
    for (xi, w) in gauss_legendre(CABLE_BENDING_POINTS) {
        let (mut d1, d2) = cable_derivatives(a, &cp, 2, xi);
        d1.extend(d2);
        let c = a.constant(w);
        let wt = a.mul2(c, l);
        let mut pt = Point::new(a, points.len(), wt, d1);
        let z = pt.z_nodes(a);
        let t1 = a.mul2(z[0], z[3]);
        let t2 = a.mul2(z[1], z[2]);
        let cross = a.sub(t1, t2);
        let kappa = if green {
            cross
        } else {
            let ss = dot(a, &z[..2], &z[..2]);
            a.div(cross, ss)
        };
        let kd = pt.rate(a, kappa);
        let k2 = square(a, kappa);
        pt.phi = a.mul(&[half, ei, k2]);
        let k2 = square(a, kd);
        pt.psi = a.mul(&[half, db, k2]);
        points.push(pt);
    }
    let (mass, load) = mass_and_load(a, &s, &cable_slots(), (2, 2), l, rho_a, None);
    let (name, module, summary, integration) = if green {
        (
            "Cable2DGreen",
            "cable2d_green",
            "Planar ANCF cable element with the Green axial strain \
             `ε_G = ½(r'·r' − 1)` and the polynomial curvature `κ = r' × r''` \
             (the classical simplification, Shabana 2013 §7; exact only for \
             inextensible deformation). Strain energy \
             `U = ½ ∫₀ᴸ (EA ε_G² + EI κ²) dx`, dissipation \
             `R = ½ ∫₀ᴸ (d_a ε̇_G² + d_b κ̇²) dx`."
                .to_string(),
            format!(
                "Exact: the integrands are polynomials in `ξ` (`ε_G²` of degree 8, \
                 `κ²` of degree 6), integrated by Gauss–Legendre rules of \
                 {CABLE_AXIAL_POINTS} (axial, exact to degree 9) and \
                 {CABLE_BENDING_POINTS} points (bending, exact to degree 7), unrolled."
            ),
        )
    } else {
        (
            "Cable2D",
            "cable2d",
            "Planar ANCF cable element (Gerstmayr and Irschik 2008, J. Sound Vib. \
             318): axial strain `ε = |r'| − 1` and material curvature \
             `κ = (r' × r'')/|r'|²`, with `'` the derivative in the reference \
             arc length. Strain energy `U = ½ ∫₀ᴸ (EA ε² + EI κ²) dx`, \
             dissipation `R = ½ ∫₀ᴸ (d_a ε̇² + d_b κ̇²) dx`."
                .to_string(),
            format!(
                "Gauss–Legendre, fixed at generation and unrolled: \
                 {CABLE_AXIAL_POINTS} points for the axial term (exact to degree 9, \
                 the degree of `ε²` with `|r'|` replaced by `|r'|²`) and \
                 {CABLE_BENDING_POINTS} for the bending term (degree 7, exact for \
                 `(r' × r'')²`); the integrands are rational, not polynomial, and \
                 at random deformations of 5 % the forces differ from a 40-point \
                 rule's by 4e-6 (relative; 2.7e-5 with 3 bending points, 1.7e-4 \
                 with 4 axial points; `integration_rule_study` in \
                 `eom-gen/tests/ancf_elements.rs`)."
            ),
        )
    };
    Definition {
        name,
        module,
        dim: 2,
        node_coords: 4,
        node_layout: ["r_x", "r_y", "r'_x", "r'_y"].map(String::from).to_vec(),
        params,
        summary,
        integration,
        pre: pre_defs,
        points,
        mass,
        load,
    }
}

/// Spatial cable, no torsion.
pub(super) fn cable3d(a: &mut Arena) -> Definition {
    let params = vec![
        ("L", "reference length [m]"),
        ("EA", "axial stiffness [N]"),
        ("EI", "bending stiffness (isotropic section) [N m²]"),
        ("rhoA", "mass per unit reference length [kg/m]"),
        (
            "d_a",
            "axial Kelvin–Voigt damping: force per unit axial strain rate [N s]",
        ),
        (
            "d_b",
            "bending Kelvin–Voigt damping: moment per unit curvature rate [N m² s]",
        ),
    ];
    let s = symbols(a, 12, &params);
    let [l, ea, ei, rho_a, da, db] = [s.p[0], s.p[1], s.p[2], s.p[3], s.p[4], s.p[5]];
    let one = a.constant(1.0);
    let half = a.ratio(1, 2);
    let mut pre_defs = Vec::new();
    let cp = cable_pre(a, &s, 3, l, &mut pre_defs);
    let mut points = Vec::new();
    for (xi, w) in gauss_legendre(CABLE_AXIAL_POINTS) {
        let (d1, _) = cable_derivatives(a, &cp, 3, xi);
        let c = a.constant(w);
        let wt = a.mul2(c, l);
        let mut pt = Point::new(a, points.len(), wt, d1);
        let z = pt.z_nodes(a);
        let ss = dot(a, &z, &z);
        let t = a.sqrt(ss);
        let eps = a.sub(t, one);
        let epsd = pt.rate(a, eps);
        let e2 = square(a, eps);
        pt.phi = a.mul(&[half, ea, e2]);
        let e2 = square(a, epsd);
        pt.psi = a.mul(&[half, da, e2]);
        points.push(pt);
    }
    for (xi, w) in gauss_legendre(CABLE_BENDING_POINTS) {
        let (mut d1, d2) = cable_derivatives(a, &cp, 3, xi);
        d1.extend(d2);
        let c = a.constant(w);
        let wt = a.mul2(c, l);
        let mut pt = Point::new(a, points.len(), wt, d1);
        let z = pt.z_nodes(a);
        let (r1, r2) = (&z[..3], &z[3..]);
        let ss = dot(a, r1, r1);
        // Curvature vector k = (r' × r'')/|r'|³; κ = |k| (its square is smooth
        // at zero curvature, κ itself is not).
        let t = a.sqrt(ss);
        let n3 = a.mul2(ss, t);
        let inv = a.recip(n3);
        let mut k = Vec::with_capacity(3);
        for (i, j) in [(1, 2), (2, 0), (0, 1)] {
            let t1 = a.mul2(r1[i], r2[j]);
            let t2 = a.mul2(r1[j], r2[i]);
            let c = a.sub(t1, t2);
            k.push(a.mul2(c, inv));
        }
        let k2 = dot(a, &k, &k);
        let kd: Vec<Id> = k.iter().map(|&e| pt.rate(a, e)).collect();
        let kd2 = dot(a, &kd, &kd);
        pt.phi = a.mul(&[half, ei, k2]);
        pt.psi = a.mul(&[half, db, kd2]);
        points.push(pt);
    }
    let (mass, load) = mass_and_load(a, &s, &cable_slots(), (2, 3), l, rho_a, None);
    Definition {
        name: "Cable3D",
        module: "cable3d",
        dim: 3,
        node_coords: 6,
        node_layout: ["r_x", "r_y", "r_z", "r'_x", "r'_y", "r'_z"]
            .map(String::from)
            .to_vec(),
        params,
        summary: "Spatial ANCF cable element, axial and bending, no torsion (a rope or \
                  hose; Gerstmayr and Shabana 2006, Nonlinear Dyn. 45): axial strain \
                  `ε = |r'| − 1`, curvature vector `k = (r' × r'')/|r'|³` with \
                  `κ = |k|` (the curvature of the deformed centre line). Strain energy \
                  `U = ½ ∫₀ᴸ (EA ε² + EI |k|²) dx`, dissipation \
                  `R = ½ ∫₀ᴸ (d_a ε̇² + d_b |k̇|²) dx`."
            .to_string(),
        integration: format!(
            "Gauss–Legendre, fixed at generation and unrolled: {CABLE_AXIAL_POINTS} \
             points for the axial term and {CABLE_BENDING_POINTS} for the bending \
             term, as for the planar cable (the integrands are rational; at random \
             deformations of 5 % the forces differ from a 40-point rule's by \
             2.5e-5, relative; `integration_rule_study`)."
        ),
        pre: pre_defs,
        points,
        mass,
        load,
    }
}

/// Gauss points along the beam's axis and through its height.
pub const BEAM_AXIAL_POINTS: usize = 5;
/// See [`BEAM_AXIAL_POINTS`].
pub const BEAM_HEIGHT_POINTS: usize = 3;

/// Planar fully parameterised beam, continuum Green–Lagrange strain,
/// plane stress.
pub(super) fn beam2d(a: &mut Arena) -> Definition {
    let params = vec![
        ("L", "reference length [m]"),
        ("E", "Young's modulus [Pa]"),
        ("nu", "Poisson's ratio [-]"),
        ("rho", "density [kg/m³]"),
        ("b", "width of the rectangular section (out of plane) [m]"),
        ("h", "height of the rectangular section (in plane) [m]"),
        (
            "mu",
            "Kelvin–Voigt retardation time: stress `C (E + mu Ė)` [s]",
        ),
    ];
    let s = symbols(a, 12, &params);
    let [l, e, nu, rho, b, h, mu] = [s.p[0], s.p[1], s.p[2], s.p[3], s.p[4], s.p[5], s.p[6]];
    let one = a.constant(1.0);
    let half = a.ratio(1, 2);
    // Locking remedy (Sopanen and Mikkola 2003, Nonlinear Dyn. 34;
    // Gerstmayr, Matikainen and Mikkola 2008, Multibody Syst. Dyn. 20):
    // Poisson's ratio is set to zero in the normal-strain terms (the
    // section vector `r,ᵧ` is constant through the height, so the
    // transverse contraction a bent section needs cannot occur and the
    // plane-stress coupling stiffens bending by `1/(1 − ν²)`), and the
    // shear term carries Cowper's correction for a rectangle,
    // `k_s = 10(1 + ν)/(12 + 11ν)` (the continuum shear strain is uniform
    // through the height), so `k_s G = 5E/(12 + 11ν)`.
    // W(E) = ½ E (E11² + E22²) + 2 k_s G E12².
    let five = a.constant(5.0);
    let twelve = a.constant(12.0);
    let eleven = a.constant(11.0);
    let e5 = a.mul2(five, e);
    let nu11 = a.mul2(eleven, nu);
    let ks_den = a.add2(twelve, nu11);
    let g = a.div(e5, ks_den);
    let two = a.constant(2.0);
    let il = a.pow(l, -1);
    let density = |a: &mut Arena, e11: Id, e22: Id, e12: Id| -> Id {
        let x = square(a, e11);
        let y = square(a, e22);
        let sum = a.add2(x, y);
        let t1 = a.mul(&[half, e, sum]);
        let s12 = square(a, e12);
        let t2 = a.mul(&[two, g, s12]);
        a.add2(t1, t2)
    };
    // Shared combinations per component: the chord (r₂ − r₁)/L, and the
    // change of the section vector over the element times the height,
    // h (r₂,ᵧ − r₁,ᵧ)/L.
    let mut pre_defs = Vec::new();
    let mut chord = Vec::with_capacity(2);
    let mut turn = Vec::with_capacity(2);
    for comp in 0..2 {
        let d = a.sub(s.q[6 + comp], s.q[comp]);
        let e = a.mul2(il, d);
        chord.push(pre(a, &mut pre_defs, e));
        let d = a.sub(s.q[10 + comp], s.q[4 + comp]);
        turn.push(a.mul(&[h, il, d]));
    }
    let mut points = Vec::new();
    for (xi, wx) in gauss_legendre(BEAM_AXIAL_POINTS) {
        for (eta, wy) in gauss_legendre(BEAM_HEIGHT_POINTS) {
            let h3 = eval(&HERMITE[2], xi);
            let h2 = eval(&HERMITE[1], xi);
            let h4 = eval(&HERMITE[3], xi);
            let mut rx = Vec::with_capacity(4);
            let mut ry = Vec::with_capacity(2);
            for comp in 0..2 {
                // r_x = h₃' Δ + h₂' r₁,ₓ + h₄' r₂,ₓ + y (r₂,ᵧ − r₁,ᵧ)/L, y = (η − ½) h
                let terms: Vec<Id> = [
                    (h3[1], chord[comp]),
                    (h2[1], s.q[2 + comp]),
                    (h4[1], s.q[8 + comp]),
                    (eta - 0.5, turn[comp]),
                ]
                .iter()
                .map(|&(c, v)| {
                    let c = a.constant(c);
                    a.mul2(c, v)
                })
                .collect();
                rx.push(a.add(&terms));
                // r_y = (1 − ξ) r₁,ᵧ + ξ r₂,ᵧ
                let c0 = a.constant(1.0 - xi);
                let c1 = a.constant(xi);
                let t0 = a.mul2(c0, s.q[4 + comp]);
                let t1 = a.mul2(c1, s.q[10 + comp]);
                ry.push(a.add2(t0, t1));
            }
            rx.extend(ry);
            let c = a.constant(wx * wy);
            let wt = a.mul(&[c, l, b, h]);
            let mut pt = Point::new(a, points.len(), wt, rx);
            let z = pt.z_nodes(a);
            let (rx, ry) = (&z[..2], &z[2..]);
            let xx = dot(a, rx, rx);
            let yy = dot(a, ry, ry);
            let xy = dot(a, rx, ry);
            let e11 = {
                let t = a.sub(xx, one);
                a.mul2(half, t)
            };
            let e22 = {
                let t = a.sub(yy, one);
                a.mul2(half, t)
            };
            let e12 = a.mul2(half, xy);
            pt.phi = density(a, e11, e22, e12);
            let [d11, d22, d12] = [e11, e22, e12].map(|x| pt.rate(a, x));
            let wd = density(a, d11, d22, d12);
            pt.psi = a.mul2(mu, wd);
            points.push(pt);
        }
    }
    // Mass: ρ L ∫ (A S₀ᵀS₀ + I S₁ᵀS₁) dξ with A = b h, I = b h³/12.
    let area = a.mul2(b, h);
    let m_axis = a.mul2(rho, area);
    let twelfth = a.ratio(1, 12);
    let h3 = a.pow(h, 3);
    let m_tr = a.mul(&[twelfth, rho, b, h3]);
    let slot = |i: usize, e: i32| Slot {
        axis: Some((&HERMITE[i], e)),
        transverse: None,
    };
    let ry = |i: usize| Slot {
        axis: None,
        transverse: Some(&LINEAR[i]),
    };
    let slots = [
        [slot(0, 0), slot(1, 1), ry(0)],
        [slot(2, 0), slot(3, 1), ry(1)],
    ];
    let (mass, load) = mass_and_load(a, &s, &slots, (3, 2), l, m_axis, Some(m_tr));
    Definition {
        name: "Beam2D",
        module: "beam2d",
        dim: 2,
        node_coords: 6,
        node_layout: ["r_x", "r_y", "∂r/∂x_x", "∂r/∂x_y", "∂r/∂y_x", "∂r/∂y_y"]
            .map(String::from)
            .to_vec(),
        params,
        summary: "Planar fully parameterised ANCF beam element (Omar and Shabana 2001, \
                  J. Sound Vib. 243; Berzeri and Shabana 2000, J. Sound Vib. 235): \
                  `r(x, y) = h₁ r₁ + L h₂ r₁,ₓ + y (1 − ξ) r₁,ᵧ + h₃ r₂ + L h₄ r₂,ₓ + y ξ r₂,ᵧ` \
                  over a rectangular section `b × h` centred on the axis. \
                  Continuum mechanics: deformation gradient `F = [r,ₓ r,ᵧ]`, \
                  Green–Lagrange strain `E = ½(FᵀF − I)`, plane stress \
                  `W = ½ E (E₁₁² + E₂₂²) + 2 k_s G E₁₂²`, `U = ∫ W dV`; \
                  Kelvin–Voigt `R = mu ∫ W(Ė) dV`. Locking remedy (Sopanen and \
                  Mikkola 2003; Gerstmayr, Matikainen and Mikkola 2008): \
                  Poisson's ratio is zero in the normal-strain terms (no \
                  Poisson locking: full plane stress stiffens bending by \
                  `1/(1 − ν²)`, 0.68 × Euler–Bernoulli at `nu = 0.3`), and the \
                  shear term has Cowper's factor `k_s = 10(1 + ν)/(12 + 11ν)`, \
                  `G = E/(2(1 + ν))`; `nu` enters only there. The section \
                  vector `r,ᵧ` is interpolated linearly, so the bending strain \
                  is constant along an element (one element: 0.75 × \
                  Euler–Bernoulli under a tip force); a cantilever converges \
                  to Timoshenko's deflection with the mesh at second order \
                  (`beam2d_cantilever_converges_to_timoshenko` in \
                  `eom-sim/tests/ancf_elements_physics.rs`)."
            .to_string(),
        integration: format!(
            "Exact: `W` is a polynomial, of degree 8 in `ξ` and 4 in `y`; \
             Gauss–Legendre {BEAM_AXIAL_POINTS} × {BEAM_HEIGHT_POINTS} points \
             (exact to degree 9 × 5), unrolled."
        ),
        pre: pre_defs,
        points,
        mass,
        load,
    }
}
