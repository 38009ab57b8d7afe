//! Time histories as SVG (plotters, SVG backend only): columns of a run's
//! CSV (`eom_sim::table::Table`) against `t`, one panel per group of
//! columns stacked under each other, each with its unit and a legend.
//! `eom-gen plot` draws the columns a user names; `simulate --plot` a
//! default set (coordinates, energy drift, constraint residuals).

use crate::error::Error;
use eom_sim::table::Table;
use plotters::prelude::*;
use std::collections::HashMap;

/// Units of columns by name (from the model: coordinates and speeds);
/// columns the runtime writes have theirs by name ([`unit`]).
pub type Units = HashMap<String, String>;

/// The columns derived from others when the CSV has what they need:
/// `energy = kinetic_energy + potential_energy` and `energy_drift =
/// energy − energy(t = 0)`. Added to `table` so they can be named.
pub fn derive_columns(table: &mut Table) {
    let (Some(t), Some(v)) = (
        table.column("kinetic_energy"),
        table.column("potential_energy"),
    ) else {
        return;
    };
    if table.header.iter().any(|h| h == "energy") {
        return;
    }
    let e: Vec<f64> = t.iter().zip(&v).map(|(a, b)| a + b).collect();
    let e0 = e.first().copied().unwrap_or(0.0);
    table.header.push("energy".into());
    table.header.push("energy_drift".into());
    for (row, e) in table.rows.iter_mut().zip(e) {
        row.push(e);
        row.push(e - e0);
    }
}

/// Names of columns as the user wrote them (from the model: the joints
/// a URDF import renamed, `joint_0_0` → `joint_0.0`), for legends.
pub type Labels = Vec<(String, String)>;

/// The renamed joints of a model: `(identifier, as written)`.
pub fn model_labels(sys: &eom_gen::system::System) -> Labels {
    sys.joints
        .iter()
        .filter_map(|j| Some((j.name.clone(), j.label.clone()?)))
        .collect()
}

/// A column's name in a legend: a renamed joint's identifier in it
/// replaced by the name as written (the longest that matches).
pub fn label_of(column: &str, labels: &Labels) -> String {
    let best = labels
        .iter()
        .filter(|(name, _)| column.contains(name.as_str()))
        .max_by_key(|(name, _)| name.len());
    match best {
        Some((name, label)) => column.replacen(name.as_str(), label, 1),
        None => column.to_string(),
    }
}

/// The unit of a column: the model's (`units`), else by the name the
/// runtime gives it, else none.
pub fn unit(column: &str, units: &Units) -> String {
    if let Some(u) = units.get(column) {
        return u.clone();
    }
    let u = match column {
        "t" => "s",
        "kinetic_energy" | "potential_energy" | "energy" | "energy_drift" => "J",
        c if c.starts_with("angular_momentum_") => "kg·m²/s",
        c if c.starts_with("linear_momentum_") => "kg·m/s",
        _ => "",
    };
    u.to_string()
}

/// The units of a model's coordinates and speeds where the joint says
/// (revolute, universal and screw angles in rad, prismatic in m, planar
/// `x, y, angle`); quaternions and modal coordinates have none.
pub fn model_units(sys: &eom_gen::system::System) -> Units {
    use eom_gen::system::JointType as J;
    let mut out = Units::new();
    for j in &sys.joints {
        let kinds: Vec<&str> = match j.kind {
            J::Revolute(_) | J::Screw(..) => vec!["rad"],
            J::Universal(..) => vec!["rad", "rad"],
            J::Prismatic(_) => vec!["m"],
            J::Planar => vec!["m", "m", "rad"],
            _ => continue,
        };
        if j.coordinate_names.len() != kinds.len() || j.speed_names.len() != kinds.len() {
            continue;
        }
        for ((q, u), k) in j.coordinate_names.iter().zip(&j.speed_names).zip(kinds) {
            out.insert(q.clone(), k.to_string());
            out.insert(u.clone(), format!("{k}/s"));
        }
    }
    out
}

/// One panel: its columns, drawn against `t` in one chart.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Column names.
    pub columns: Vec<String>,
}

/// Panels from `--y`: comma-separated panels, `+` joining the columns of
/// one panel (`theta,phi1+phi2,energy`). Every unknown column is an error
/// that names the columns there are.
pub fn parse_panels(spec: &[String], table: &Table) -> Result<Vec<Panel>, Error> {
    let mut panels = Vec::new();
    let mut unknown = Vec::new();
    for part in spec.iter().flat_map(|s| s.split(',')) {
        let columns: Vec<String> = part
            .split('+')
            .map(|c| c.trim().to_string())
            .filter(|c| !c.is_empty())
            .collect();
        for c in &columns {
            if !table.header.contains(c) {
                unknown.push(c.clone());
            }
        }
        if !columns.is_empty() {
            panels.push(Panel { columns });
        }
    }
    if !unknown.is_empty() {
        return Err(Error::Usage(vec![format!(
            "--y: no column {} in the file; its columns: {}",
            unknown
                .iter()
                .map(|c| format!("`{c}`"))
                .collect::<Vec<_>>()
                .join(", "),
            table.header.join(", ")
        )]));
    }
    if panels.is_empty() {
        return Err(Error::Usage(vec![format!(
            "--y names no column; the file's columns: {}",
            table.header.join(", ")
        )]));
    }
    Ok(panels)
}

/// The default panels of `simulate --plot`: the coordinates (in panels of
/// at most six, grouped by unit), the energy drift, the constraint
/// residuals, each where the table has it.
pub fn default_panels(table: &Table, coordinates: &[&str], units: &Units) -> Vec<Panel> {
    let mut panels: Vec<Panel> = Vec::new();
    let mut by_unit: Vec<(String, Vec<String>)> = Vec::new();
    for c in coordinates
        .iter()
        .filter(|c| table.header.iter().any(|h| h == *c))
    {
        let u = unit(c, units);
        match by_unit.iter_mut().find(|(x, _)| *x == u) {
            Some((_, v)) => v.push(c.to_string()),
            None => by_unit.push((u, vec![c.to_string()])),
        }
    }
    for (_, cols) in by_unit {
        for chunk in cols.chunks(6) {
            panels.push(Panel {
                columns: chunk.to_vec(),
            });
        }
    }
    for extra in [
        &["energy_drift"][..],
        &["constraint_residual", "velocity_constraint_residual"][..],
    ] {
        let columns: Vec<String> = extra
            .iter()
            .filter(|c| {
                table
                    .column(c)
                    .is_some_and(|v| v.iter().any(|x| x.is_finite()))
            })
            .map(|c| c.to_string())
            .collect();
        if !columns.is_empty() {
            panels.push(Panel { columns });
        }
    }
    panels
}

/// The panels drawn against `t` as one SVG document titled `title`.
pub fn svg(
    table: &Table,
    panels: &[Panel],
    units: &Units,
    labels: &Labels,
    title: &str,
) -> Result<String, Error> {
    let t = table.column("t").ok_or_else(|| {
        Error::Format(format!(
            "the file has no column `t` to plot against; its columns: {}",
            table.header.join(", ")
        ))
    })?;
    let mut out = String::new();
    draw(table, &t, panels, labels, units, title, &mut out)
        .map_err(|e| Error::Plot(format!("plotting {title}: {e}")))?;
    Ok(out)
}

/// Padded bounds of the finite values (a constant gets a unit band).
fn span(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        (-1.0, 1.0)
    } else if hi - lo <= 1e-12 * hi.abs().max(lo.abs()).max(1e-300) {
        let pad = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        (lo - pad, hi + pad)
    } else {
        let pad = 0.05 * (hi - lo);
        (lo - pad, hi + pad)
    }
}

fn draw(
    table: &Table,
    t: &[f64],
    panels: &[Panel],
    labels: &Labels,
    units: &Units,
    title: &str,
    out: &mut String,
) -> Result<(), Box<dyn std::error::Error>> {
    const HEIGHT: u32 = 240;
    let n = panels.len().max(1) as u32;
    let root = SVGBackend::with_string(out, (960, 50 + HEIGHT * n)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 18))?;
    let areas = root.split_evenly((panels.len().max(1), 1));
    let (t0, t1) = span(t.iter().copied());
    let (t0, t1) = match (t.first(), t.last()) {
        (Some(&a), Some(&b)) if b > a => (a, b),
        _ => (t0, t1),
    };
    for (k, (panel, area)) in panels.iter().zip(&areas).enumerate() {
        let series: Vec<(String, Vec<(f64, f64)>)> = panel
            .columns
            .iter()
            .filter_map(|c| {
                let v = table.column(c)?;
                let pts = t
                    .iter()
                    .zip(v)
                    .filter(|(a, b)| a.is_finite() && b.is_finite())
                    .map(|(a, b)| (*a, b))
                    .collect();
                Some((c.clone(), pts))
            })
            .collect();
        let (y0, y1) = span(series.iter().flat_map(|(_, p)| p.iter().map(|x| x.1)));
        let panel_units: Vec<String> = panel.columns.iter().map(|c| unit(c, units)).collect();
        let shared = panel_units.windows(2).all(|w| w[0] == w[1]);
        let y_desc = match panel_units.first() {
            Some(u) if shared && !u.is_empty() => u.clone(),
            _ => String::new(),
        };
        let mut chart = ChartBuilder::on(area)
            .margin(10)
            .x_label_area_size(if k + 1 == panels.len() { 36 } else { 20 })
            .y_label_area_size(80)
            .build_cartesian_2d(t0..t1, y0..y1)?;
        // Enough digits that neighbouring ticks differ (a small drift
        // about a large value).
        let digits =
            ((y0.abs().max(y1.abs()) / (y1 - y0)).log10().ceil() + 1.0).clamp(2.0, 12.0) as usize;
        let fmt = move |y: &f64| format!("{y:.digits$e}");
        let mut mesh = chart.configure_mesh();
        mesh.y_desc(y_desc.as_str()).y_label_formatter(&fmt);
        if k + 1 == panels.len() {
            mesh.x_desc("t, s");
        }
        mesh.draw()?;
        for (j, (name, pts)) in series.into_iter().enumerate() {
            let color = crate::plot::COLORS[j % crate::plot::COLORS.len()].to_rgba();
            let u = &panel_units[j];
            let name = label_of(&name, labels);
            let label = if shared || u.is_empty() {
                name
            } else {
                format!("{name}, {u}")
            };
            chart
                .draw_series(LineSeries::new(pts, color.stroke_width(2)))?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                });
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

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> Table {
        let mut t = Table::new(
            ["t", "theta", "kinetic_energy", "potential_energy"]
                .map(String::from)
                .to_vec(),
        );
        t.push(vec![0.0, 1.0, 0.0, -1.0]);
        t.push(vec![0.5, 0.0, 1.0, -2.0]);
        derive_columns(&mut t);
        t
    }

    #[test]
    fn energy_and_its_drift_are_derived() {
        // E = T + V: −1 then −1; the drift from E(0) is 0 both times.
        let t = table();
        assert_eq!(t.column("energy"), Some(vec![-1.0, -1.0]));
        assert_eq!(t.column("energy_drift"), Some(vec![0.0, 0.0]));
    }

    #[test]
    fn unknown_columns_are_named_with_the_ones_there_are() {
        let t = table();
        let e = parse_panels(&["theta,phi+energy,psi".into()], &t)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("no column `phi`, `psi`"), "{e}");
        assert!(e.contains("t, theta, kinetic_energy"), "{e}");
        let p = parse_panels(
            &["theta".into(), "kinetic_energy+potential_energy".into()],
            &t,
        );
        assert_eq!(p.map(|p| p.len()).ok(), Some(2));
    }

    /// A URDF joint renamed to an identifier is named as written in the
    /// legend.
    #[test]
    fn legends_name_joints_as_written() {
        let labels: Labels = vec![
            ("joint_0_0".into(), "joint_0.0".into()),
            ("j".into(), "J!".into()),
        ];
        assert_eq!(label_of("joint_0_0", &labels), "joint_0.0");
        assert_eq!(label_of("joint_0_0_dot", &labels), "joint_0.0_dot");
        assert_eq!(label_of("energy", &labels), "energy");
        let t = table();
        let panels = parse_panels(&["theta".into()], &t).unwrap_or_default();
        let labels: Labels = vec![("theta".into(), "θ (shoulder.1)".into())];
        let s = svg(&t, &panels, &Units::new(), &labels, "test").unwrap_or_default();
        assert!(s.contains("θ (shoulder.1)"), "{s}");
    }

    #[test]
    fn a_plot_has_its_panels_units_and_legend() {
        let t = table();
        let panels = parse_panels(&["theta,energy+energy_drift".into()], &t).unwrap_or_default();
        let units: Units = [("theta".to_string(), "rad".to_string())].into();
        let s = svg(&t, &panels, &units, &Labels::new(), "test").unwrap_or_default();
        for text in ["rad", "energy_drift", "t, s", "\nJ\n"] {
            assert!(s.contains(text), "no `{text}` in the SVG");
        }
    }
}
