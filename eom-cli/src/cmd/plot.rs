//! `eom-gen plot RUN.csv --y COLUMNS -o plot.svg`: time histories of a
//! run's CSV (`simulate --csv`), one panel per group of columns
//! (`crate::history`).

use crate::args::Vary;
use crate::error::Error;
use crate::output::fail;
use clap::Args;
use std::process::ExitCode;

/// Plot columns of a run's CSV against time, as SVG.
#[derive(Args)]
pub struct PlotArgs {
    /// The CSV of a run (`eom-gen simulate --csv`): `t` first, then named columns.
    pub csv: String,
    /// Columns to plot: comma-separated panels, `+` joining the columns of
    /// one panel (e.g. `theta,phi1+phi2,energy_drift`); `energy` and
    /// `energy_drift` are derived from `kinetic_energy` and `potential_energy`.
    #[arg(long, required = true)]
    pub y: Vec<String>,
    /// The SVG file to write.
    #[arg(short, long)]
    pub output: String,
    /// The model the run came from: the units of its coordinates and speeds.
    #[arg(long)]
    pub model: Option<String>,
}

pub fn run(a: &PlotArgs, urdf: &eom_gen::urdf::Options) -> ExitCode {
    let text = match std::fs::read_to_string(&a.csv) {
        Ok(t) => t,
        Err(e) => return fail(&Error::io(&a.csv, format!("cannot read it: {e}"))),
    };
    let mut table = match eom_sim::table::Table::from_csv(&text) {
        Ok(t) => t,
        Err(e) => return fail(&Error::Format(format!("{}: {e}", a.csv))),
    };
    crate::history::derive_columns(&mut table);
    let panels = match crate::history::parse_panels(&a.y, &table) {
        Ok(p) => p,
        Err(e) => return fail(&e),
    };
    let (units, labels) = match &a.model {
        Some(m) => match crate::open::open(m, urdf, &Vary::default()) {
            Ok(o) => (
                crate::history::model_units(&o.checked.system),
                crate::history::model_labels(&o.checked.system),
            ),
            Err(code) => return code,
        },
        None => Default::default(),
    };
    match crate::history::svg(&table, &panels, &units, &labels, &a.csv) {
        Ok(svg) => match crate::output::write_file(&a.output, &svg) {
            Ok(()) => {
                eprintln!("plot written to {}", a.output);
                ExitCode::SUCCESS
            }
            Err(code) => code,
        },
        Err(e) => fail(&e),
    }
}
