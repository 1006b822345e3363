//! `xacro.load_yaml(FILE)`: a YAML file as a value (mappings are dicts, also readable as
//! `d.key`; sequences are lists), with xacro's unit tags `!radians`, `!degrees`, `!meters`,
//! `!millimeters`, `!foot`, `!inches` converting a scalar (an expression) to radians / metres.

use std::path::Path;
use std::rc::Rc;

use serde_yaml::Value as Yaml;

use crate::expr::{self, ExprError, Names};
use crate::value::Value;

/// Reads the YAML file `path`.
///
/// # Errors
/// Unreadable file, invalid YAML, a unit tag whose scalar is not a number.
pub fn load(source: &crate::files::Source, path: &Path) -> Result<Value, ExprError> {
    let text = crate::expand::read_capped(source, path)
        .map_err(|e| ExprError::new(format!("load_yaml: cannot read '{}': {e}", path.display())))?;
    let doc: Yaml = serde_yaml::from_str(&text).map_err(|e| {
        ExprError::new(format!(
            "load_yaml: {}: invalid YAML: {e}",
            crate::expand::display(path)
        ))
    })?;
    convert(&doc)
}

/// No names: a unit tag's scalar sees only the built-ins (`pi`, `radians()`).
struct Nothing;

impl Names for Nothing {
    fn lookup(&mut self, _: &str) -> Result<Option<Value>, ExprError> {
        Ok(None)
    }
    fn call(&mut self, _: &str, _: &[Value]) -> Result<Option<Value>, ExprError> {
        Ok(None)
    }
}

fn convert(y: &Yaml) -> Result<Value, ExprError> {
    Ok(match y {
        Yaml::Null => Value::None,
        Yaml::Bool(b) => Value::Bool(*b),
        Yaml::Number(n) => match n.as_i64() {
            Some(i) => Value::Int(i),
            None => Value::Float(n.as_f64().unwrap_or(f64::NAN)),
        },
        Yaml::String(s) => Value::str(s.as_str()),
        Yaml::Sequence(items) => Value::List(Rc::new(
            items.iter().map(convert).collect::<Result<_, _>>()?,
        )),
        Yaml::Mapping(m) => Value::Dict(Rc::new(
            m.iter()
                .map(|(k, v)| Ok((convert(k)?, convert(v)?)))
                .collect::<Result<_, ExprError>>()?,
        )),
        Yaml::Tagged(t) => {
            let tag = t.tag.to_string();
            let factor = match tag.trim_start_matches('!') {
                "radians" | "meters" => 1.0,
                "degrees" => std::f64::consts::PI / 180.0,
                "millimeters" => 0.001,
                "foot" => 0.3048,
                "inches" => 0.0254,
                _ => return convert(&t.value),
            };
            let src = match &t.value {
                Yaml::String(s) => s.clone(),
                Yaml::Number(n) => n.to_string(),
                other => {
                    return Err(ExprError::new(format!(
                        "load_yaml: expected a scalar after {tag}, found {other:?}"
                    )))
                }
            };
            let v = expr::evaluate(&src, &mut Nothing)?;
            let x = expr::num(&v, &tag)?.as_f64();
            Value::Float(x * factor)
        }
    })
}
