//! What `check`, `stats` and `dump` say about a model's cables (ANCF
//! chains): the chain (elements, nodes, coordinates, free coordinates), the
//! element kernel it runs (model-independent, generated once per element
//! type into `elements/src/`), its integration rule, and, for
//! `stats`, the kernel's operation counts from the symbolic derivation.

use eom_gen::System;
use eom_gen::ancf::{Kind, define, derive};
use eom_gen::sym::Arena;
use eom_sim::large::ancf::chain;
use serde_json::{Value, json};
use std::fmt::Write;

/// One cable's facts (no derivation: cheap).
struct Facts {
    name: String,
    kernel: String,
    elements: usize,
    nodes: usize,
    node_coords: usize,
    coordinates: usize,
    free: Option<usize>,
    kernel_coordinates: usize,
    parameters: Vec<&'static str>,
    rule: String,
    module: &'static str,
}

fn facts(sys: &System) -> Vec<Facts> {
    sys.cables
        .iter()
        .map(|c| {
            let spec = &c.chain;
            let def = Some(define(&mut Arena::new(), spec.element));
            let node_coords = def.as_ref().map_or(0, |d| d.node_coords);
            let nodes = spec.elements + 1;
            Facts {
                name: c.name.clone(),
                kernel: spec.element.name().to_string(),
                elements: spec.elements,
                nodes,
                node_coords,
                coordinates: nodes * node_coords,
                free: chain(&eom_gen::cables::chain_spec(c))
                    .ok()
                    .map(|ch| ch.model.n_free()),
                kernel_coordinates: 2 * node_coords,
                parameters: def
                    .as_ref()
                    .map_or_else(Vec::new, |d| d.params.iter().map(|p| p.0).collect()),
                rule: def
                    .as_ref()
                    .map_or_else(String::new, |d| d.integration.clone()),
                module: def.as_ref().map_or("", |d| d.module),
            }
        })
        .collect()
}

/// Lines for `check`'s human summary (empty without cables).
pub fn check_lines(sys: &System) -> String {
    let mut out = String::new();
    for f in facts(sys) {
        let _ = writeln!(
            out,
            "  cable        {}: {} × {} elements, {} nodes × {} = {} coordinates ({} free), \
             kernel eom_elements::{} ({} per element; parameters {})",
            f.name,
            f.kernel,
            f.elements,
            f.nodes,
            f.node_coords,
            f.coordinates,
            f.free.map_or("?".into(), |n| n.to_string()),
            f.kernel,
            f.kernel_coordinates,
            f.parameters.join(", ")
        );
        let _ = writeln!(out, "               rule: {}", f.rule);
    }
    out
}

/// The cables of `check --json` (replaces the short list).
pub fn check_json(sys: &System) -> Value {
    Value::Array(
        facts(sys)
            .into_iter()
            .map(|f| {
                json!({
                    "name": f.name,
                    "element": f.kernel,
                    "elements": f.elements,
                    "nodes": f.nodes,
                    "coordinates": f.coordinates,
                    "free_coordinates": f.free,
                    "kernel": format!("eom_elements::{}", f.kernel),
                    "kernel_file": format!("elements/src/{}.rs", f.module),
                    "kernel_coordinates": f.kernel_coordinates,
                    "parameters": f.parameters,
                    "rule": f.rule,
                })
            })
            .collect(),
    )
}

/// `stats` for the cables: per distinct element type its kernels'
/// operation counts (derived here, as `regenerate -- elements` does), per
/// cable the counts per call of the assembled forces and Jacobian. Human
/// text and JSON; both empty without cables.
pub fn stats(sys: &System) -> (String, Value) {
    let facts = facts(sys);
    if facts.is_empty() {
        return (String::new(), Value::Null);
    }
    let mut kinds: Vec<String> = facts.iter().map(|f| f.kernel.clone()).collect();
    kinds.sort();
    kinds.dedup();
    let mut text = String::from(
        "  cables: one model-independent kernel per element type (elements/src/), \
         applied by a loop over elements\n",
    );
    let _ = writeln!(
        text,
        "  {:<28} {:>8} {:>8} {:>6} {:>6} {:>6} {:>6} {:>6} {:>8}",
        "kernel", "add", "mul", "div", "neg", "sqrt", "trig", "other", "total"
    );
    let mut kernels = serde_json::Map::new();
    let mut per_call = std::collections::HashMap::new();
    for name in &kinds {
        let Some(k) = Kind::from_name(name) else {
            continue;
        };
        let derived = derive(k);
        let counts = derived.op_counts();
        let mut obj = serde_json::Map::new();
        for (part, c) in [
            "internal_forces",
            "internal_jacobians",
            "mass",
            "uniform_load",
        ]
        .iter()
        .zip(&counts)
        {
            let _ = writeln!(
                text,
                "  {:<28} {:>8} {:>8} {:>6} {:>6} {:>6} {:>6} {:>6} {:>8}",
                format!("{name}::{part}"),
                c.adds,
                c.muls,
                c.divs,
                c.negs,
                c.sqrts,
                c.trig,
                c.other,
                c.total()
            );
            obj.insert(
                part.to_string(),
                json!({
                    "add": c.adds, "mul": c.muls, "div": c.divs, "neg": c.negs,
                    "sqrt": c.sqrts, "trig": c.trig, "other": c.other, "total": c.total(),
                }),
            );
        }
        obj.insert("rule".into(), json!(derived.def.integration));
        kernels.insert(name.clone(), Value::Object(obj));
        per_call.insert(name.clone(), (counts[0].total(), counts[1].total()));
    }
    let mut cables = Vec::new();
    for f in &facts {
        let (fo, jo) = per_call.get(&f.kernel).copied().unwrap_or((0, 0));
        let _ = writeln!(
            text,
            "  cable {}: {} × {} elements, {} coordinates; one force evaluation {} ops, one Jacobian {} ops (kernel ops × elements, before assembly)",
            f.name,
            f.kernel,
            f.elements,
            f.coordinates,
            fo * f.elements,
            jo * f.elements
        );
        cables.push(json!({
            "name": f.name,
            "element": f.kernel,
            "elements": f.elements,
            "coordinates": f.coordinates,
            "free_coordinates": f.free,
            "forces_ops": fo * f.elements,
            "jacobian_ops": jo * f.elements,
        }));
    }
    (
        text,
        json!({ "kernels": Value::Object(kernels), "cables": cables }),
    )
}

/// What `dump` says on standard error for a model with cables: their
/// kernels are not in the dumped source.
pub fn dump_note(sys: &System) -> String {
    let mut out = String::new();
    for f in facts(sys) {
        let _ = writeln!(
            out,
            "note: cable `{}` ({} × {}) is not in this source: ANCF element kernels are \
             model-independent, generated once per element type into \
             elements/src/{}.rs (eom_elements::{}) and assembled at run time \
             by eom_sim::large (`solve-static`, `simulate`)",
            f.name, f.kernel, f.elements, f.module, f.kernel
        );
    }
    out
}
