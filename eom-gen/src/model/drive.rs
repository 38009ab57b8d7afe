//! Inputs driven by expressions (`eom-gen simulate --input NAME=EXPR`): an
//! actuator's runtime input replaced by a known generalised force, an
//! expression of parameters, `pi`, time `t`, coordinates and speeds — a
//! prescribed torque history (`"2*sin(3*t)"`) or a control law
//! (`"-20*theta - 4*theta_dot"`). The input leaves the model's inputs; the
//! expression is generated like a `JointForce`, so it is simplified with the
//! rest of the equations.

use super::Checked;
use crate::diag::{Span, did_you_mean, list_names};
use crate::expr::Ast;
use crate::system::{Force, ForceElement, InitialValue, Quantity};
use std::collections::HashMap;
use std::fmt;

/// Why an input could not be driven.
#[derive(Clone, Debug, PartialEq)]
pub struct DriveError {
    /// The input as the user named it.
    pub input: String,
    /// What is wrong.
    pub message: String,
    /// What would be right.
    pub help: String,
}

impl fmt::Display for DriveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}; {}", self.message, self.help)
    }
}

impl std::error::Error for DriveError {}

/// Replaces each named input of `checked` by its expression (`(input,
/// expression)` pairs). Every problem at once: unknown inputs (with the
/// closest name), an input driven twice, expressions that do not parse or
/// use names the model does not have.
pub fn drive_inputs(
    checked: &mut Checked,
    drives: &[(String, String)],
) -> Result<(), Vec<DriveError>> {
    let sys = &mut checked.system;
    let mut errors = Vec::new();
    let mut parsed: Vec<(usize, Quantity)> = Vec::new();
    // Parameters at their defaults; time and the state at zero.
    let mut known: HashMap<String, f64> = sys
        .parameters
        .iter()
        .map(|p| (p.name.clone(), p.value.value))
        .collect();
    for name in sys.coordinate_names().into_iter().chain(sys.speed_names()) {
        known.insert(name.to_string(), 0.0);
    }
    known.insert("t".into(), 0.0);
    known.insert("pi".into(), std::f64::consts::PI);
    for (k, (input, text)) in drives.iter().enumerate() {
        let error = |message: String, help: String| DriveError {
            input: input.clone(),
            message,
            help,
        };
        let Some(index) = sys.inputs.iter().position(|n| n == input) else {
            let help = match did_you_mean(input, sys.inputs.iter().map(String::as_str)) {
                Some(best) => format!("did you mean `{best}`?"),
                None if sys.inputs.is_empty() => "the model has no inputs (actuators)".into(),
                None => format!(
                    "the model's inputs are {}",
                    list_names(sys.inputs.iter().map(String::as_str))
                ),
            };
            errors.push(error(format!("unknown input `{input}`"), help));
            continue;
        };
        if drives[..k].iter().any(|(other, _)| other == input) {
            errors.push(error(
                format!("input `{input}` is driven twice"),
                "give one expression per input".into(),
            ));
            continue;
        }
        let ast = match Ast::parse(text) {
            Ok(ast) => ast,
            Err(e) => {
                errors.push(error(
                    format!("in expression `{text}` for input `{input}`: {}", e.message),
                    e.help.to_string(),
                ));
                continue;
            }
        };
        let unknown: Vec<&str> = ast
            .names()
            .into_iter()
            .map(|(n, _)| n)
            .filter(|n| !known.contains_key(*n))
            .collect();
        if !unknown.is_empty() {
            for name in unknown {
                let help = match did_you_mean(name, known.keys().map(String::as_str)) {
                    Some(best) => format!("did you mean `{best}`?"),
                    None => "an input's expression may use parameters, `pi`, time `t`, coordinates and speeds".into(),
                };
                errors.push(error(
                    format!("unknown name `{name}` in the expression for input `{input}`"),
                    help,
                ));
            }
            continue;
        }
        let value = ast.eval(&|n| known.get(n).copied()).unwrap_or(f64::NAN);
        parsed.push((
            index,
            Quantity {
                expr: ast,
                value,
                span: Span::default(),
            },
        ));
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    // Highest index first, so the indices still to drive stay valid.
    parsed.sort_by_key(|p| std::cmp::Reverse(p.0));
    for (index, quantity) in parsed {
        let name = sys.inputs.remove(index);
        let mut driven = None;
        for force in &mut sys.forces {
            if let ForceElement::Actuator { joint, inputs } = &mut force.element {
                let nu = inputs.len();
                for (speed, slot) in inputs.iter_mut().enumerate() {
                    match *slot {
                        Some(i) if i == index => {
                            *slot = None;
                            driven = Some((*joint, speed, nu, force.span));
                        }
                        Some(i) if i > index => *slot = Some(i - 1),
                        _ => {}
                    }
                }
            }
        }
        // Every input belongs to one actuator (the validator made them).
        let Some((joint, speed, nu, span)) = driven else {
            continue;
        };
        let zero = Quantity {
            expr: Ast::Num(0.0),
            value: 0.0,
            span,
        };
        let mut values = vec![zero; nu];
        values[speed] = Quantity { span, ..quantity };
        let mut force_name = format!("{name}_driven");
        while sys.forces.iter().any(|f| f.name == force_name) {
            force_name.push('_');
        }
        sys.forces.push(Force {
            name: force_name,
            element: ForceElement::JointForce { joint, values },
            span,
        });
    }
    Ok(())
}

/// Replaces the initial positions and speeds of the coordinates the model
/// keeps (`eom-gen bench --q0 … --u0 …`): one value per coordinate or
/// speed, in the model's order, finite.
pub fn set_initial(
    checked: &mut Checked,
    q0: Option<&[f64]>,
    u0: Option<&[f64]>,
) -> Result<(), String> {
    let sys = &mut checked.system;
    for (what, values, speeds) in [("q0", q0, false), ("u0", u0, true)] {
        let Some(values) = values else { continue };
        let names = if speeds {
            sys.speed_names()
        } else {
            sys.coordinate_names()
        };
        if values.len() != names.len() {
            return Err(format!(
                "{what} has {} value(s); the model has {}: {}",
                values.len(),
                names.len(),
                list_names(names.iter().copied())
            ));
        }
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(format!("{what} holds {v}; give finite numbers"));
        }
        let names: Vec<String> = names.iter().map(|n| n.to_string()).collect();
        for (name, &value) in names.iter().zip(values) {
            // The model's own names: a joint's (set), or an elastic
            // coordinate of a flexible body, which starts undeformed.
            if sys.set_initial_value(name, speeds, value) != InitialValue::Set && value != 0.0 {
                return Err(format!(
                    "{what}: `{name}` is an elastic coordinate, which starts at zero"
                ));
            }
        }
    }
    Ok(())
}
