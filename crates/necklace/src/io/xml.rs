//! A small XML scanner for the VTK XML files we read: start and end tags with their
//! attributes (entities unescaped), `<?xml?>` declarations, `<!-- -->` comments and
//! `<!DOCTYPE>`-like declarations skipped, text between tags left to the caller, every
//! position with its line for error messages. Not a validating parser: just enough for
//! `vtu`'s reader, which walks the tags and takes the text of the data arrays.

use super::text;
use crate::error::{Error, ErrorKind, Result};

/// A start or end tag.
pub(super) struct Tag<'a> {
    pub name: &'a [u8],
    pub attributes: Vec<(&'a [u8], String)>,
    pub closing: bool,
    pub self_closing: bool,
    pub line: usize,
}

impl Tag<'_> {
    pub fn attribute(&self, key: &str) -> Option<&str> {
        self.attributes
            .iter()
            .find(|(k, _)| *k == key.as_bytes())
            .map(|(_, value)| value.as_str())
    }

    /// An integer attribute, if present.
    pub fn int_attribute(&self, key: &str) -> Result<Option<i64>> {
        self.attribute(key)
            .map(|value| text::parse_int(value.as_bytes(), key, self.line))
            .transpose()
    }
}

/// A position in the file and its line.
pub(super) struct Scanner<'a> {
    pub data: &'a [u8],
    pub position: usize,
    pub line: usize,
}

impl<'a> Scanner<'a> {
    /// Move to `position`, counting the line breaks passed.
    pub fn advance_to(&mut self, position: usize) {
        let passed = &self.data[self.position..position];
        self.line += passed.iter().filter(|&&b| b == b'\n').count();
        self.position = position;
    }

    /// The position of the next `pattern` at or after the current position.
    pub fn find(&self, pattern: &[u8]) -> Option<usize> {
        self.data[self.position..]
            .windows(pattern.len())
            .position(|w| w == pattern)
            .map(|i| self.position + i)
    }

    /// Move past the next `pattern`, which must exist.
    pub fn skip_past(&mut self, pattern: &[u8]) -> Result<()> {
        let at = self.find(pattern).ok_or_else(|| {
            Error::new(
                ErrorKind::Truncated,
                format!("file ends before {}", String::from_utf8_lossy(pattern)),
            )
            .at_line(self.line)
        })?;
        self.advance_to(at + pattern.len());
        Ok(())
    }

    /// The next start or end tag; declarations and comments are skipped, text between
    /// tags is ignored.
    pub fn next_tag(&mut self) -> Result<Option<Tag<'a>>> {
        loop {
            let Some(at) = self.find(b"<") else {
                self.advance_to(self.data.len());
                return Ok(None);
            };
            self.advance_to(at);
            let rest = &self.data[at..];
            if rest.starts_with(b"<?") {
                self.skip_past(b"?>")?;
            } else if rest.starts_with(b"<!--") {
                self.skip_past(b"-->")?;
            } else if rest.starts_with(b"<!") {
                self.skip_past(b">")?;
            } else {
                return self.tag().map(Some);
            }
        }
    }

    /// The tag starting at the current `<`.
    pub fn tag(&mut self) -> Result<Tag<'a>> {
        let data = self.data;
        let line = self.line;
        let truncated = || Error::new(ErrorKind::Truncated, "file ends inside a tag").at_line(line);
        let syntax = |message: String| Error::new(ErrorKind::Syntax, message).at_line(line);
        let skip_space = |i: &mut usize| {
            while data.get(*i).is_some_and(u8::is_ascii_whitespace) {
                *i += 1;
            }
        };
        let take_name = |i: &mut usize| {
            let start = *i;
            while data
                .get(*i)
                .is_some_and(|&b| !b.is_ascii_whitespace() && !b"/>=".contains(&b))
            {
                *i += 1;
            }
            &data[start..*i]
        };

        let mut i = self.position + 1;
        let closing = data.get(i) == Some(&b'/');
        if closing {
            i += 1;
        }
        let name = take_name(&mut i);
        if name.is_empty() {
            return Err(data
                .get(i)
                .map_or_else(truncated, |_| syntax("a tag without a name".to_string())));
        }
        let mut attributes = Vec::new();
        let self_closing = loop {
            skip_space(&mut i);
            match data.get(i) {
                None => return Err(truncated()),
                Some(b'>') => {
                    i += 1;
                    break false;
                }
                Some(b'/') if !closing && data.get(i + 1) == Some(&b'>') => {
                    i += 2;
                    break true;
                }
                Some(_) if closing => {
                    return Err(syntax(format!(
                        "unexpected text in closing tag {}",
                        text::shown(name)
                    )))
                }
                Some(_) => {}
            }
            // An attribute: key = "value" (or 'value').
            let key = take_name(&mut i);
            skip_space(&mut i);
            match data.get(i) {
                None => return Err(truncated()),
                Some(b'=') if !key.is_empty() => i += 1,
                Some(_) => {
                    return Err(syntax(format!(
                        "expected an attribute 'name=\"value\"' in tag {}",
                        text::shown(name)
                    )))
                }
            }
            skip_space(&mut i);
            let quote = match data.get(i) {
                None => return Err(truncated()),
                Some(&quote) if quote == b'"' || quote == b'\'' => quote,
                Some(_) => {
                    return Err(syntax(format!(
                        "attribute {} has an unquoted value",
                        text::shown(key)
                    )))
                }
            };
            let value_start = i + 1;
            let value_end = data[value_start..]
                .iter()
                .position(|&b| b == quote)
                .map(|length| value_start + length)
                .ok_or_else(truncated)?;
            attributes.push((key, unescape(&data[value_start..value_end])));
            i = value_end + 1;
        };
        self.advance_to(i);
        Ok(Tag {
            name,
            attributes,
            closing,
            self_closing,
            line,
        })
    }
}

/// Replace the five predefined XML entities.
pub(super) fn unescape(value: &[u8]) -> String {
    String::from_utf8_lossy(value)
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}
