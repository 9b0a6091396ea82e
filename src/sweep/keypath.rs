//! Key paths in the scene's own syntax (`cloths[0].material.stretch`, `wind.velocity[2]`) and
//! setting them on a scene's YAML value before the scene's strict parse.

use serde_yaml_ng::{Mapping, Value};
use std::fmt;

/// Why a text is not a key path; carries the path's text and the part at fault.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum KeyPathError {
    #[error("empty key path")]
    Empty,
    #[error("`{text}`: a key is missing before `{rest}`")]
    MissingKey { text: String, rest: String },
    #[error("`{text}`: `{key}` is not a key name")]
    BadKey { text: String, key: String },
    #[error("`{text}`: `[` without `]`")]
    Unclosed { text: String },
    #[error("`{text}`: `[{index}]` is not a list index")]
    BadIndex { text: String, index: String },
    #[error("`{text}`: expected `.` before `{rest}`")]
    ExpectedDot { text: String, rest: String },
    #[error("`{text}`: ends with `.`")]
    TrailingDot { text: String },
}

/// Why a value cannot be set at a key path of a document: `walked` is the part of the path
/// that exists, `found` what is there.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SetError {
    #[error("`{walked}` is {found}, not a section with key `{key}`")]
    NotSection {
        walked: String,
        found: &'static str,
        key: String,
    },
    #[error("`{walked}` is {found}, not a list")]
    NotList { walked: String, found: &'static str },
    #[error("`{walked}`: index {index} out of range (the list has {len})")]
    OutOfRange {
        walked: String,
        index: usize,
        len: usize,
    },
}

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
    pub fn parse(text: &str) -> Result<KeyPath, KeyPathError> {
        let mut segments = Vec::new();
        let mut rest = text;
        let whole = || text.to_string();
        if rest.is_empty() {
            return Err(KeyPathError::Empty);
        }
        loop {
            let end = rest.find(['.', '[']).unwrap_or(rest.len());
            let key = &rest[..end];
            if key.is_empty() {
                // `[0]` right after another index is fine; anywhere else a key is missing.
                if !(rest.starts_with('[') && matches!(segments.last(), Some(Segment::Index(_)))) {
                    return Err(KeyPathError::MissingKey {
                        text: whole(),
                        rest: rest.to_string(),
                    });
                }
            } else {
                if !key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                    return Err(KeyPathError::BadKey {
                        text: whole(),
                        key: key.to_string(),
                    });
                }
                segments.push(Segment::Key(key.to_string()));
            }
            rest = &rest[end..];
            while let Some(after) = rest.strip_prefix('[') {
                let close = after
                    .find(']')
                    .ok_or_else(|| KeyPathError::Unclosed { text: whole() })?;
                let i: usize = after[..close].parse().map_err(|_| KeyPathError::BadIndex {
                    text: whole(),
                    index: after[..close].to_string(),
                })?;
                segments.push(Segment::Index(i));
                rest = &after[close + 1..];
            }
            if rest.is_empty() {
                break;
            }
            rest = rest
                .strip_prefix('.')
                .ok_or_else(|| KeyPathError::ExpectedDot {
                    text: whole(),
                    rest: rest.to_string(),
                })?;
            if rest.is_empty() {
                return Err(KeyPathError::TrailingDot { text: whole() });
            }
        }
        Ok(KeyPath {
            text: text.to_string(),
            segments,
        })
    }

    /// A path of plain keys (`robot.trajectory.points`), for paths the code itself names.
    pub fn of_keys(keys: &[&str]) -> KeyPath {
        KeyPath {
            text: keys.join("."),
            segments: keys.iter().map(|k| Segment::Key(k.to_string())).collect(),
        }
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
    pub fn set(&self, root: &mut Value, new: Value) -> Result<(), SetError> {
        let mut v = root;
        let mut walked = String::new();
        for s in &self.segments {
            if v.is_null() {
                *v = Value::Mapping(Mapping::new());
            }
            v = match s {
                Segment::Key(k) => {
                    let Value::Mapping(m) = v else {
                        return Err(SetError::NotSection {
                            walked,
                            found: describe(v),
                            key: k.clone(),
                        });
                    };
                    if !walked.is_empty() {
                        walked.push('.');
                    }
                    walked.push_str(k);
                    m.entry(Value::String(k.clone())).or_insert(Value::Null)
                }
                Segment::Index(i) => {
                    let Value::Sequence(l) = v else {
                        return Err(SetError::NotList {
                            walked,
                            found: describe(v),
                        });
                    };
                    let n = l.len();
                    walked.push_str(&format!("[{i}]"));
                    l.get_mut(*i).ok_or_else(|| SetError::OutOfRange {
                        walked: walked.clone(),
                        index: *i,
                        len: n,
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
        assert!(matches!(
            KeyPath::parse("a[x]"),
            Err(KeyPathError::BadIndex { index, .. }) if index == "x"
        ));
        assert_eq!(
            KeyPath::of_keys(&["robot", "trajectory", "points"]),
            KeyPath::parse("robot.trajectory.points").unwrap()
        );
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
        assert_eq!(
            e,
            SetError::OutOfRange {
                walked: "cloths[3]".into(),
                index: 3,
                len: 1
            }
        );
        assert!(e.to_string().contains("out of range"), "{e}");
        let e = KeyPath::parse("cloths[0].name.first")
            .unwrap()
            .set(&mut v, Value::from("x"))
            .unwrap_err();
        assert!(
            matches!(&e, SetError::NotSection { walked, found: "a string", key }
                if walked == "cloths[0].name" && key == "first"),
            "{e}"
        );
    }
}
