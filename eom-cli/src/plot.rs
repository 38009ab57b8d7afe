//! Work-precision diagrams as SVG (plotters, SVG backend only): CPU time
//! per run against the error, log-log, one line per integrator (and
//! constraint solver), the error at the end time on the left and the
//! largest error along the path on the right.

use crate::sweep::WorkPrecision;
use plotters::prelude::*;

/// Errors below this are drawn at it (round-off level).
const ERROR_FLOOR: f64 = 1e-16;

/// The diagram of a sweep as an SVG document.
pub fn svg(w: &WorkPrecision) -> Result<String, crate::error::Error> {
    let mut out = String::new();
    draw(w, &mut out)
        .map_err(|e| crate::error::Error::Plot(format!("plotting {}: {e}", w.model)))?;
    Ok(out)
}

type Series = Vec<(String, Vec<(f64, f64)>)>;

/// Points with a finite error, grouped by series, as `(error, CPU ms)` in
/// sweep order (tolerances or steps decreasing).
fn series(w: &WorkPrecision, path: bool) -> Series {
    let mut out: Series = Vec::new();
    for p in &w.points {
        let name = p.series(w.constrained);
        let e = if path { p.path_error } else { p.end_error };
        let Some(e) = e.filter(|e| e.is_finite()) else {
            continue;
        };
        let xy = (e.max(ERROR_FLOOR), p.cpu_s * 1e3);
        match out.iter_mut().find(|(n, _)| *n == name) {
            Some((_, v)) => v.push(xy),
            None => out.push((name, vec![xy])),
        }
    }
    out
}

/// Distinct colours (Okabe–Ito, then darker shades), in series order:
/// every plot of the CLI draws its series in these.
pub(crate) const COLORS: [RGBColor; 10] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(230, 159, 0),
    RGBColor(0, 0, 0),
    RGBColor(120, 60, 20),
    RGBColor(90, 90, 160),
    RGBColor(130, 130, 130),
];

/// Decade bounds around the values.
fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), x| {
        (lo.min(x), hi.max(x))
    });
    if !(lo.is_finite() && hi > 0.0) {
        return (1e-3, 1.0);
    }
    let lo = 10f64.powf(lo.log10().floor());
    let hi = 10f64.powf(hi.log10().ceil());
    (lo, if hi > lo { hi } else { lo * 10.0 })
}

fn draw(w: &WorkPrecision, out: &mut String) -> Result<(), Box<dyn std::error::Error>> {
    let errors = w
        .points
        .iter()
        .flat_map(|p| [p.end_error, p.path_error])
        .flatten()
        .filter(|e| e.is_finite())
        .map(|e| e.max(ERROR_FLOOR));
    let (x0, x1) = range(errors);
    let (y0, y1) = range(w.points.iter().map(|p| p.cpu_s * 1e3).filter(|t| *t > 0.0));
    let root = SVGBackend::with_string(out, (1100, 520)).into_drawing_area();
    root.fill(&WHITE)?;
    let title = match &w.reference {
        Some(r) => format!(
            "{}: work-precision to t = {} s (reference {} at {:.0e}, checked by {} to {:.1e})",
            w.model, w.t_end, r.integrator, r.tol, r.check, r.check_end_error
        ),
        None => format!("{}: work-precision", w.model),
    };
    let root = root.titled(&title, ("sans-serif", 18))?;
    // The path panel only where path errors were measured.
    let panels: Vec<(DrawingArea<SVGBackend, plotters::coord::Shift>, bool)> =
        if w.points.iter().any(|p| p.path_error.is_some()) {
            let (left, right) = root.split_horizontally(550);
            vec![(left, false), (right, true)]
        } else {
            vec![(root.clone(), false)]
        };
    for (area, path) in panels {
        let mut chart = ChartBuilder::on(&area)
            .caption(
                if path {
                    "largest error along the path"
                } else {
                    "error at the end time"
                },
                ("sans-serif", 15),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
        chart
            .configure_mesh()
            .x_desc(w.error_label.as_str())
            .y_desc("CPU time per run, ms")
            .x_label_formatter(&|x| format!("{x:.0e}"))
            .y_label_formatter(&|y| format!("{y:.0e}"))
            .draw()?;
        // How far the reference is confirmed: errors left of this line
        // are below the agreement of the two reference methods.
        let floor = match &w.reference {
            Some(r) if path => r.check_path_error,
            Some(r) => r.check_end_error,
            None => f64::NAN,
        };
        if floor.is_finite() && floor > x0 && floor < x1 {
            chart
                .draw_series(DashedLineSeries::new(
                    [(floor, y0), (floor, y1)],
                    6,
                    4,
                    BLACK.mix(0.6).stroke_width(1),
                ))?
                .label("reference check")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.mix(0.6)));
        }
        for (k, (name, pts)) in series(w, path).into_iter().enumerate() {
            let color = COLORS[k % COLORS.len()].to_rgba();
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                });
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
    }
    root.present()?;
    Ok(())
}
