//! Key paths in the scene's own syntax (`cloths[0].material.stretch`, `wind.velocity[2]`) and
//! setting them on a scene's YAML value before the scene's strict parse.

use serde_yaml_ng::{Mapping, Value};
use std::fmt;

/// One step of a key path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Segment {
    Key(String),
    Index(usize),
}

/// A parsed key path; `Display` gives back its text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct KeyPath {
    text: String,
    segments: Vec<Segment>,
}

impl fmt::Display for KeyPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

impl KeyPath {
    /// Parses `a.b[0].c`. Keys are `[A-Za-z0-9_]+`; indices are decimal.
    pub fn parse(text: &str) -> Result<KeyPath, String> {
        let mut segments = Vec::new();
        let mut rest = text;
        if rest.is_empty() {
            return Err("empty key path".into());
        }
        loop {
            let end = rest.find(['.', '[']).unwrap_or(rest.len());
            let key = &rest[..end];
            if key.is_empty() {
                // `[0]` right after another index is fine; anywhere else a key is missing.
                if !(rest.starts_with('[') && matches!(segments.last(), Some(Segment::Index(_)))) {
                    return Err(format!("`{text}`: a key is missing before `{rest}`"));
                }
            } else {
                if !key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                    return Err(format!("`{text}`: `{key}` is not a key name"));
                }
                segments.push(Segment::Key(key.to_string()));
            }
            rest = &rest[end..];
            while let Some(after) = rest.strip_prefix('[') {
                let close = after
                    .find(']')
                    .ok_or_else(|| format!("`{text}`: `[` without `]`"))?;
                let i: usize = after[..close].parse().map_err(|_| {
                    format!("`{text}`: `[{}]` is not a list index", &after[..close])
                })?;
                segments.push(Segment::Index(i));
                rest = &after[close + 1..];
            }
            if rest.is_empty() {
                break;
            }
            rest = rest
                .strip_prefix('.')
                .ok_or_else(|| format!("`{text}`: expected `.` before `{rest}`"))?;
            if rest.is_empty() {
                return Err(format!("`{text}`: ends with `.`"));
            }
        }
        Ok(KeyPath {
            text: text.to_string(),
            segments,
        })
    }

    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// The value at this path, if the document has it.
    pub fn get<'a>(&self, root: &'a Value) -> Option<&'a Value> {
        let mut v = root;
        for s in &self.segments {
            v = match (s, v) {
                (Segment::Key(k), Value::Mapping(m)) => m.get(k.as_str())?,
                (Segment::Index(i), Value::Sequence(l)) => l.get(*i)?,
                _ => return None,
            };
        }
        Some(v)
    }

    /// Sets the value at this path. Missing sections are created (the scene's strict parse then
    /// rejects names it does not know); a list index past the end, or a step into a value that
    /// is not a section or a list, is an error that says which part of the path.
    pub fn set(&self, root: &mut Value, new: Value) -> Result<(), String> {
        let mut v = root;
        let mut walked = String::new();
        for s in &self.segments {
            if v.is_null() {
                *v = Value::Mapping(Mapping::new());
            }
            v = match s {
                Segment::Key(k) => {
                    let Value::Mapping(m) = v else {
                        return Err(format!(
                            "`{walked}` is {}, not a section with key `{k}`",
                            describe(v)
                        ));
                    };
                    if !walked.is_empty() {
                        walked.push('.');
                    }
                    walked.push_str(k);
                    m.entry(Value::String(k.clone())).or_insert(Value::Null)
                }
                Segment::Index(i) => {
                    let Value::Sequence(l) = v else {
                        return Err(format!("`{walked}` is {}, not a list", describe(v)));
                    };
                    let n = l.len();
                    walked.push_str(&format!("[{i}]"));
                    l.get_mut(*i).ok_or_else(|| {
                        format!("`{walked}`: index {i} out of range (the list has {n})")
                    })?
                }
            };
        }
        *v = new;
        Ok(())
    }
}

/// A value's kind for messages.
pub fn describe(v: &Value) -> &'static str {
    match v {
        Value::Null => "empty",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Sequence(_) => "a list",
        Value::Mapping(_) => "a section",
        Value::Tagged(_) => "a tagged value",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn yaml(s: &str) -> Value {
        serde_yaml_ng::from_str(s).unwrap()
    }

    #[test]
    fn parse_and_display() {
        let k = KeyPath::parse("cloths[0].material.stretch").unwrap();
        assert_eq!(
            k.segments(),
            &[
                Segment::Key("cloths".into()),
                Segment::Index(0),
                Segment::Key("material".into()),
                Segment::Key("stretch".into())
            ]
        );
        assert_eq!(k.to_string(), "cloths[0].material.stretch");
        assert!(KeyPath::parse("a[1][2].b").is_ok());
        for bad in ["", "a..b", "a.", ".a", "a[x]", "a[1", "a b", "a[0]b"] {
            assert!(KeyPath::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn set_creates_sections_and_checks_indices() {
        let mut v = yaml("cloths: [{ name: a, material: { stretch: 1 } }]\n");
        KeyPath::parse("cloths[0].material.stretch")
            .unwrap()
            .set(&mut v, Value::from(5))
            .unwrap();
        KeyPath::parse("wind.velocity")
            .unwrap()
            .set(&mut v, yaml("[1, 2, 3]"))
            .unwrap();
        assert_eq!(
            KeyPath::parse("cloths[0].material.stretch")
                .unwrap()
                .get(&v),
            Some(&Value::from(5))
        );
        assert_eq!(
            KeyPath::parse("wind.velocity[1]").unwrap().get(&v),
            Some(&Value::from(2))
        );
        let e = KeyPath::parse("cloths[3].name")
            .unwrap()
            .set(&mut v, Value::from("x"))
            .unwrap_err();
        assert!(e.contains("cloths[3]") && e.contains("out of range"), "{e}");
        let e = KeyPath::parse("cloths[0].name.first")
            .unwrap()
            .set(&mut v, Value::from("x"))
            .unwrap_err();
        assert!(e.contains("a string"), "{e}");
    }
}
