//! Running the generated code compiled: `eom-gen eval` writes a small crate
//! around a model's generated source into a cache directory keyed by the
//! content hash, builds it in release mode once (cargo shows its progress),
//! and reuses the binary on later calls.
//!
//! The cache is `$EOM_CACHE_DIR`, else `$XDG_CACHE_HOME/eom`, else
//! `~/.cache/eom`; all cached crates share one target directory there.

use crate::error::Error;
use eom_gen::emit::{camel, fnv1a};
use eom_gen::interpret::Evaluation;
use std::path::{Path, PathBuf};
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

/// The dependency lines of the cached crate: this checkout's `eom-sim` if
/// present, else the published version, with its `serde` feature, and
/// `serde` and `serde_json` for the request and the reply.
fn eom_sim_dependency() -> String {
    let local = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../eom-sim"));
    let sim = match local.canonicalize() {
        Ok(p) if p.join("Cargo.toml").exists() => format!(
            "eom-sim = {{ path = {:?}, features = [\"serde\"] }}",
            p.display().to_string()
        ),
        _ => format!(
            "eom-sim = {{ version = \"{}\", features = [\"serde\"] }}",
            env!("CARGO_PKG_VERSION")
        ),
    };
    format!("{sim}\nserde = {{ version = \"1\", features = [\"derive\"] }}\nserde_json = \"1\"")
}

/// A hash of the local runtime's sources (empty without a checkout), so a
/// changed `eom-sim` (or its lane type, `eom-lanes`) rebuilds the cached
/// crates.
fn runtime_fingerprint() -> String {
    fn walk(dir: &std::path::Path, out: &mut Vec<(PathBuf, Vec<u8>)>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push((p.clone(), std::fs::read(&p).unwrap_or_default()));
            }
        }
    }
    let mut files = Vec::new();
    for dir in ["/../eom-sim/src", "/../lanes/src"] {
        walk(
            &PathBuf::from(format!("{}{dir}", env!("CARGO_MANIFEST_DIR"))),
            &mut files,
        );
    }
    files.sort();
    let mut bytes = Vec::new();
    for (p, text) in files {
        bytes.extend(p.to_string_lossy().as_bytes());
        bytes.extend(text);
    }
    format!("{:016x}", fnv1a(&bytes))
}

/// The program around a model's generated source: one JSON request on the
/// command line, one JSON reply on standard output. Everything it does is
/// the runtime's (`eom_sim::simulate_generated`, `Model::evaluate`).
const MAIN: &str = r#"//! Runs the generated model for `eom-gen`: `Run` integrates it with
//! `eom_sim::simulate_generated`, `Eval` evaluates every function it offers.
mod model;
use eom_sim::Model;

#[derive(serde::Deserialize)]
struct Request {
    /// The model's runtime inputs, held constant (default: zero).
    #[serde(default)]
    inputs: Vec<f64>,
    what: What,
}

#[derive(serde::Deserialize)]
enum What {
    Run(eom_sim::RunOptions),
    /// `udot`: the accelerations of inverse dynamics and of outputs that
    /// depend on them; without, the model's forward dynamics at the state.
    /// `lambda`: the constraint multipliers of the reactions (default none).
    Eval {
        t: f64,
        q: Vec<f64>,
        u: Vec<f64>,
        tau: Vec<f64>,
        #[serde(default)]
        udot: Option<Vec<f64>>,
        #[serde(default)]
        lambda: Vec<f64>,
    },
}

fn main() {
    let arg = std::env::args().nth(1).unwrap_or_default();
    let mut m = model::MODEL::default();
    let request = serde_json::from_str::<Request>(&arg);
    if let Ok(r) = &request {
        for (d, s) in m.inputs.iter_mut().zip(&r.inputs) {
            *d = *s;
        }
    }
    let reply = match request.map(|r| r.what) {
        Ok(What::Run(o)) => serde_json::to_string(
            &eom_sim::simulate_generated::<model::MODEL, { model::NY }, { model::NYC }>(&m, &o)
                .map_err(|e| e.to_string()),
        ),
        Ok(What::Eval { t, q, u, tau, udot, lambda }) => {
            let at = eom_sim::Point { t, q: &q, u: &u, tau: &tau, lambda: &lambda, ..Default::default() };
            let udot = udot.unwrap_or_else(|| {
                let mut a = vec![f64::NAN; u.len()];
                m.evaluate("forward_dynamics", &at, &mut a);
                a
            });
            let at = eom_sim::Point { udot: &udot, ..at };
            let functions: Vec<(&str, Vec<f64>)> = model::MODEL::FUNCTIONS
                .iter()
                .map(|f| {
                    let mut out = vec![f64::NAN; f.len];
                    m.evaluate(f.name, &at, &mut out);
                    (f.name, out)
                })
                .collect();
            serde_json::to_string(&Ok::<_, String>(serde_json::json!({ "functions": functions })))
        }
        Err(e) => serde_json::to_string(&Err::<(), _>(format!("bad request: {e}"))),
    };
    match reply {
        Ok(text) => println!("{text}"),
        Err(e) => {
            eprintln!("cannot encode the reply: {e}");
            std::process::exit(1);
        }
    }
}
"#;

/// The release profile of the cached crates: one codegen unit, so the
/// generated functions and the loops that call them are optimised together.
const PROFILE: &str = "[profile.release]\ncodegen-units = 1\n";

/// The `model` module of a cached crate: the generated source, `MODEL`
/// (its type), `NQ`, `NY = NQ + NU` and `NYC = NY + NC`.
pub(crate) fn model_module(name: &str, source: &str, nq: usize, nu: usize) -> String {
    format!(
        "{source}\npub type MODEL = {};\n#[allow(dead_code)]\npub const NQ: usize = {nq};\npub const NY: usize = {};\npub const NYC: usize = NY + <MODEL as ::eom_sim::ConstrainedModel>::NC;\n",
        camel(name),
        nq + nu,
    )
}

/// Builds (once) the cached crate of a model and returns its executable.
pub fn executable(name: &str, source: &str, nq: usize, nu: usize) -> Result<PathBuf, Error> {
    let model = model_module(name, source, nq, nu);
    build_cached(&CachedCrate {
        prefix: "eom-eval",
        name,
        main: MAIN,
        model: &model,
        rustflags: None,
    })
}

/// Does the machine running this have fused multiply–add? Builds with
/// `-C target-cpu=native` then compile `f64::mul_add` to one instruction,
/// so the generated source may use it (`EmitOptions::fma`); without it
/// `mul_add` would be a libm call.
pub(crate) fn native_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("fma")
    }
    #[cfg(target_arch = "aarch64")]
    {
        true
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        false
    }
}

/// A binary crate around a model's generated source, built in the cache.
pub(crate) struct CachedCrate<'a> {
    /// First part of the binary's name (`eom-eval`, `eom-bench`).
    pub prefix: &'a str,
    /// The model's name.
    pub name: &'a str,
    /// `src/main.rs`; it declares `mod model;`.
    pub main: &'a str,
    /// `src/model.rs`: the generated source and whatever `main` needs.
    pub model: &'a str,
    /// Extra `rustc` flags (e.g. `-C target-cpu=native`); such builds use
    /// their own target directory so the default one is not rebuilt.
    pub rustflags: Option<&'a str>,
}

/// Builds (once) a cached crate in release mode and returns its executable.
/// The cache key covers the sources, the flags and the runtime used.
pub(crate) fn build_cached(c: &CachedCrate<'_>) -> Result<PathBuf, Error> {
    let root = cache_root();
    let key = format!(
        "{:016x}",
        fnv1a(
            format!(
                "{}{}{PROFILE}{}{}{}",
                c.model,
                c.main,
                eom_sim_dependency(),
                runtime_fingerprint(),
                c.rustflags.unwrap_or("")
            )
            .as_bytes()
        )
    );
    let name = c.name;
    let dir = root.join(format!("{name}-{key}"));
    let exe_name = format!("{}-{name}-{key}", c.prefix);
    let target = root.join(if c.rustflags.is_some() {
        "target-flags"
    } else {
        "target"
    });
    let exe = target.join("release").join(&exe_name);
    if !exe.exists() {
        std::fs::create_dir_all(dir.join("src"))
            .map_err(|e| Error::io(dir.display(), format!("cannot create the directory: {e}")))?;
        let manifest = format!(
            "[package]\nname = \"{exe_name}\"\nversion = \"0.0.0\"\nedition = \"2024\"\npublish = false\n\n[dependencies]\n{}\n\n[workspace]\n\n{PROFILE}",
            eom_sim_dependency()
        );
        for (file, text) in [
            ("Cargo.toml", manifest.as_str()),
            ("src/main.rs", c.main),
            ("src/model.rs", c.model),
        ] {
            std::fs::write(dir.join(file), text)
                .map_err(|e| Error::io(dir.join(file).display(), e))?;
        }
        eprintln!(
            "building the generated code of `{name}` in release mode, once: later runs reuse it from {} (cargo's progress follows) …",
            root.display()
        );
        let started = std::time::Instant::now();
        let mut cargo = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
        cargo
            .args(["build", "--release", "--manifest-path"])
            .arg(dir.join("Cargo.toml"))
            .arg("--target-dir")
            .arg(&target);
        if let Some(flags) = c.rustflags {
            cargo.env_remove("RUSTFLAGS").env(
                "CARGO_ENCODED_RUSTFLAGS",
                flags.split_whitespace().collect::<Vec<_>>().join("\u{1f}"),
            );
        }
        let status = cargo
            .status()
            .map_err(|e| Error::Build(format!("cannot run cargo: {e}")))?;
        if !status.success() {
            return Err(Error::Build(format!(
                "building the generated code failed ({status}); the crate is in {}",
                dir.display()
            )));
        }
        eprintln!(
            "built `{name}` in {:.0} s; cached",
            started.elapsed().as_secs_f64()
        );
    }
    Ok(exe)
}

/// Runs the cached executable of a model with one request and decodes
/// its reply.
fn request<T: serde::de::DeserializeOwned>(exe: &Path, request: &str) -> Result<T, Error> {
    let out = Command::new(exe)
        .arg(request)
        .output()
        .map_err(|e| Error::Program(format!("cannot run {}: {e}", exe.display())))?;
    if !out.status.success() {
        return Err(Error::Program(format!(
            "{} exited with {}: {}",
            exe.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    let reply: Result<T, String> = serde_json::from_slice(&out.stdout)
        .map_err(|e| Error::Program(format!("unexpected reply of {}: {e}", exe.display())))?;
    reply.map_err(Error::Refused)
}

/// Builds (once) and runs the compiled model at a state `at`: every
/// function it offers, as [`Evaluation`], at the accelerations `at.udot`
/// (when empty: the model's forward dynamics at the state).
pub fn evaluate(
    name: &str,
    source: &str,
    at: &eom_sim::Point<'_>,
    inputs: &[f64],
) -> Result<Evaluation, Error> {
    #[derive(serde::Deserialize)]
    struct Reply {
        functions: Vec<(String, Vec<Option<f64>>)>,
    }
    let exe = executable(name, source, at.q.len(), at.u.len())?;
    let udot = (!at.udot.is_empty()).then_some(at.udot);
    let req = serde_json::json!({
        "inputs": inputs,
        "what": { "Eval": { "t": at.t, "q": at.q, "u": at.u, "tau": at.tau, "udot": udot, "lambda": at.lambda } },
    });
    let reply: Reply = request(&exe, &req.to_string())?;
    Ok(Evaluation {
        functions: reply
            .functions
            .into_iter()
            .map(|(n, v)| (n, v.into_iter().map(|x| x.unwrap_or(f64::NAN)).collect()))
            .collect(),
    })
}

/// Integrates the compiled model (built once) with the runtime's runner.
pub fn simulate(
    name: &str,
    source: &str,
    nq: usize,
    nu: usize,
    options: &eom_sim::RunOptions,
    inputs: &[f64],
) -> Result<eom_sim::RunReport, Error> {
    let exe = executable(name, source, nq, nu)?;
    let req = serde_json::json!({ "inputs": inputs, "what": { "Run": options } });
    request(&exe, &req.to_string())
}
