//! Flexible (floating-frame) bodies on the animation page: the stations
//! along each body and their translational mode shapes, sent once; per
//! frame the page gets the body's pose and its elastic coordinates and
//! draws `R (p + S q_f) + r`.

use super::Error;
use super::Scene;
use std::fmt::Write;

/// A flexible (floating-frame) body as the page draws it: stations along
/// it, each at `p + S q_f` in the body frame (`S` the station's
/// translational shapes, 3 × k, linear in the elastic coordinates), so the
/// page gets the shapes once and per frame only the body's pose and its
/// `k` elastic coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct FlexDrawing {
    /// The body's index in the scene (tree order).
    pub body: usize,
    /// Its first elastic coordinate in the system's `q`.
    pub q_index: usize,
    /// Number of elastic coordinates `k`.
    pub k: usize,
    /// The stations' undeformed places, body axes.
    pub places: Vec<[f64; 3]>,
    /// Per station, the rows `x, y, z` of its shapes (each `k` long).
    pub shapes: Vec<[Vec<f64>; 3]>,
    /// Which stations are finite-element (or named) nodes.
    pub nodes: Vec<usize>,
    /// Stations along an axis, joined by rods (a beam, assumed modes);
    /// `false`: an imported model's nodes, drawn as balls alone (no
    /// element connectivity is read).
    pub line: bool,
}

/// Stations per element of a built-in beam: the Hermite cubics between
/// the nodes drawn by this many straight pieces.
pub const PIECES_PER_ELEMENT: usize = 4;

/// Stations along a body with assumed modes (its shape functions of `x`
/// evaluated at each).
pub const ASSUMED_PIECES: usize = 32;

/// The flexible bodies of the scene: a built-in beam at
/// [`PIECES_PER_ELEMENT`] stations per element (the elements' cubic
/// interpolation of the mode shapes, `flex_outputs::deformation`);
/// assumed modes at [`ASSUMED_PIECES`]` + 1` stations (their shape
/// functions, `flex::assumed::section`); imported modal data at their
/// nodes (`flex_outputs::node_point`, where their shapes are known).
pub fn flex_bodies(
    sys: &eom_gen::system::System,
    scene: &Scene,
) -> Result<Vec<FlexDrawing>, Error> {
    use eom_gen::mech::flex_outputs::{deformation, node_point};
    use eom_gen::system::FlexSource;
    let mut out = Vec::new();
    for (i, b) in scene.bodies.iter().enumerate() {
        let Some(flex) = sys
            .bodies
            .iter()
            .find(|s| s.name == b.name)
            .and_then(|s| s.flexible.as_deref())
        else {
            continue;
        };
        let k = flex.count();
        let unit = |j: usize| -> Vec<f64> { (0..k).map(|m| f64::from(u8::from(m == j))).collect() };
        let zero = vec![0.0; k];
        let mut places = Vec::new();
        let mut shapes_at = Vec::new();
        let mut nodes = Vec::new();
        match flex.source {
            FlexSource::Beam => {
                let beam = &flex.beam;
                let n = beam.elements * PIECES_PER_ELEMENT;
                for s in 0..=n {
                    let x = beam.length * s as f64 / n as f64;
                    if s % PIECES_PER_ELEMENT == 0 {
                        nodes.push(places.len());
                    }
                    places.push([x, 0.0, 0.0]);
                    let cols: Vec<[f64; 6]> =
                        (0..k).map(|j| deformation(flex, x, &unit(j))).collect();
                    shapes_at.push(std::array::from_fn(|r| cols.iter().map(|c| c[r]).collect()));
                }
            }
            FlexSource::Assumed { ref shapes, .. } => {
                // The shape functions of `x` along the body.
                let n = ASSUMED_PIECES;
                for s in 0..=n {
                    let x = flex.beam.length * s as f64 / n as f64;
                    let Some(sec) = eom_gen::flex::assumed::section(shapes, x) else {
                        continue;
                    };
                    if s == 0 || s == n {
                        nodes.push(places.len());
                    }
                    places.push([x, 0.0, 0.0]);
                    shapes_at.push(std::array::from_fn(|r| {
                        (0..k).map(|j| sec.translation[(r, j)]).collect()
                    }));
                }
            }
            FlexSource::Modal { .. } => {
                for node in 0..flex.modes.shapes.nrows() / 6 {
                    let p = node_point(flex, node, &zero).0;
                    nodes.push(places.len());
                    places.push(p);
                    let cols: Vec<[f64; 3]> = (0..k)
                        .map(|j| {
                            let d = node_point(flex, node, &unit(j)).0;
                            [d[0] - p[0], d[1] - p[1], d[2] - p[2]]
                        })
                        .collect();
                    shapes_at.push(std::array::from_fn(|r| cols.iter().map(|c| c[r]).collect()));
                }
            }
        }
        if places.len() < 2 {
            continue;
        }
        out.push(FlexDrawing {
            body: i,
            q_index: flex.q_index,
            k,
            places,
            shapes: shapes_at,
            nodes,
            line: !matches!(flex.source, FlexSource::Modal { .. }),
        });
    }
    Ok(out)
}

/// The page's `flex`: per flexible body its scene index, `k`, where its
/// coordinates sit in a row of `flexFrames`, the stations' places `p`
/// (3 per station), their shapes `s` (3 × k per station, row-major) and
/// the node stations.
pub(super) fn flex_json(flexes: &[FlexDrawing]) -> Result<String, Error> {
    let mut s = String::from("[");
    let mut at = 0;
    for (n, f) in flexes.iter().enumerate() {
        if n > 0 {
            s.push(',');
        }
        let list = |v: &mut dyn Iterator<Item = &f64>| -> Result<String, Error> {
            let items: Vec<String> = v.map(|x| significant(*x)).collect::<Result<_, _>>()?;
            Ok(items.join(","))
        };
        let p = list(&mut f.places.iter().flatten())?;
        let sh = list(&mut f.shapes.iter().flatten().flatten())?;
        let _ = write!(
            s,
            "{{\"body\":{},\"k\":{},\"at\":{at},\"p\":[{p}],\"s\":[{sh}],\"nodes\":{},\"line\":{}}}",
            f.body,
            f.k,
            serde_json::to_string(&f.nodes).unwrap_or_else(|_| "[]".into()),
            f.line,
        );
        at += f.k;
    }
    s.push(']');
    Ok(s)
}

/// `x` with 7 significant digits (elastic coordinates and shapes can be
/// far below the 6 decimals of a pose); not finite refuses.
pub(super) fn significant(x: f64) -> Result<String, Error> {
    if !x.is_finite() {
        return Err(Error::Refused(format!(
            "the trajectory holds {x}: nothing to animate"
        )));
    }
    if x == 0.0 {
        return Ok("0".into());
    }
    let s = format!("{x:.6e}");
    let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
    let mut m = mantissa.to_string();
    if m.contains('.') {
        while m.ends_with('0') {
            m.pop();
        }
        if m.ends_with('.') {
            m.pop();
        }
    }
    Ok(if exp == "0" { m } else { format!("{m}e{exp}") })
}

#[cfg(test)]
mod tests {
    use super::super::html;
    use super::*;
    use eom_sim::table::Table;

    /// The page of the hub and beam draws the beam deformed: per frame the
    /// body frame's pose and the 4 modal coordinates, once the stations'
    /// mode shapes. Evaluated as the page does (`R (p + S q_f) + r`), the
    /// places of the beam's root, middle and tip nodes agree with the
    /// model's own outputs `NodePosition` (the formulated `outputs`,
    /// interpreted) to the page's rounding, while the bending moves the
    /// tip by centimetres.
    #[test]
    fn hub_beam_page_carries_the_deformation() {
        // models/hub_beam.ron with node outputs.
        let text = include_str!("../../../models/hub_beam.ron").replace(
                "    joints: [",
                "    outputs: [NodePosition(body: \"beam\", node: 0), \
                 NodePosition(body: \"beam\", node: 5), NodePosition(body: \"beam\", node: 10)],\n    joints: [",
            );
        let dir = std::env::temp_dir().join(format!("eom-flexpage-{}", std::process::id()));
        let _ = std::fs::create_dir_all(&dir);
        let path = dir.join("hub_beam.ron");
        let _ = std::fs::write(&path, text);
        let opened = crate::open::open(
            &path.display().to_string(),
            &Default::default(),
            &Default::default(),
        );
        let _ = std::fs::remove_dir_all(&dir);
        let Ok(opened) = opened else {
            panic!("cannot open the hub and beam with outputs");
        };
        let sys = &opened.checked.system;
        let f =
            match eom_gen::mech::formulate(sys, eom_gen::functions::FunctionSet::all_requested()) {
                Ok(f) => f,
                Err(e) => panic!("{e}"),
            };
        let names: Vec<String> = sys
            .coordinate_names()
            .iter()
            .map(|n| n.to_string())
            .collect();
        assert_eq!(
            names.len(),
            5,
            "hub angle and 4 modal coordinates: {names:?}"
        );
        let mut header = vec!["t".to_string()];
        header.extend(names);
        let mut table = Table::new(header);
        let frames = [
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [0.5, 0.7, 0.06, -0.01, 0.004, 0.001],
            [1.0, 2.0, -0.05, 0.02, -0.003, 0.0005],
        ];
        for f in frames {
            table.push(f.to_vec());
        }
        let page = match html(sys, &table, &[]) {
            Ok(p) => p,
            Err(e) => panic!("{e}"),
        };
        let start = page.find(r#"type="application/json">"#).map(|i| i + 24);
        let data = start.and_then(|s| Some(&page[s..s + page[s..].find("</script>")?]));
        let data: serde_json::Value = match data.map(serde_json::from_str) {
            Some(Ok(v)) => v,
            other => panic!("the page's data does not parse: {other:?}"),
        };
        let nums = |v: &serde_json::Value| -> Vec<f64> {
            v.as_array()
                .map(|a| a.iter().filter_map(serde_json::Value::as_f64).collect())
                .unwrap_or_default()
        };
        let flex = &data["flex"][0];
        let (body, k) = (flex["body"].as_u64(), flex["k"].as_u64());
        assert_eq!(k, Some(4));
        assert_eq!(flex["line"], true, "a beam is drawn along its axis");
        let body = body.unwrap_or(0) as usize;
        assert_eq!(data["bodies"][body]["name"], "beam");
        let (p, shapes) = (nums(&flex["p"]), nums(&flex["s"]));
        let nodes: Vec<usize> = nums(&flex["nodes"]).iter().map(|&x| x as usize).collect();
        assert_eq!(nodes.len(), 11, "10 elements: 11 nodes");
        assert_eq!(p.len(), 3 * (10 * PIECES_PER_ELEMENT + 1));
        assert_eq!(shapes.len(), 4 * p.len());
        let mut tip_bend: f64 = 0.0;
        for (frame, row) in frames.iter().enumerate() {
            let pose = nums(&data["poses"][frame]);
            let qf = nums(&data["flexFrames"][frame]);
            assert_eq!(qf, row[2..], "the elastic coordinates, frame {frame}");
            let (r, quat) = (
                &pose[7 * body..7 * body + 3],
                &pose[7 * body + 3..7 * body + 7],
            );
            // v' = v + 2w (u × v) + 2 u × (u × v), u = (x, y, z).
            let turn = |v: [f64; 3]| {
                let u = [quat[0], quat[1], quat[2]];
                let cross = |a: [f64; 3], b: [f64; 3]| {
                    [
                        a[1] * b[2] - a[2] * b[1],
                        a[2] * b[0] - a[0] * b[2],
                        a[0] * b[1] - a[1] * b[0],
                    ]
                };
                let c = cross(u, v);
                let cc = cross(u, c);
                std::array::from_fn::<f64, 3, _>(|i| v[i] + 2.0 * quat[3] * c[i] + 2.0 * cc[i])
            };
            let x = eom_gen::interpret::Point {
                sys,
                q: &row[1..],
                u: &[0.0; 5],
                udot: &[0.0; 5],
                tau: &[],
                inputs: &[],
                params: &[],
                multipliers: &[],
                t: row[0],
            };
            let outputs = eom_gen::interpret::evaluate_function(
                &f,
                eom_gen::functions::Function::Outputs,
                &x,
            )
            .unwrap_or_default();
            let mut compared = 0;
            for (node, &st) in nodes.iter().enumerate() {
                let local: [f64; 3] = std::array::from_fn(|a| {
                    p[3 * st + a]
                        + (0..4)
                            .map(|m| shapes[12 * st + 4 * a + m] * qf[m])
                            .sum::<f64>()
                });
                let drawn: [f64; 3] = std::array::from_fn(|a| r[a] + turn(local)[a]);
                let rigid: [f64; 3] = std::array::from_fn(|a| {
                    r[a] + turn([p[3 * st], p[3 * st + 1], p[3 * st + 2]])[a]
                });
                let Some(at) = f
                    .output_names
                    .iter()
                    .position(|n| *n == format!("beam_node{node}_x"))
                else {
                    continue;
                };
                let want = &outputs[at..at + 3];
                let err = (0..3)
                    .map(|a| (drawn[a] - want[a]).abs())
                    .fold(0.0, f64::max);
                assert!(
                    err < 2e-6,
                    "frame {frame}, node {node}: drawn {drawn:?}, output {want:?}"
                );
                compared += 1;
                let bend = (0..3)
                    .map(|a| (rigid[a] - want[a]).abs())
                    .fold(0.0, f64::max);
                tip_bend = tip_bend.max(bend);
            }
            assert_eq!(compared, 3, "nodes 0, 5 and 10");
        }
        assert!(
            tip_bend > 0.01,
            "the frames bend the beam by only {tip_bend} m"
        );
    }

    /// A rod with assumed modes (docs/model-format.md's example, turned on
    /// a hub) is drawn along its shape functions: the station at `L/2`
    /// of the page, evaluated as the page does, is the model's own
    /// `NodePosition` output of a named node there, and its first shape
    /// `v = sin(πx/L)` bends it by `q₁` in the body's `y` there.
    #[test]
    fn assumed_modes_are_drawn_along_their_shapes() {
        let text = r#"Model(name: "assumed_rod", parameters: [(name: "L", value: 10.0)],
            bodies: [(name: "rod", flexible: AssumedModes(
                length: "L", rho_a: 1.2, rho_ip: 1e-4, ea: 2.8e7, ei_y: 1.4e4, ei_z: 1.4e4, gj: 1e4,
                shapes: [(v: "sin(pi*x/L)"), (v: "sin(2*pi*x/L)", w: "0"),
                         (u: "sin(pi*x/(2*L))"), (phi: "sin(pi*x/(2*L))")],
                nodes: [(name: "mid", x: "L/2")]))],
            joints: [(name: "hub", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "rod")],
            outputs: [NodePosition(body: "rod", node: 0)])"#;
        let dir = std::env::temp_dir().join(format!("eom-assumed-{}", std::process::id()));
        let _ = std::fs::create_dir_all(&dir);
        let path = dir.join("assumed_rod.ron");
        let _ = std::fs::write(&path, text);
        let opened = crate::open::open(
            &path.display().to_string(),
            &Default::default(),
            &Default::default(),
        );
        let _ = std::fs::remove_dir_all(&dir);
        let opened = match opened {
            Ok(o) => o,
            Err(_) => panic!("cannot open the assumed-modes rod"),
        };
        let sys = &opened.checked.system;
        let f =
            match eom_gen::mech::formulate(sys, eom_gen::functions::FunctionSet::all_requested()) {
                Ok(f) => f,
                Err(e) => panic!("{e}"),
            };
        let q = [0.4, 0.3, -0.1, 0.02, 0.05];
        let mut header = vec!["t".to_string()];
        header.extend(sys.coordinate_names().iter().map(|n| n.to_string()));
        let mut table = Table::new(header);
        table.push([0.0].into_iter().chain(q).collect());
        let page = match html(sys, &table, &[]) {
            Ok(p) => p,
            Err(e) => panic!("{e}"),
        };
        let start = page.find(r#"type="application/json">"#).map(|i| i + 24);
        let data = start.and_then(|s| Some(&page[s..s + page[s..].find("</script>")?]));
        let data: serde_json::Value = match data.map(serde_json::from_str) {
            Some(Ok(v)) => v,
            other => panic!("the page's data does not parse: {other:?}"),
        };
        let nums = |v: &serde_json::Value| -> Vec<f64> {
            v.as_array()
                .map(|a| a.iter().filter_map(serde_json::Value::as_f64).collect())
                .unwrap_or_default()
        };
        let flex = &data["flex"][0];
        let (p, shapes, qf) = (
            nums(&flex["p"]),
            nums(&flex["s"]),
            nums(&data["flexFrames"][0]),
        );
        assert_eq!(p.len(), 3 * (ASSUMED_PIECES + 1));
        assert_eq!(qf, q[1..]);
        let st = ASSUMED_PIECES / 2;
        let local: [f64; 3] = std::array::from_fn(|a| {
            p[3 * st + a]
                + (0..4)
                    .map(|m| shapes[12 * st + 4 * a + m] * qf[m])
                    .sum::<f64>()
        });
        // u = q₃ sin(π/4), v = q₁ sin(π/2) + q₂ sin(π) at x = L/2.
        let want_local = [5.0 + q[3] * (std::f64::consts::PI / 4.0).sin(), q[1], 0.0];
        for a in 0..3 {
            assert!(
                (local[a] - want_local[a]).abs() < 1e-6,
                "{local:?} vs {want_local:?}"
            );
        }
        let pose = nums(&data["poses"][0]);
        let (c, s) = (q[0].cos(), q[0].sin());
        assert!((pose[0..3].iter().map(|x| x.abs()).sum::<f64>()) < 1e-12);
        let drawn = [
            c * local[0] - s * local[1],
            s * local[0] + c * local[1],
            local[2],
        ];
        let x = eom_gen::interpret::Point {
            sys,
            q: &q,
            u: &[0.0; 5],
            udot: &[0.0; 5],
            tau: &[],
            inputs: &[],
            params: &[],
            multipliers: &[],
            t: 0.0,
        };
        let out =
            eom_gen::interpret::evaluate_function(&f, eom_gen::functions::Function::Outputs, &x)
                .unwrap_or_default();
        let Some(at) = f.output_names.iter().position(|n| n == "rod_node0_x") else {
            panic!("outputs {:?}", f.output_names)
        };
        for a in 0..3 {
            assert!(
                (drawn[a] - out[at + a]).abs() < 2e-6,
                "drawn {drawn:?}, output {:?}",
                &out[at..at + 3]
            );
        }
    }
}
