//! A minimal owned XML element tree on top of `quick-xml`, enough for Collada: element local
//! names (namespaces dropped), attributes, and concatenated text.

use quick_xml::events::{BytesStart, Event};

/// Why a Collada file is not an XML element tree; the parser's error is the source.
#[derive(Debug, thiserror::Error)]
pub enum XmlError {
    #[error("XML error at byte {position}")]
    Syntax {
        position: u64,
        #[source]
        source: quick_xml::Error,
    },
    #[error("bad attribute in <{element}>")]
    Attribute {
        element: String,
        #[source]
        source: quick_xml::events::attributes::AttrError,
    },
    #[error("bad attribute `{key}` in <{element}>")]
    AttributeValue {
        element: String,
        key: String,
        #[source]
        source: quick_xml::Error,
    },
    #[error("bad text encoding")]
    Encoding(#[source] quick_xml::encoding::EncodingError),
    #[error("XML nested deeper than {max} elements")]
    TooDeep { max: usize },
    #[error("unbalanced closing tag")]
    Unbalanced,
    #[error("document ended before the root element closed")]
    Unclosed,
}

#[derive(Debug, Default)]
pub(super) struct Element {
    pub name: String,
    pub attrs: Vec<(String, String)>,
    pub children: Vec<Element>,
    pub text: String,
}

/// Nesting deeper than this is rejected instead of recursing without bound later.
const MAX_DEPTH: usize = 256;

impl Element {
    pub fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    pub fn child(&self, name: &str) -> Option<&Element> {
        self.children.iter().find(|c| c.name == name)
    }

    pub fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }

    /// Depth-first search for all descendants with this name.
    pub fn descendants_named<'a>(&'a self, name: &str, out: &mut Vec<&'a Element>) {
        for c in &self.children {
            if c.name == name {
                out.push(c);
            }
            c.descendants_named(name, out);
        }
    }
}

fn open(e: &BytesStart) -> Result<Element, XmlError> {
    let name = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
    let mut attrs = Vec::new();
    for a in e.attributes() {
        let a = a.map_err(|source| XmlError::Attribute {
            element: name.clone(),
            source,
        })?;
        let key = String::from_utf8_lossy(a.key.local_name().as_ref()).into_owned();
        let value = a
            .unescape_value()
            .map_err(|source| XmlError::AttributeValue {
                element: name.clone(),
                key: key.clone(),
                source,
            })?
            .into_owned();
        attrs.push((key, value));
    }
    Ok(Element {
        name,
        attrs,
        ..Default::default()
    })
}

/// Parses a whole document and returns its root element.
pub(super) fn parse(bytes: &[u8]) -> Result<Element, XmlError> {
    let mut reader = quick_xml::Reader::from_reader(bytes);
    let mut stack: Vec<Element> = Vec::new();
    let mut buf = Vec::new();
    loop {
        let event = reader
            .read_event_into(&mut buf)
            .map_err(|source| XmlError::Syntax {
                position: reader.error_position(),
                source,
            })?;
        match event {
            Event::Start(e) => {
                if stack.len() >= MAX_DEPTH {
                    return Err(XmlError::TooDeep { max: MAX_DEPTH });
                }
                stack.push(open(&e)?);
            }
            Event::Empty(e) => {
                let el = open(&e)?;
                match stack.last_mut() {
                    Some(parent) => parent.children.push(el),
                    None => return Ok(el),
                }
            }
            Event::End(_) => {
                let el = stack.pop().ok_or(XmlError::Unbalanced)?;
                match stack.last_mut() {
                    Some(parent) => parent.children.push(el),
                    None => return Ok(el),
                }
            }
            Event::Text(t) => {
                if let Some(top) = stack.last_mut() {
                    let s = t.decode().map_err(XmlError::Encoding)?;
                    top.text.push_str(&s);
                }
            }
            Event::CData(t) => {
                if let Some(top) = stack.last_mut() {
                    top.text.push_str(&String::from_utf8_lossy(&t));
                }
            }
            Event::Eof => return Err(XmlError::Unclosed),
            _ => {}
        }
        buf.clear();
    }
}
