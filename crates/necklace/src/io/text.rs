//! Helpers shared by the readers: numbered lines and tokens of text formats (OBJ, OFF,
//! ascii PLY, ascii STL), number parsing whose errors name the line, and the fan split
//! of polygons into triangles.
//!
//! Everything works on bytes: a line is split at `\n` with one trailing `\r` dropped,
//! tokens are separated by ASCII whitespace (spaces, tabs), and a token that is not
//! UTF-8 or not a number is a [`ErrorKind::Syntax`] error, never a panic.

use crate::error::{Error, ErrorKind, Result};

/// The lines of `data` with their 1-based numbers, without the `\n` or `\r\n` ending.
pub(crate) fn raw_lines(data: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    data.split_inclusive(|&b| b == b'\n')
        .enumerate()
        .map(|(i, line)| {
            let line = line.strip_suffix(b"\n").unwrap_or(line);
            (i + 1, line.strip_suffix(b"\r").unwrap_or(line))
        })
}

/// The number of the last line of `data` (0 for no data): where "file ends early"
/// errors point.
pub(crate) fn last_line(data: &[u8]) -> usize {
    data.split_inclusive(|&b| b == b'\n').count()
}

/// Cut a `#` comment off a line.
pub(crate) fn strip_comment(line: &[u8]) -> &[u8] {
    match line.iter().position(|&b| b == b'#') {
        Some(i) => &line[..i],
        None => line,
    }
}

/// Numbered lines with `#` comments cut off and surrounding whitespace trimmed; blank
/// lines (and comment-only lines) are skipped.
pub(crate) fn content_lines(data: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    raw_lines(data).filter_map(|(number, line)| {
        let line = strip_comment(line).trim_ascii();
        (!line.is_empty()).then_some((number, line))
    })
}

/// The whitespace-separated tokens of a line.
pub(crate) fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(u8::is_ascii_whitespace)
        .filter(|token| !token.is_empty())
}

/// A token quoted for a message, shortened if long.
pub(crate) fn shown(token: &[u8]) -> String {
    const MAX: usize = 24;
    let text = String::from_utf8_lossy(token);
    if text.chars().count() > MAX {
        let short: String = text.chars().take(MAX).collect();
        format!("'{short}...'")
    } else {
        format!("'{text}'")
    }
}

/// Parse a number (any value, NaN and infinities included).
pub(crate) fn parse_number(token: &[u8], line: usize) -> Result<f64> {
    std::str::from_utf8(token)
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
        .ok_or_else(|| {
            Error::new(
                ErrorKind::Syntax,
                format!("expected a number, found {}", shown(token)),
            )
            .at_line(line)
        })
}

/// The first three tokens as a finite position; extra tokens are left unread.
pub(crate) fn parse_position<'a>(
    mut tokens: impl Iterator<Item = &'a [u8]>,
    line: usize,
) -> Result<[f64; 3]> {
    let mut position = [0.0; 3];
    for (found, coordinate) in position.iter_mut().enumerate() {
        let token = tokens.next().ok_or_else(|| {
            Error::new(
                ErrorKind::Syntax,
                format!("vertex has {found} coordinates, expected 3"),
            )
            .at_line(line)
        })?;
        *coordinate = parse_coordinate(token, line)?;
    }
    Ok(position)
}

/// Parse a coordinate: a number that must be finite.
pub(crate) fn parse_coordinate(token: &[u8], line: usize) -> Result<f64> {
    let value = parse_number(token, line)?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::new(
            ErrorKind::NonFinite,
            format!("non-finite coordinate {}", shown(token)),
        )
        .at_line(line))
    }
}

/// Parse an integer; `what` names it in the error message ("vertex index", ...).
pub(crate) fn parse_int(token: &[u8], what: &str, line: usize) -> Result<i64> {
    std::str::from_utf8(token)
        .ok()
        .and_then(|s| s.parse::<i64>().ok())
        .ok_or_else(|| {
            Error::new(
                ErrorKind::Syntax,
                format!("expected an integer {what}, found {}", shown(token)),
            )
            .at_line(line)
        })
}

/// Append the fan triangulation (v0, v1, v2), (v0, v2, v3), ... of a polygon.
pub(crate) fn fan_split(polygon: &[u32], triangles: &mut Vec<[u32; 3]>) {
    if let Some((&first, rest)) = polygon.split_first() {
        triangles.extend(rest.windows(2).map(|pair| [first, pair[0], pair[1]]));
    }
}

/// The error for a polygon with fewer than 3 corners.
pub(crate) fn too_few_corners(what: &str, corners: impl std::fmt::Display) -> Error {
    Error::new(
        ErrorKind::Syntax,
        format!("{what} has {corners} vertices, at least 3 needed"),
    )
}
