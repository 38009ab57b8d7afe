//! Parameter studies (`eom-gen sweep`): the cases of a study (a grid, the
//! cartesian product of every `--param`'s values, or seeded random
//! samples), deterministic shards of them, and the results table (one row
//! per case: parameters, final state, chosen outputs, run statistics and
//! why the run stopped or failed) written as CSV (and Parquet with the
//! `parquet` feature), read back and merged.

use serde::{Deserialize, Serialize};

/// The values one `--param` takes.
#[derive(Clone, Debug, PartialEq)]
pub enum Axis {
    /// These values (`1,2,5`, `10:100:10`, `3`).
    Values(Vec<f64>),
    /// Uniform in `[a, b]` (`a:b`, with `--samples` only).
    Range(f64, f64),
}

/// Largest number of cases of one study.
pub const MAX_CASES: usize = 10_000_000;

/// `NAME=SPEC`: `a:b:step` (from `a` to `b` inclusive), `a:b` (uniform,
/// with `--samples`), `v1,v2,…` or one value.
pub fn parse_axis(item: &str) -> Result<(String, Axis), String> {
    let bad = |why: &str| {
        format!(
            "--param `{item}`: {why}; expected NAME=a:b:step (a grid from a to b), NAME=a:b \
             (uniform, with --samples), NAME=v1,v2,… or NAME=v"
        )
    };
    let (name, spec) = item.split_once('=').ok_or_else(|| bad("no `=`"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(bad("no name"));
    }
    let num = |x: &str| -> Result<f64, String> {
        x.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| bad(&format!("`{}` is not a finite number", x.trim())))
    };
    let axis = if spec.contains(':') {
        let parts: Vec<&str> = spec.split(':').collect();
        match parts.as_slice() {
            [a, b] => {
                let (a, b) = (num(a)?, num(b)?);
                if b < a {
                    return Err(bad("the range ends before it starts"));
                }
                Axis::Range(a, b)
            }
            [a, b, step] => {
                let (a, b, step) = (num(a)?, num(b)?, num(step)?);
                if step <= 0.0 {
                    return Err(bad("the step must be positive"));
                }
                if b < a {
                    return Err(bad("the range ends before it starts"));
                }
                let n = ((b - a) / step + 1e-9).floor();
                if n + 1.0 > MAX_CASES as f64 {
                    return Err(bad("too many values"));
                }
                Axis::Values((0..=n as usize).map(|i| a + i as f64 * step).collect())
            }
            _ => return Err(bad("too many `:`")),
        }
    } else {
        Axis::Values(spec.split(',').map(num).collect::<Result<_, _>>()?)
    };
    Ok((name.to_string(), axis))
}

/// What a study is: everything that decides its cases and their runs,
/// written to `study.json` beside the results so shards can be checked to
/// belong to one study before they are merged.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Study {
    /// The model file as given.
    pub model: String,
    /// The `--param` items as given.
    pub params: Vec<String>,
    /// Random samples instead of the grid.
    pub samples: Option<usize>,
    /// Seed of the samples.
    pub seed: u64,
    /// The run options (integrator, tolerances, end time, …).
    pub run: eom_sim::RunOptions,
    /// The outputs recorded at the end time.
    pub outputs: Vec<String>,
    /// Number of cases of the whole study.
    pub cases: usize,
    /// Generalized-α's spectral radius at infinity (models with cables).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rho_inf: Option<f64>,
}

/// splitmix64: a 64-bit mix with good avalanche (Steele, Lea and Flood
/// 2014), so sample `i` of parameter `j` depends only on the seed, `i` and
/// `j`, whichever shard draws it.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A uniform number in `[0, 1)` for sample `i`, parameter `j`.
fn uniform(seed: u64, i: usize, j: usize) -> f64 {
    let z = mix(mix(mix(seed) ^ i as u64) ^ j as u64);
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// The parameter values of every case: the grid (the first parameter
/// varies slowest) or `samples` seeded random draws (uniform in a range,
/// or one of the listed values).
pub fn cases(
    axes: &[(String, Axis)],
    samples: Option<usize>,
    seed: u64,
) -> Result<Vec<Vec<f64>>, String> {
    if let Some(n) = samples {
        if n == 0 || n > MAX_CASES {
            return Err(format!("--samples must be from 1 to {MAX_CASES}"));
        }
        return Ok((0..n)
            .map(|i| {
                axes.iter()
                    .enumerate()
                    .map(|(j, (_, a))| {
                        let u = uniform(seed, i, j);
                        match a {
                            Axis::Range(lo, hi) => lo + u * (hi - lo),
                            Axis::Values(v) => v[((u * v.len() as f64) as usize).min(v.len() - 1)],
                        }
                    })
                    .collect()
            })
            .collect());
    }
    let mut total: usize = 1;
    for (name, a) in axes {
        match a {
            Axis::Range(lo, hi) => {
                return Err(format!(
                    "--param {name}={lo}:{hi} is a range to sample: give --samples N, or a grid step \
                     ({name}={lo}:{hi}:STEP)"
                ));
            }
            Axis::Values(v) => {
                total = total.saturating_mul(v.len());
            }
        }
    }
    if total > MAX_CASES {
        return Err(format!(
            "the grid has {total} cases, more than {MAX_CASES}: use fewer values or --samples"
        ));
    }
    let mut out = vec![Vec::new()];
    for (_, a) in axes {
        let Axis::Values(v) = a else { continue };
        out = out
            .into_iter()
            .flat_map(|row| {
                v.iter().map(move |x| {
                    let mut r = row.clone();
                    r.push(*x);
                    r
                })
            })
            .collect();
    }
    Ok(out)
}

/// `--shard I/N`: slice `I` (0-based) of `N`.
pub fn parse_shard(text: &str) -> Result<(usize, usize), String> {
    let parsed = text.split_once('/').and_then(|(i, n)| {
        let (i, n) = (
            i.trim().parse::<usize>().ok()?,
            n.trim().parse::<usize>().ok()?,
        );
        (n > 0 && i < n).then_some((i, n))
    });
    parsed.ok_or_else(|| {
        format!(
            "--shard `{text}`: expected I/N with 0 ≤ I < N (slice I of N, counted from 0; \
             Slurm: --shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT with --array=0-(N-1))"
        )
    })
}

/// The case indices of shard `i` of `n`: every `n`-th case from `i`, so
/// slices are as even in cost as the cases are mixed.
pub fn shard(cases: usize, (i, n): (usize, usize)) -> Vec<usize> {
    (i..cases).step_by(n).collect()
}

/// The results: numbers under named columns (`case` first) and per row
/// why the run stopped (`finished`) or failed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Results {
    /// Numbers (`eom_sim::table::Table`, written the same way).
    pub table: eom_sim::table::Table,
    /// The `stop` column, per row.
    pub stop: Vec<String>,
}

impl Results {
    /// The CSV: the table's columns, then `stop` quoted.
    pub fn to_csv(&self) -> String {
        let numbers = self.table.to_csv();
        let mut lines = numbers.lines();
        let mut out = format!("{},stop\n", lines.next().unwrap_or_default());
        for (line, stop) in lines.zip(&self.stop) {
            out += &format!("{line},\"{}\"\n", stop.replace('"', "\"\""));
        }
        out
    }

    /// Reads [`Results::to_csv`] back.
    pub fn from_csv(text: &str) -> Result<Results, String> {
        let mut numbers = String::new();
        let mut stop = Vec::new();
        for (k, line) in text.lines().enumerate() {
            if k == 0 {
                let header = line
                    .strip_suffix(",stop")
                    .ok_or("the header does not end with `stop`: not a sweep's results.csv")?;
                numbers += header;
            } else {
                let q = line
                    .find(",\"")
                    .ok_or_else(|| format!("line {}: no quoted `stop` field", k + 1))?;
                numbers += &line[..q];
                let s = line[q + 2..]
                    .strip_suffix('"')
                    .ok_or_else(|| format!("line {}: the `stop` field is not closed", k + 1))?;
                stop.push(s.replace("\"\"", "\""));
            }
            numbers.push('\n');
        }
        let table = eom_sim::table::Table::from_csv(&numbers)?;
        Ok(Results { table, stop })
    }

    /// Parquet: every numeric column `DOUBLE`, `stop` a UTF-8 string.
    #[cfg(feature = "parquet")]
    pub fn write_parquet(&self, path: &std::path::Path) -> Result<(), String> {
        use parquet::data_type::{ByteArray, ByteArrayType, DoubleType};
        use parquet::file::writer::SerializedFileWriter;
        use parquet::schema::parser::parse_message_type;
        use std::sync::Arc;
        let fields: String = self
            .table
            .header
            .iter()
            .enumerate()
            .map(|(k, _)| format!("REQUIRED DOUBLE c{k};"))
            .collect();
        let schema = parse_message_type(&format!(
            "message results {{ {fields} REQUIRED BYTE_ARRAY stop (UTF8); }}"
        ))
        .map_err(|e| e.to_string())?;
        // Column names as written (parquet's schema text cannot hold every
        // name a model may use): renamed after parsing.
        let mut fields: Vec<parquet::schema::types::TypePtr> = schema.get_fields().to_vec();
        for (f, name) in fields.iter_mut().zip(&self.table.header) {
            let t = parquet::schema::types::Type::primitive_type_builder(
                name,
                parquet::basic::Type::DOUBLE,
            )
            .with_repetition(parquet::basic::Repetition::REQUIRED)
            .build()
            .map_err(|e| e.to_string())?;
            *f = Arc::new(t);
        }
        let schema = parquet::schema::types::Type::group_type_builder("results")
            .with_fields(fields)
            .build()
            .map_err(|e| e.to_string())?;
        let file = std::fs::File::create(path).map_err(|e| e.to_string())?;
        let mut w = SerializedFileWriter::new(file, Arc::new(schema), Default::default())
            .map_err(|e| e.to_string())?;
        let mut rg = w.next_row_group().map_err(|e| e.to_string())?;
        let mut k = 0;
        while let Some(mut c) = rg.next_column().map_err(|e| e.to_string())? {
            if k < self.table.header.len() {
                let v: Vec<f64> = self.table.rows.iter().map(|r| r[k]).collect();
                c.typed::<DoubleType>()
                    .write_batch(&v, None, None)
                    .map_err(|e| e.to_string())?;
            } else {
                let v: Vec<ByteArray> = self
                    .stop
                    .iter()
                    .map(|s| ByteArray::from(s.as_str()))
                    .collect();
                c.typed::<ByteArrayType>()
                    .write_batch(&v, None, None)
                    .map_err(|e| e.to_string())?;
            }
            c.close().map_err(|e| e.to_string())?;
            k += 1;
        }
        rg.close().map_err(|e| e.to_string())?;
        w.close().map_err(|e| e.to_string())?;
        Ok(())
    }

    /// Writes `results.csv` (and `results.parquet` with the `parquet`
    /// feature) and `study.json` into `dir`; the files written.
    pub fn write(&self, dir: &std::path::Path, study: &Study) -> Result<Vec<String>, String> {
        let mut written = Vec::new();
        let csv = dir.join("results.csv");
        std::fs::write(&csv, self.to_csv()).map_err(|e| format!("`{}`: {e}", csv.display()))?;
        written.push(csv.display().to_string());
        #[cfg(feature = "parquet")]
        {
            let pq = dir.join("results.parquet");
            self.write_parquet(&pq)
                .map_err(|e| format!("`{}`: {e}", pq.display()))?;
            written.push(pq.display().to_string());
        }
        let json = dir.join("study.json");
        let text = serde_json::to_string_pretty(study).map_err(|e| e.to_string())?;
        std::fs::write(&json, text + "\n").map_err(|e| format!("`{}`: {e}", json.display()))?;
        Ok(written)
    }
}

/// Reads the shards in `dirs` (each `results.csv` and `study.json` of one
/// study) and joins them in case order. Shards of different studies, the
/// same case twice or a case missing are errors.
pub fn merge(dirs: &[String]) -> Result<(Study, Results), String> {
    let mut study: Option<Study> = None;
    let mut rows: Vec<(usize, Vec<f64>, String)> = Vec::new();
    let mut header: Option<Vec<String>> = None;
    for d in dirs {
        let dir = std::path::Path::new(d);
        let read = |f: &str| {
            std::fs::read_to_string(dir.join(f))
                .map_err(|e| format!("`{}`: {e}", dir.join(f).display()))
        };
        let s: Study = serde_json::from_str(&read("study.json")?)
            .map_err(|e| format!("`{d}/study.json`: {e}"))?;
        match &study {
            Some(first) if *first != s => {
                return Err(format!(
                    "`{d}` is a shard of another study than `{}` (model, parameters, samples, seed, \
                     run options or outputs differ)",
                    dirs[0]
                ));
            }
            Some(_) => {}
            None => study = Some(s),
        }
        let r = Results::from_csv(&read("results.csv")?)
            .map_err(|e| format!("`{d}/results.csv`: {e}"))?;
        match &header {
            Some(h) if *h != r.table.header => {
                return Err(format!(
                    "`{d}/results.csv` has other columns than `{}`",
                    dirs[0]
                ));
            }
            Some(_) => {}
            None => header = Some(r.table.header.clone()),
        }
        for (row, stop) in r.table.rows.into_iter().zip(r.stop) {
            rows.push((row[0] as usize, row, stop));
        }
    }
    let (Some(study), Some(header)) = (study, header) else {
        return Err("--merge names no directory".into());
    };
    rows.sort_by_key(|r| r.0);
    for w in rows.windows(2) {
        if w[0].0 == w[1].0 {
            return Err(format!("case {} is in two shards", w[0].0));
        }
    }
    let have: Vec<usize> = rows.iter().map(|r| r.0).collect();
    let missing: Vec<usize> = (0..study.cases)
        .filter(|c| have.binary_search(c).is_err())
        .collect();
    if !missing.is_empty() {
        let shown: Vec<String> = missing.iter().take(10).map(usize::to_string).collect();
        return Err(format!(
            "{} of {} cases are in no shard (cases {}{}): a shard is missing",
            missing.len(),
            study.cases,
            shown.join(", "),
            if missing.len() > 10 { ", …" } else { "" }
        ));
    }
    let mut table = eom_sim::table::Table::new(header);
    let mut stop = Vec::new();
    for (_, row, s) in rows {
        table.push(row);
        stop.push(s);
    }
    Ok((study, Results { table, stop }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_parse_grids_lists_and_ranges() {
        let (n, a) = parse_axis("k=10:100:10").unwrap_or_default_axis();
        assert_eq!(n, "k");
        assert_eq!(a, Axis::Values((1..=10).map(|i| 10.0 * i as f64).collect()));
        assert_eq!(
            parse_axis("m=1,2").ok(),
            Some(("m".into(), Axis::Values(vec![1.0, 2.0])))
        );
        assert_eq!(
            parse_axis("m=1:2").ok(),
            Some(("m".into(), Axis::Range(1.0, 2.0)))
        );
        for bad in ["k", "=1", "k=1:0:1", "k=0:1:0", "k=a", "k=1:2:3:4", "k=nan"] {
            assert!(parse_axis(bad).is_err(), "{bad}");
        }
    }

    trait OrDefault {
        fn unwrap_or_default_axis(self) -> (String, Axis);
    }
    impl OrDefault for Result<(String, Axis), String> {
        fn unwrap_or_default_axis(self) -> (String, Axis) {
            self.unwrap_or_else(|_| (String::new(), Axis::Values(Vec::new())))
        }
    }

    #[test]
    fn grid_is_the_cartesian_product_first_slowest() {
        let axes = vec![
            ("a".into(), Axis::Values(vec![1.0, 2.0])),
            ("b".into(), Axis::Values(vec![10.0, 20.0, 30.0])),
        ];
        let c = cases(&axes, None, 0).unwrap_or_default();
        assert_eq!(c.len(), 6);
        assert_eq!(c[0], vec![1.0, 10.0]);
        assert_eq!(c[2], vec![1.0, 30.0]);
        assert_eq!(c[3], vec![2.0, 10.0]);
    }

    #[test]
    fn samples_are_seeded_in_range_and_reproducible() {
        let axes = vec![
            ("a".into(), Axis::Range(-1.0, 3.0)),
            ("b".into(), Axis::Values(vec![5.0, 7.0])),
        ];
        let c = cases(&axes, Some(1000), 42).unwrap_or_default();
        assert_eq!(c, cases(&axes, Some(1000), 42).unwrap_or_default());
        assert_ne!(c, cases(&axes, Some(1000), 43).unwrap_or_default());
        assert!(c.iter().all(|r| (-1.0..3.0).contains(&r[0])));
        assert!(c.iter().all(|r| r[1] == 5.0 || r[1] == 7.0));
        // A uniform sample of 1000: its mean within 4 standard errors of 1.
        let mean = c.iter().map(|r| r[0]).sum::<f64>() / 1000.0;
        let se = 4.0 / 12f64.sqrt() / 1000f64.sqrt();
        assert!((mean - 1.0).abs() < 4.0 * se, "mean {mean}");
        assert!(cases(&axes, None, 0).is_err());
    }

    #[test]
    fn shards_partition_the_cases() {
        let mut all: Vec<usize> = (0..3).flat_map(|i| shard(10, (i, 3))).collect();
        all.sort_unstable();
        assert_eq!(all, (0..10).collect::<Vec<_>>());
        assert_eq!(parse_shard("2/4"), Ok((2, 4)));
        for bad in ["4/4", "1", "a/2", "0/0"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn results_read_back() {
        let mut table = eom_sim::table::Table::new(vec!["case".into(), "k".into()]);
        table.push(vec![0.0, 1.5]);
        table.push(vec![1.0, f64::NAN]);
        let r = Results {
            table,
            stop: vec!["finished".into(), "failed: \"x\", y".into()],
        };
        let back = Results::from_csv(&r.to_csv()).unwrap_or_default();
        assert_eq!(back.stop, r.stop);
        assert_eq!(back.table.rows[0], r.table.rows[0]);
        assert!(back.table.rows[1][1].is_nan());
    }

    #[cfg(feature = "parquet")]
    #[test]
    fn parquet_reads_back_with_its_names_and_values() {
        use parquet::file::reader::{FileReader, SerializedFileReader};
        let mut table = eom_sim::table::Table::new(vec!["case".into(), "bob.x".into()]);
        table.push(vec![0.0, 1.5]);
        table.push(vec![1.0, -2.25]);
        let r = Results {
            table,
            stop: vec!["finished".into(), "failed: why".into()],
        };
        let path = std::env::temp_dir().join(format!("eom-study-{}.parquet", std::process::id()));
        assert_eq!(r.write_parquet(&path), Ok(()));
        let file = std::fs::File::open(&path).expect("written");
        let reader = SerializedFileReader::new(file).expect("a parquet file");
        let names: Vec<String> = reader
            .metadata()
            .file_metadata()
            .schema()
            .get_fields()
            .iter()
            .map(|f| f.name().to_string())
            .collect();
        assert_eq!(names, ["case", "bob.x", "stop"]);
        let rows: Vec<String> = reader
            .get_row_iter(None)
            .expect("rows")
            .map(|r| r.map(|r| r.to_string()).unwrap_or_default())
            .collect();
        assert_eq!(rows.len(), 2);
        assert!(
            rows[1].contains("-2.25") && rows[1].contains("failed: why"),
            "{rows:?}"
        );
        let _ = std::fs::remove_file(path);
    }
}
