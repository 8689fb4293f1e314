//! The design document before it is typed: `[parameters]` evaluated and `"= expression"` strings
//! replaced by their values, and a scene's overrides applied by dotted key path.

use crate::expr;
use std::collections::BTreeMap;

/// Evaluates the `[parameters]` table in order (numbers, or `"= expression"` of the parameters
/// before it), then replaces every `"= expression"` string elsewhere by its value. Hinge angles
/// and other relations stay strings (they are expressions of the coordinates, parsed later).
pub(super) fn resolve_expressions(doc: &mut toml::Value) -> Result<(), (String, String)> {
    let mut params: BTreeMap<String, f64> = BTreeMap::new();
    if let Some(toml::Value::Table(t)) = doc.get_mut("parameters") {
        for (k, v) in t.iter_mut() {
            let x = match v {
                toml::Value::Float(x) => *x,
                toml::Value::Integer(i) => *i as f64,
                toml::Value::String(s) if s.trim_start().starts_with('=') => {
                    let e = expr::parse(s.trim_start()[1..].trim(), &[], &params)
                        .map_err(|m| (format!("parameters.{k}"), m))?;
                    e.constant
                }
                _ => {
                    return Err((
                        format!("parameters.{k}"),
                        "must be a number or \"= expression\" of earlier parameters".into(),
                    ));
                }
            };
            if !x.is_finite() {
                return Err((
                    format!("parameters.{k}"),
                    format!("evaluates to {x} (allowed: finite)"),
                ));
            }
            params.insert(k.clone(), x);
            *v = toml::Value::Float(x);
        }
    }
    fn walk(
        v: &mut toml::Value,
        path: &str,
        params: &BTreeMap<String, f64>,
    ) -> Result<(), (String, String)> {
        match v {
            toml::Value::String(s) if s.trim_start().starts_with('=') => {
                let e = expr::parse(s.trim_start()[1..].trim(), &[], params)
                    .map_err(|m| (path.to_string(), m))?;
                if !e.constant.is_finite() {
                    return Err((
                        path.to_string(),
                        format!("evaluates to {} (allowed: finite)", e.constant),
                    ));
                }
                *v = toml::Value::Float(e.constant);
            }
            toml::Value::Table(t) => {
                for (k, x) in t.iter_mut() {
                    if path.is_empty() && k == "parameters" {
                        continue;
                    }
                    let name = x.get("name").and_then(|n| n.as_str()).map(str::to_string);
                    let p = if path.is_empty() {
                        k.clone()
                    } else {
                        format!("{path}.{k}")
                    };
                    let _ = name;
                    walk(x, &p, params)?;
                }
            }
            toml::Value::Array(a) => {
                for (i, x) in a.iter_mut().enumerate() {
                    let label = x
                        .get("name")
                        .and_then(|n| n.as_str())
                        .map_or(i.to_string(), str::to_string);
                    walk(x, &format!("{path}.{label}"), params)?;
                }
            }
            _ => {}
        }
        Ok(())
    }
    walk(doc, "", &params)
}

/// Applies `path = value` to a TOML document; arrays of tables are addressed by their `name`.
pub fn apply_override(doc: &mut toml::Value, path: &str, value: toml::Value) -> Result<(), String> {
    let parts: Vec<&str> = path.split('.').collect();
    let mut cur = doc;
    for (k, part) in parts.iter().enumerate() {
        let last = k + 1 == parts.len();
        match cur {
            toml::Value::Table(t) => {
                if last {
                    if !t.contains_key(*part) && k > 0 && parts[k - 1] != "parameters" {
                        // New keys are allowed only where the schema has optional fields; the
                        // typed pass after this reports anything unknown.
                    }
                    t.insert(part.to_string(), value);
                    return Ok(());
                }
                let keys: Vec<String> = t.keys().cloned().collect();
                cur = t
                    .get_mut(*part)
                    .ok_or_else(|| format!("no `{part}` here (present: {})", keys.join(", ")))?;
            }
            toml::Value::Array(a) => {
                let names: Vec<String> = a
                    .iter()
                    .filter_map(|x| x.get("name").and_then(|n| n.as_str()).map(str::to_string))
                    .collect();
                let idx = a
                    .iter()
                    .position(|x| x.get("name").and_then(|n| n.as_str()) == Some(part))
                    .or_else(|| part.parse::<usize>().ok().filter(|i| *i < a.len()))
                    .ok_or_else(|| {
                        format!("no entry named `{part}` (entries: {})", names.join(", "))
                    })?;
                if last {
                    a[idx] = value;
                    return Ok(());
                }
                cur = &mut a[idx];
            }
            _ => return Err(format!("`{part}` is inside a value that is not a table")),
        }
    }
    Err("empty override path".into())
}
