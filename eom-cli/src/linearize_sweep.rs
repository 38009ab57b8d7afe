//! `eom-gen linearize --sweep NAME=a:b:n`: the eigenvalues against a
//! parameter, as a table, JSON, CSV and an SVG of their real and imaginary
//! parts (one dot per eigenvalue and value: no tracking of branches, so
//! crossings are drawn as they are), and the stability boundaries: where
//! the number of eigenvalues in the right half-plane changes between two
//! points, the parameter is bisected (linearising again) to where an
//! eigenvalue or a pair crosses the imaginary axis — a bicycle's weave and
//! capsize speeds (`models/whipple.ron`).

use eom_gen::linearize::Eigenvalue;
use plotters::prelude::*;
use std::process::ExitCode;

/// One value of the parameter: its eigenvalues, or why it has none.
pub type SweepPoint = (f64, Result<Vec<Eigenvalue>, String>);

/// A stability boundary: across `value`, the count of eigenvalues with a positive real part goes from
/// `unstable_below` to `unstable_above` (in the sweep's direction).
#[derive(Clone, Debug)]
pub struct Crossing {
    /// The parameter's value at the boundary.
    pub value: f64,
    /// The crossing eigenvalue's imaginary part (rad/s): zero for a real
    /// one, else the frequency of the pair (a Hopf boundary).
    pub frequency: f64,
    /// Eigenvalues with positive real part just before the boundary.
    pub unstable_below: usize,
    /// And just after.
    pub unstable_above: usize,
}

/// Eigenvalues with a real part above `1e-10` of the largest modulus
/// (structural zeros — cyclic coordinates, conserved quantities — sit at
/// round-off, far below).
fn unstable(e: &[Eigenvalue]) -> usize {
    let scale = e.iter().map(|l| l.natural_frequency).fold(1.0, f64::max);
    e.iter().filter(|l| l.re > 1e-10 * scale).count()
}

/// The stability boundaries of a sweep: each change of [`unstable`]
/// between neighbouring points, bisected with `at` (the eigenvalues at a
/// value of the parameter) to `1e-7` relative, then a secant step on the
/// crossing eigenvalue's real part to `Re λ = 0`. A value where `at` fails
/// ends that bisection where it stands.
pub fn crossings(
    points: &[SweepPoint],
    at: &dyn Fn(f64) -> Option<Vec<Eigenvalue>>,
) -> Vec<Crossing> {
    let mut out = Vec::new();
    for pair in points.windows(2) {
        let ((a, Ok(ea)), (b, Ok(eb))) = (&pair[0], &pair[1]) else {
            continue;
        };
        let (na, nb) = (unstable(ea), unstable(eb));
        if na == nb {
            continue;
        }
        let (mut lo, mut hi) = (*a, *b);
        let (mut e_lo, mut e_hi) = (ea.clone(), eb.clone());
        let tol = 1e-7 * a.abs().max(b.abs()).max(1e-300);
        while (hi - lo).abs() > tol {
            let mid = 0.5 * (lo + hi);
            let Some(e) = at(mid) else { break };
            if unstable(&e) == na {
                (lo, e_lo) = (mid, e);
            } else {
                (hi, e_hi) = (mid, e);
            }
        }
        // The crossing eigenvalue: on the side with more unstable ones,
        // the unstable one nearest the axis. The count's threshold is a
        // hair right of the axis, so the last step is a secant on its real
        // part to Re λ = 0, from that side and a point ten brackets
        // further in (on the other side a structural zero can sit beside
        // it and be mistaken for it).
        let ((vu, eu), vs) = if nb > na {
            ((hi, &e_hi), lo)
        } else {
            ((lo, &e_lo), hi)
        };
        let nearest_unstable = |e: &[Eigenvalue]| {
            let scale = e.iter().map(|l| l.natural_frequency).fold(1.0, f64::max);
            e.iter()
                .filter(|l| l.re > 1e-10 * scale)
                .min_by(|x, y| x.re.total_cmp(&y.re))
                .copied()
        };
        let Some(lu) = nearest_unstable(eu) else {
            continue;
        };
        let v2 = vu + 10.0 * (vu - vs);
        let value = match at(v2).as_deref().and_then(nearest_unstable) {
            Some(l2) if l2.re != lu.re => vu - lu.re * (v2 - vu) / (l2.re - lu.re),
            _ => 0.5 * (vu + vs),
        };
        out.push(Crossing {
            value,
            frequency: lu.im.abs(),
            unstable_below: na,
            unstable_above: nb,
        });
    }
    out
}

/// Prints (text or `json`) and writes (`csv`, `svg`) a sweep; exit status
/// 0 when every point was linearised, 3 when some were not (each said why
/// on stderr and in the report), 1 if a file cannot be written.
pub fn report(
    name: &str,
    points: &[SweepPoint],
    crossings: &[Crossing],
    json: bool,
    csv: Option<&str>,
    svg: Option<&str>,
    model: &str,
) -> ExitCode {
    if let Some(path) = csv
        && let Err(code) = crate::output::write_file(path, &csv_text(name, points))
    {
        return code;
    }
    if let Some(path) = svg {
        let drawn = draw(name, points, model).map_err(|e| {
            crate::output::fail(&crate::error::Error::Plot(format!(
                "plotting the sweep of `{name}`: {e}"
            )))
        });
        match drawn {
            Ok(text) => {
                if let Err(code) = crate::output::write_file(path, &text) {
                    return code;
                }
            }
            Err(code) => return code,
        }
    }
    if json {
        let eig: Vec<serde_json::Value> = points
            .iter()
            .map(|(_, r)| match r {
                Ok(e) => serde_json::json!(e.iter().map(|l| [l.re, l.im]).collect::<Vec<_>>()),
                Err(_) => serde_json::Value::Null,
            })
            .collect();
        let errors: Vec<Option<&str>> = points
            .iter()
            .map(|(_, r)| r.as_ref().err().map(String::as_str))
            .collect();
        let v = serde_json::json!({
            "parameter": name,
            "values": points.iter().map(|(v, _)| *v).collect::<Vec<_>>(),
            "eigenvalues": eig,
            "errors": errors,
            "crossings": crossings.iter().map(|c| serde_json::json!({
                "value": c.value,
                "frequency": c.frequency,
                "unstable_below": c.unstable_below,
                "unstable_above": c.unstable_above,
            })).collect::<Vec<_>>(),
        });
        println!("{v}");
    } else {
        print!("{}", table(name, points));
        print!("{}", boundaries(name, crossings));
    }
    if points.iter().all(|(_, r)| r.is_ok()) {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(3)
    }
}

fn table(name: &str, points: &[SweepPoint]) -> String {
    let mut s = format!("{name:>12}  eigenvalues (re ± im i, 1/s)\n");
    for (v, r) in points {
        let row = match r {
            Ok(e) => e
                .iter()
                .map(|l| format!("{:.6}{:+.6}i", l.re, l.im))
                .collect::<Vec<_>>()
                .join("  "),
            Err(why) => format!("— ({why})"),
        };
        s += &format!("{v:>12.6}  {row}\n");
    }
    s
}

/// The stability boundaries, one line each.
fn boundaries(name: &str, crossings: &[Crossing]) -> String {
    let mut s = String::from("stability boundaries (eigenvalues with Re λ > 0 change)\n");
    if crossings.is_empty() {
        s += "  none in the range\n";
    }
    for c in crossings {
        let what = if c.frequency > 0.0 {
            format!(
                "a pair crosses the imaginary axis at ±{:.6}i rad/s",
                c.frequency
            )
        } else {
            "a real eigenvalue crosses zero".to_string()
        };
        s += &format!(
            "  {name} = {:.9}: {what}; unstable eigenvalues {} → {}\n",
            c.value, c.unstable_below, c.unstable_above
        );
    }
    s
}

fn csv_text(name: &str, points: &[SweepPoint]) -> String {
    let mut s = format!("{name},k,re,im,natural_frequency,damping_ratio\n");
    for (v, r) in points {
        if let Ok(e) = r {
            for (k, l) in e.iter().enumerate() {
                s += &format!(
                    "{v},{k},{},{},{},{}\n",
                    l.re, l.im, l.natural_frequency, l.damping_ratio
                );
            }
        }
    }
    s
}

/// The real parts (left) and imaginary parts (right) against the
/// parameter.
fn draw(
    name: &str,
    points: &[SweepPoint],
    model: &str,
) -> Result<String, Box<dyn std::error::Error>> {
    let mut out = String::new();
    {
        let all: Vec<(f64, &Eigenvalue)> = points
            .iter()
            .filter_map(|(v, r)| r.as_ref().ok().map(|e| (*v, e)))
            .flat_map(|(v, e)| e.iter().map(move |l| (v, l)))
            .filter(|(_, l)| l.re.is_finite() && l.im.is_finite())
            .collect();
        let span = |f: &dyn Fn(&Eigenvalue) -> f64| {
            let (lo, hi) = all
                .iter()
                .map(|(_, l)| f(l))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                    (a.min(x), b.max(x))
                });
            if !(lo.is_finite() && hi.is_finite()) {
                (-1.0, 1.0)
            } else if hi - lo < 1e-12 {
                (lo - 1.0, hi + 1.0)
            } else {
                let pad = 0.05 * (hi - lo);
                (lo - pad, hi + pad)
            }
        };
        let (x0, x1) = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (v, _)| {
                (a.min(*v), b.max(*v))
            });
        let (x0, x1) = if x1 > x0 {
            (x0, x1)
        } else {
            (x0 - 1.0, x0 + 1.0)
        };
        let root = SVGBackend::with_string(&mut out, (1100, 480)).into_drawing_area();
        root.fill(&WHITE)?;
        let root = root.titled(
            &format!("{model}: eigenvalues against `{name}`"),
            ("sans-serif", 18),
        )?;
        let (left, right) = root.split_horizontally(550);
        for (area, part, label) in [(left, 0, "Re λ, 1/s"), (right, 1, "Im λ, rad/s")] {
            let get = move |l: &Eigenvalue| if part == 0 { l.re } else { l.im };
            let (y0, y1) = span(&get);
            let mut chart = ChartBuilder::on(&area)
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .build_cartesian_2d(x0..x1, y0..y1)?;
            chart.configure_mesh().x_desc(name).y_desc(label).draw()?;
            if part == 0 && y0 < 0.0 && y1 > 0.0 {
                // Stability boundary.
                chart.draw_series(LineSeries::new(
                    [(x0, 0.0), (x1, 0.0)],
                    BLACK.mix(0.5).stroke_width(1),
                ))?;
            }
            chart.draw_series(
                all.iter()
                    .map(|(v, l)| Circle::new((*v, get(l)), 2, RGBColor(0, 114, 178).filled())),
            )?;
        }
        root.present()?;
    }
    Ok(out)
}
