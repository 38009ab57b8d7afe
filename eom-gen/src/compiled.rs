//! Running the generated code compiled: `eom-gen eval` writes a small crate
//! around a model's generated source into a cache directory keyed by the
//! content hash, builds it in release mode once (cargo shows its progress),
//! and reuses the binary on later calls.
//!
//! The cache is `$EOM_CACHE_DIR`, else `$XDG_CACHE_HOME/eom`, else
//! `~/.cache/eom`; all cached crates share one target directory there.

use crate::emit::{camel, fnv1a};
use crate::interpret::Evaluation;
use std::path::PathBuf;
use std::process::Command;

fn cache_root() -> PathBuf {
    if let Some(d) = std::env::var_os("EOM_CACHE_DIR") {
        return PathBuf::from(d);
    }
    if let Some(d) = std::env::var_os("XDG_CACHE_HOME") {
        return PathBuf::from(d).join("eom");
    }
    match std::env::var_os("HOME") {
        Some(h) => PathBuf::from(h).join(".cache").join("eom"),
        None => std::env::temp_dir().join("eom-cache"),
    }
}

/// The `eom-sim` dependency line for the cached crate: this checkout's
/// source if present, else the published version.
fn eom_sim_dependency() -> String {
    let local = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../eom-sim"));
    match local.canonicalize() {
        Ok(p) if p.join("Cargo.toml").exists() => {
            format!("eom-sim = {{ path = {:?} }}", p.display().to_string())
        }
        _ => format!("eom-sim = \"{}\"", env!("CARGO_PKG_VERSION")),
    }
}

const MAIN: &str = r#"//! Evaluates the generated model at a state given on the command line and
//! prints JSON: `eval Q U TAU T` with comma-separated lists.
mod model;
use eom_sim::{Model, Vector};

fn list(s: &str) -> Vec<f64> {
    s.split(',').filter(|x| !x.trim().is_empty()).map(|x| x.trim().parse().unwrap_or(f64::NAN)).collect()
}

fn vector<V: Vector>(v: &[f64]) -> V {
    let mut out = V::ZERO;
    for (o, x) in out.as_mut().iter_mut().zip(v) {
        *o = *x;
    }
    out
}

fn json(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| if x.is_finite() { format!("{x:?}") } else { "null".into() }).collect();
    format!("[{}]", items.join(","))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |k: usize| args.get(k).map(String::as_str).unwrap_or("");
    let m = model::MODEL::default();
    let q: <model::MODEL as Model>::Q = vector(&list(arg(1)));
    let u: <model::MODEL as Model>::U = vector(&list(arg(2)));
    let tau: <model::MODEL as Model>::U = vector(&list(arg(3)));
    let t: f64 = arg(4).parse().unwrap_or(0.0);
    let mut qdot = <model::MODEL as Model>::Q::ZERO;
    m.qdot(&q, &u, &mut qdot);
    let mut udot = <model::MODEL as Model>::U::ZERO;
    m.forward_dynamics(t, &q, &u, &tau, &mut udot);
    let mut mm = <model::MODEL as Model>::MASS_ZERO;
    m.mass_matrix(t, &q, &mut mm);
    let mut b = <model::MODEL as Model>::U::ZERO;
    m.bias(t, &q, &u, &mut b);
    let e = m.energy(t, &q, &u);
    let rows: Vec<String> = mm.as_ref().iter().map(|r| json(r.as_ref())).collect();
    println!(
        "{{\"qdot\":{},\"udot\":{},\"mass_matrix\":[{}],\"bias\":{},\"kinetic_energy\":{},\"potential_energy\":{}}}",
        json(qdot.as_ref()), json(udot.as_ref()), rows.join(","), json(b.as_ref()), json(&e[..1]).trim_matches(|c| c == '[' || c == ']'), json(&e[1..]).trim_matches(|c| c == '[' || c == ']')
    );
}
"#;

/// Builds (once) and runs the compiled model at a state.
pub fn evaluate(
    name: &str,
    source: &str,
    q: &[f64],
    u: &[f64],
    tau: &[f64],
    t: f64,
) -> Result<Evaluation, String> {
    let root = cache_root();
    let key = format!("{:016x}", fnv1a(source.as_bytes()));
    let dir = root.join(format!("{name}-{key}"));
    let exe_name = format!("eom-eval-{name}-{key}");
    let target = root.join("target");
    let exe = target.join("release").join(&exe_name);
    if !exe.exists() {
        std::fs::create_dir_all(dir.join("src"))
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        let manifest = format!(
            "[package]\nname = \"{exe_name}\"\nversion = \"0.0.0\"\nedition = \"2024\"\npublish = false\n\n[dependencies]\n{}\n\n[workspace]\n",
            eom_sim_dependency()
        );
        let model = format!("{source}\npub type MODEL = {};\n", camel(name));
        for (file, text) in [
            ("Cargo.toml", manifest.as_str()),
            ("src/main.rs", MAIN),
            ("src/model.rs", model.as_str()),
        ] {
            std::fs::write(dir.join(file), text)
                .map_err(|e| format!("cannot write {file}: {e}"))?;
        }
        eprintln!("compiling the generated code of `{name}` in release mode (first time only) …");
        let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
            .args(["build", "--release", "--manifest-path"])
            .arg(dir.join("Cargo.toml"))
            .arg("--target-dir")
            .arg(&target)
            .status()
            .map_err(|e| format!("cannot run cargo: {e}"))?;
        if !status.success() {
            return Err(format!(
                "building the generated code failed ({status}); the crate is in {}",
                dir.display()
            ));
        }
    }
    let join = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:?}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    let out = Command::new(&exe)
        .args([join(q), join(u), join(tau), format!("{t:?}")])
        .output()
        .map_err(|e| format!("cannot run {}: {e}", exe.display()))?;
    let v: serde_json::Value = serde_json::from_slice(&out.stdout)
        .map_err(|e| format!("unexpected output of {}: {e}", exe.display()))?;
    let vec = |k: &str| -> Vec<f64> {
        v[k].as_array()
            .map(|a| a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect())
            .unwrap_or_default()
    };
    let mass_matrix = v["mass_matrix"]
        .as_array()
        .map(|rows| {
            rows.iter()
                .map(|r| {
                    r.as_array()
                        .map(|a| a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect())
                        .unwrap_or_default()
                })
                .collect()
        })
        .unwrap_or_default();
    Ok(Evaluation {
        qdot: vec("qdot"),
        udot: vec("udot"),
        mass_matrix,
        bias: vec("bias"),
        kinetic_energy: v["kinetic_energy"].as_f64().unwrap_or(f64::NAN),
        potential_energy: v["potential_energy"].as_f64().unwrap_or(f64::NAN),
    })
}
