//! Errors about input a person wrote (designs, scenes): they name the file, the line when it is
//! known, the key, and what is allowed.

use std::fmt;

#[derive(Clone, Debug, PartialEq)]
pub struct InputError {
    /// The file (or a label such as `<override>`).
    pub file: String,
    /// 1-based line in that file, when known.
    pub line: Option<usize>,
    /// Dotted key path, e.g. `body.float.mass_kg`.
    pub key: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}:{}: `{}`: {}", self.file, l, self.key, self.message),
            None => write!(f, "{}: `{}`: {}", self.file, self.key, self.message),
        }
    }
}

impl std::error::Error for InputError {}

/// Finds the 1-based line of `key = …` in `text`, searching after the first line that contains
/// `anchor` (e.g. `name = "float"`) when given. Good enough to point a person at the place.
pub fn locate(text: &str, anchor: Option<&str>, key: &str) -> Option<usize> {
    let mut started = anchor.is_none();
    for (i, line) in text.lines().enumerate() {
        let l = line.trim_start();
        if !started {
            if anchor.is_some_and(|a| l.contains(a)) {
                started = true;
                if line_has_key(l, key) {
                    return Some(i + 1);
                }
            }
            continue;
        }
        if line_has_key(l, key) {
            return Some(i + 1);
        }
    }
    None
}

fn line_has_key(l: &str, key: &str) -> bool {
    // `key = …` at the start, or `, key = …` / `{ key = …` inside an inline table.
    let bytes = l.as_bytes();
    let mut from = 0;
    while let Some(p) = l[from..].find(key) {
        let start = from + p;
        let end = start + key.len();
        let before_ok = start == 0 || matches!(bytes[start - 1], b' ' | b'{' | b',');
        let after = l[end..].trim_start();
        if before_ok && after.starts_with('=') {
            return true;
        }
        from = end;
    }
    false
}

/// Converts a toml deserialisation error (which carries a byte span) into an [`InputError`].
pub fn from_toml(file: &str, text: &str, e: &toml::de::Error) -> InputError {
    let line = e
        .span()
        .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
    let msg = e.message().to_string();
    // The first back-quoted name is the key only in messages about a field; in others
    // ("unknown variant `x`") it is a value, and the key is the one written on the line.
    let quoted = msg.split('`').nth(1).map(str::to_string);
    let on_line = line.and_then(|l| key_on_line(text, l));
    let about_field = ["unknown field", "missing field", "duplicate key"]
        .iter()
        .any(|p| msg.starts_with(p));
    let key = if about_field {
        quoted.or(on_line)
    } else {
        on_line.or(quoted)
    }
    .unwrap_or_else(|| "(document)".to_string());
    InputError {
        file: file.to_string(),
        line,
        key,
        message: msg,
    }
}

/// The dotted key written on 1-based line `line` of a TOML text (`table.key` under a
/// `[table]` or `[[table]]` header), for errors whose message names no key (a value of the
/// wrong type says only what it expected).
fn key_on_line(text: &str, line: usize) -> Option<String> {
    let lines: Vec<&str> = text.lines().collect();
    let here = lines.get(line.checked_sub(1)?)?.trim();
    if here.starts_with('[') || here.starts_with('#') {
        return None;
    }
    let (key, _) = here.split_once('=')?;
    let key = key.trim().trim_matches('"');
    if key.is_empty() {
        return None;
    }
    let table = lines[..line - 1]
        .iter()
        .rev()
        .map(|l| l.trim())
        .find(|l| l.starts_with('['))
        .map(|l| {
            l.trim_start_matches('[')
                .split(']')
                .next()
                .unwrap_or("")
                .trim()
        });
    Some(match table {
        Some(t) if !t.is_empty() => format!("{t}.{key}"),
        _ => key.to_string(),
    })
}
