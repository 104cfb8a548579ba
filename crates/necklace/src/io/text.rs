//! Helpers shared by the readers: numbered lines and tokens of text formats (OBJ, OFF,
//! ascii PLY, ascii STL), number parsing whose errors name the line, and the triangulation
//! of polygons into triangles.
//!
//! Everything works on bytes: a line ends at `\n`, `\r\n` or a lone `\r` (old Mac files),
//! tokens are separated by ASCII whitespace (spaces, tabs), and a token that is not
//! UTF-8 or not a number is a [`ErrorKind::Syntax`] error, never a panic.

use crate::error::{Error, ErrorKind, Result};

/// The lines of `data` with their 1-based numbers, without their `\n`, `\r\n` or `\r`
/// ending.
pub(crate) fn raw_lines(data: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    let mut rest = data;
    let mut number = 0;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        number += 1;
        let (line, next) = match rest.iter().position(|&b| b == b'\n' || b == b'\r') {
            Some(i) if rest[i] == b'\r' && rest.get(i + 1) == Some(&b'\n') => (&rest[..i], i + 2),
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        rest = &rest[next..];
        Some((number, line))
    })
}

/// The number of the last line of `data` (0 for no data): where "file ends early"
/// errors point.
pub(crate) fn last_line(data: &[u8]) -> usize {
    raw_lines(data).count()
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

/// A token quoted for a message, shortened if long; bytes that are not printable text
/// (control characters such as a terminal escape, invalid UTF-8) are written as `\x1b`.
pub(crate) fn shown(token: &[u8]) -> String {
    const MAX: usize = 24;
    let text = crate::error::printable(&String::from_utf8_lossy(token));
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

/// Append a triangulation of a polygon, in time linear in its corners. A triangle or
/// quad is split as a fan from its first corner, (v0, v1, v2), (v0, v2, v3), as every
/// tool does. A larger polygon is split by halving: the triangle (v0, vm, vn) on the
/// middle corner, then each half's arc the same way, so that no corner gets more than
/// about 2 log2(n) triangles. (A fan of an n-gon puts n − 2 slivers on one corner,
/// which makes spatial queries round that corner quadratic.) For a convex polygon both
/// are valid triangulations.
pub(crate) fn triangulate(polygon: &[u32], triangles: &mut Vec<[u32; 3]>) {
    if polygon.len() <= 4 {
        if let Some((&first, rest)) = polygon.split_first() {
            triangles.extend(rest.windows(2).map(|pair| [first, pair[0], pair[1]]));
        }
        return;
    }
    // The polygon is cut into the triangle on corners 0, m, n-1 plus the two arcs
    // 0..=m and m..=n-1, closed by their chords; arcs are split at their middle in
    // turn (an explicit stack: no recursion depth to worry about).
    let n = polygon.len();
    let mut arcs = vec![(0usize, n - 1)];
    while let Some((a, b)) = arcs.pop() {
        if b - a < 2 {
            continue;
        }
        let m = a + (b - a) / 2;
        triangles.push([polygon[a], polygon[m], polygon[b]]);
        arcs.push((m, b));
        arcs.push((a, m));
    }
}

/// The error for a polygon with fewer than 3 corners.
pub(crate) fn too_few_corners(what: &str, corners: impl std::fmt::Display) -> Error {
    Error::new(
        ErrorKind::Syntax,
        format!("{what} has {corners} vertices, at least 3 needed"),
    )
}
