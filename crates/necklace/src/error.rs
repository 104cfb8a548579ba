//! The library's one error type.
//!
//! Every fallible call returns [`Result<T>`]. An [`Error`] says *what* went wrong
//! ([`ErrorKind`]), *where* (the file or source name, and a [`Location`]: a line or a
//! byte offset) and a short human message. Its `Display` is always a single line, e.g.
//! `bunny.off: line 12: vertex index 3490 out of range (3485 vertices)`.
//!
//! [`printable`] makes what a message quotes from the input one visible line: control
//! and invisible characters as escapes (`\x1b`, `\u{feff}`), and numbers of more than 24
//! digits in scientific notation (never a 300-digit number).

use std::fmt;
use std::path::Path;

/// What kind of problem an [`Error`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ErrorKind {
    /// The operating system refused to read or write a file.
    Io,
    /// The input holds no data at all.
    Empty,
    /// The file format could not be recognised from the name or the content.
    UnknownFormat,
    /// The data ends before what the header or the syntax promises.
    Truncated,
    /// A token or a header line is not what the format allows.
    Syntax,
    /// A face refers to a vertex that does not exist.
    IndexOutOfRange,
    /// A coordinate is NaN or infinite.
    NonFinite,
    /// Declared and actual counts disagree (or a count is impossible).
    CountMismatch,
    /// Valid in the format, but a feature this library does not read.
    Unsupported,
    /// A caller-supplied parameter is outside its allowed range or unknown.
    InvalidArgument,
    /// The mesh was read but is not what the method needs (e.g. open or non-manifold).
    InvalidMesh,
    /// The work would exceed a size budget (e.g. the volume mesh's tet count); the
    /// message names the figure and the option that lifts the budget.
    OverBudget,
    /// A failure that is not the input's: a dependency returned inconsistent output,
    /// an encoder failed on valid data. The CLI exits with status 1 and asks for a
    /// report.
    Internal,
}

/// Where in the input an error was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Location {
    /// 1-based line number (text formats).
    Line(usize),
    /// 0-based byte offset (binary formats).
    Byte(u64),
}

/// An error with its kind, its source (file name) and its location.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Error {
    kind: ErrorKind,
    source: Option<String>,
    location: Option<Location>,
    message: String,
}

/// `Result` with the library's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// A new error with a kind and a message, without source or location.
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        // Keep the one-line promise even if a message was built from input text, and
        // never pass a terminal escape from a file through to the user's terminal.
        let message = printable(&message.into());
        Error {
            kind,
            source: None,
            location: None,
            message,
        }
    }

    /// Shorthand for an [`ErrorKind::InvalidArgument`] error.
    pub fn invalid_argument(message: impl Into<String>) -> Self {
        Error::new(ErrorKind::InvalidArgument, message)
    }

    /// Attach a line number (1-based).
    pub fn at_line(mut self, line: usize) -> Self {
        self.location = Some(Location::Line(line));
        self
    }

    /// Attach a byte offset (0-based).
    pub fn at_byte(mut self, offset: u64) -> Self {
        self.location = Some(Location::Byte(offset));
        self
    }

    /// Attach the source name (usually the file path) unless one is already set.
    pub fn in_source(mut self, source: impl Into<String>) -> Self {
        if self.source.is_none() {
            self.source = Some(printable(&source.into()));
        }
        self
    }

    /// Attach a file path as source.
    pub fn in_file(self, path: &Path) -> Self {
        self.in_source(path.display().to_string())
    }

    /// What kind of problem this is.
    pub fn kind(&self) -> ErrorKind {
        self.kind
    }

    /// The file or source name, if known.
    pub fn source_name(&self) -> Option<&str> {
        self.source.as_deref()
    }

    /// The line or byte offset, if known.
    pub fn location(&self) -> Option<Location> {
        self.location
    }

    /// The message without source and location.
    pub fn message(&self) -> &str {
        &self.message
    }

    /// True for errors caused by what the caller gave: the input, the arguments, the
    /// files named (unreadable, unwritable) or a budget; false for an
    /// [`ErrorKind::Internal`] failure. The CLI exits with status 2 for the first, 1
    /// for the second.
    pub fn is_input_error(&self) -> bool {
        self.kind != ErrorKind::Internal
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(source) = &self.source {
            write!(f, "{source}: ")?;
        }
        match self.location {
            Some(Location::Line(line)) => write!(f, "line {line}: ")?,
            Some(Location::Byte(offset)) => write!(f, "byte {offset}: ")?,
            None => {}
        }
        f.write_str(&self.message)
    }
}

impl std::error::Error for Error {}

/// Numbers in messages longer than this many digits are rewritten in scientific notation.
/// (`{}` writes an `f64` with up to 17 significant digits, but writes 1e-300 or 1e300
/// out in full.)
const MAX_DIGITS: usize = 24;

/// `text` with numbers of more than [`MAX_DIGITS`] digits written in scientific
/// notation, so that no message holds a 300-digit number.
fn compact_numbers(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < bytes.len() {
        let start = i;
        while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
            i += 1;
        }
        if i == start {
            let c = text[i..].chars().next().unwrap_or(' ');
            out.push(c);
            i += c.len_utf8();
            continue;
        }
        let run = &text[start..i];
        let digits = run.bytes().filter(u8::is_ascii_digit).count();
        match run.parse::<f64>() {
            Ok(x) if digits > MAX_DIGITS => out.push_str(&format!("{x:.6e}")),
            _ => out.push_str(run),
        }
    }
    out
}

/// `text` with every character that is not printable written as an escape: control
/// characters (terminal escapes, line ends, tabs) as `\x1b`, and invisible format
/// characters (a byte-order mark, bidirectional overrides, zero-width spaces) as
/// `\u{feff}`, so that a message quoting input stays one visible line.
pub fn printable(text: &str) -> String {
    use std::fmt::Write as _;
    let invisible = |c: char| matches!(c, '\u{200b}'..='\u{200f}' | '\u{2028}'..='\u{202e}' | '\u{2060}'..='\u{206f}' | '\u{feff}');
    let text = compact_numbers(text);
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() && (c as u32) < 0x100 {
            let _ = write!(out, "\\x{:02x}", c as u32);
        } else if c.is_control() || invisible(c) {
            let _ = write!(out, "\\u{{{:x}}}", c as u32);
        } else {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_internal_failures_are_not_the_callers() {
        for kind in [ErrorKind::Io, ErrorKind::Syntax, ErrorKind::OverBudget] {
            assert!(Error::new(kind, "x").is_input_error(), "{kind:?}");
        }
        assert!(!Error::new(ErrorKind::Internal, "x").is_input_error());
    }

    #[test]
    fn display_is_one_line_with_source_and_location() {
        let e = Error::new(ErrorKind::Syntax, "bad\ntoken")
            .at_line(7)
            .in_source("a.obj");
        assert_eq!(e.to_string(), "a.obj: line 7: bad\\x0atoken");
        let e = Error::new(ErrorKind::Truncated, "ends early").at_byte(84);
        assert_eq!(e.to_string(), "byte 84: ends early");
    }

    #[test]
    fn escapes_and_invisible_characters_are_quoted() {
        let e = Error::new(
            ErrorKind::Syntax,
            "found '\u{1b}[2J\u{1b}]0;x\u{7}' \u{feff}v",
        );
        assert_eq!(e.to_string(), "found '\\x1b[2J\\x1b]0;x\\x07' \\u{feff}v");
        assert_eq!(printable("Genus 2, 1.5 mm, é"), "Genus 2, 1.5 mm, é");
        let tiny = format!("h = {} must be positive", 1e-300);
        assert_eq!(printable(&tiny), "h = 1.000000e-300 must be positive");
        let e = Error::invalid_argument(format!("h = {}, or {}", 1e300, 0.1 + 0.2));
        assert_eq!(e.to_string(), "h = 1.000000e300, or 0.30000000000000004");
    }
}
