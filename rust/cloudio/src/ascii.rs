//! ASCII point-cloud parser (parallel over line-aligned chunks) and writer.

use gagekit_core::{GkError, Result};
use rayon::prelude::*;

/// Options of [`parse_ascii`].
#[derive(Debug, Clone)]
pub struct AsciiOptions {
    /// Number of coordinates per point to return (2 or 3).
    pub dim: usize,
    /// Lines to skip unconditionally at the top (NIST `.ds`: the count line).
    pub skip_lines: usize,
}

impl Default for AsciiOptions {
    fn default() -> Self {
        Self { dim: 3, skip_lines: 0 }
    }
}

/// Result of [`parse_ascii`].
#[derive(Debug, Clone, PartialEq)]
pub struct Parsed {
    /// Row-major coordinates, `dim` per point.
    pub coords: Vec<f64>,
    /// Number of header lines recognised (after `skip_lines`).
    pub header_lines: usize,
    /// Columns (0-based) the coordinates were taken from.
    pub columns: Vec<usize>,
    /// Number of columns of the first data line.
    pub ncols: usize,
    /// Whether the file was read with a decimal comma ([`Style::DecimalComma`]).
    pub decimal_comma: bool,
}

/// How a file separates its values: the usual way (comma, semicolon, space, tab), or the
/// way of locales with a decimal comma (`1,5;2,5;3,5` as a spreadsheet writes it in
/// Germany or France, or `1,5 2,5 3,5`): then only semicolons and whitespace separate and
/// a comma is the decimal mark.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    Standard,
    DecimalComma,
}

fn is_sep(b: u8, style: Style) -> bool {
    match style {
        Style::Standard => matches!(b, b',' | b';' | b' ' | b'\t' | b'\r'),
        Style::DecimalComma => matches!(b, b';' | b' ' | b'\t' | b'\r'),
    }
}

fn is_hard(b: u8, style: Style) -> bool {
    match style {
        Style::Standard => matches!(b, b',' | b';'),
        Style::DecimalComma => b == b';',
    }
}

/// A token that reads as a number only with a decimal comma: digits, one comma, digits
/// (an optional sign and exponent), e.g. `-1,5` or `2,5e3`.
fn is_comma_decimal(t: &[u8]) -> bool {
    let t = t.strip_prefix(b"-").or_else(|| t.strip_prefix(b"+")).unwrap_or(t);
    let Some(c) = t.iter().position(|&b| b == b',') else { return false };
    let (int, frac) = (&t[..c], &t[c + 1..]);
    let frac_digits = frac.iter().take_while(|b| b.is_ascii_digit()).count();
    let rest = &frac[frac_digits..];
    !int.is_empty()
        && int.iter().all(u8::is_ascii_digit)
        && frac_digits > 0
        && (rest.is_empty()
            || (matches!(rest[0], b'e' | b'E') && rest.len() > 1 && {
                let e = rest[1..].strip_prefix(b"-").or_else(|| rest[1..].strip_prefix(b"+")).unwrap_or(&rest[1..]);
                !e.is_empty() && e.iter().all(u8::is_ascii_digit)
            }))
}

/// The separator style of a file, from its first line that starts like a number: a
/// semicolon with a decimal-comma number (`1,5;2,5`), or whitespace-separated tokens that
/// all are decimal-comma numbers (`1,5 2,5 3,5`), mean [`Style::DecimalComma`].
pub fn detect_style(line: &[u8]) -> Style {
    let t = trim(line);
    let tokens: Vec<&[u8]> = t
        .split(|&b| matches!(b, b';' | b' ' | b'\t' | b'\r'))
        .filter(|x| !x.is_empty())
        .collect();
    let any_comma_decimal = tokens.iter().any(|x| is_comma_decimal(x));
    if t.contains(&b';') && any_comma_decimal {
        return Style::DecimalComma;
    }
    if !t.contains(&b';')
        && tokens.len() >= 2
        && tokens.iter().all(|x| is_comma_decimal(x))
    {
        return Style::DecimalComma;
    }
    Style::Standard
}

/// The separator style of a file from its lines: [`detect_style`] of the first line that
/// starts like a number (not a comment or a header).
fn style_of<'a>(lines: impl Iterator<Item = &'a [u8]>) -> Style {
    lines
        .map(trim)
        .find(|l| !is_skipped(l) && matches!(l[0], b'0'..=b'9' | b'-' | b'+' | b'.'))
        .map_or(Style::Standard, detect_style)
}

/// Number of values on the first data line (every field a number) among the first
/// `max_lines` lines of a text file's beginning `head`, read as [`parse_ascii`] reads it
/// (byte-order mark, comments, separator style with decimal commas); 0 if there is none.
/// `1,5;2,5` has 2 values, `1,5,2` has 3.
pub fn data_columns(head: &[u8], max_lines: usize) -> usize {
    let head = head.strip_prefix(&[0xEF, 0xBB, 0xBF]).unwrap_or(head);
    let lines = || head.split(|&b| b == b'\n').take(max_lines);
    let style = style_of(lines());
    lines()
        .filter(|l| !is_skipped(l))
        .map(|l| fields(l, style))
        .find(|f| !f.is_empty() && f.iter().all(|x| parse_num(x, style).is_some()))
        .map_or(0, |f| f.len())
}

pub(crate) fn is_skipped(line: &[u8]) -> bool {
    let t = trim(line);
    t.is_empty() || t[0] == b'#' || t.starts_with(b"//")
}

pub(crate) fn trim(mut s: &[u8]) -> &[u8] {
    while let Some((&f, rest)) = s.split_first() {
        if f.is_ascii_whitespace() {
            s = rest;
        } else {
            break;
        }
    }
    while let Some((&l, rest)) = s.split_last() {
        if l.is_ascii_whitespace() {
            s = rest;
        } else {
            break;
        }
    }
    s
}

/// Split a line into fields: runs of separators count as one, except that
/// a comma or semicolon always separates (so `1,,2` has an empty field).
fn fields(line: &[u8], style: Style) -> Vec<&[u8]> {
    let line = trim(line);
    let mut out = Vec::new();
    let mut start = 0;
    let mut i = 0;
    while i < line.len() {
        if is_sep(line[i], style) {
            out.push(&line[start..i]);
            // swallow surrounding whitespace and at most one hard separator
            let mut hard = is_hard(line[i], style);
            i += 1;
            while i < line.len() && is_sep(line[i], style) {
                if is_hard(line[i], style) {
                    if hard {
                        out.push(&line[i..i]); // empty field between two hard separators
                    }
                    hard = true;
                }
                i += 1;
            }
            start = i;
        } else {
            i += 1;
        }
    }
    if start < line.len() || line.is_empty() {
        out.push(&line[start..]);
    }
    out
}

pub(crate) fn parse_f64(s: &[u8]) -> Option<f64> {
    fast_float2::parse::<f64, _>(s).ok()
}

/// A number in `style`: with [`Style::DecimalComma`] the comma is the decimal mark.
fn parse_num(s: &[u8], style: Style) -> Option<f64> {
    if style == Style::DecimalComma {
        if let Some(c) = s.iter().position(|&b| b == b',') {
            if s.len() > 64 || s[c + 1..].contains(&b',') {
                return None;
            }
            let mut buf = [0u8; 64];
            buf[..s.len()].copy_from_slice(s);
            buf[c] = b'.';
            return parse_f64(&buf[..s.len()]);
        }
    }
    parse_f64(s)
}

/// Column indices named x, y, z (case-insensitive, units in brackets allowed)
/// in a header line, if all the needed ones are present.
fn header_columns(line: &[u8], dim: usize, style: Style) -> Option<Vec<usize>> {
    let names: Vec<String> = fields(line, style)
        .iter()
        .map(|f| {
            let s = String::from_utf8_lossy(f).to_ascii_lowercase();
            let s = s.trim_matches(|c: char| c == '"' || c == '\'');
            s.split(|c: char| c == '(' || c == '[' || c == ' ').next().unwrap_or("").to_string()
        })
        .collect();
    ["x", "y", "z"][..dim]
        .iter()
        .map(|want| names.iter().position(|n| n == want))
        .collect()
}

/// Find `\n`-terminated lines. Returns the byte offsets of the line starts.
pub(crate) fn line_starts(bytes: &[u8]) -> Vec<usize> {
    let mut starts = vec![0];
    starts.extend(memchr::memchr_iter(b'\n', bytes).map(|i| i + 1).filter(|&i| i < bytes.len()));
    starts
}

pub(crate) fn line_at<'a>(bytes: &'a [u8], starts: &[usize], k: usize) -> &'a [u8] {
    let end = starts.get(k + 1).copied().unwrap_or(bytes.len());
    &bytes[starts[k]..end]
}

/// The text of `bytes`, after the checks of [`parse_ascii`]: `dim` is 2 or 3, the text
/// is not UTF-16 nor binary (no NUL byte); a UTF-8 byte-order mark is skipped.
fn checked_text<'a>(bytes: &'a [u8], dim: usize, what: &str) -> Result<&'a [u8]> {
    if !(2..=3).contains(&dim) {
        return Err(GkError::invalid(format!("{what}: dim must be 2 or 3, got {dim}")));
    }
    if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
        return Err(GkError::invalid(format!(
            "{what}: UTF-16 text (as Excel's \"Unicode Text\"); save it as CSV UTF-8 or plain ASCII"
        )));
    }
    let bytes = bytes.strip_prefix(&[0xEF, 0xBB, 0xBF]).unwrap_or(bytes);
    if memchr::memchr(0, bytes).is_some() {
        return Err(GkError::invalid(format!(
            "{what}: this is a binary file, not an ASCII point list (XYZ/CSV/TXT)"
        )));
    }
    Ok(bytes)
}

/// The lines of a text with its separator style, and the file's name for error messages.
struct Lines<'a> {
    bytes: &'a [u8],
    starts: Vec<usize>,
    nlines: usize,
    style: Style,
    what: &'a str,
}

impl<'a> Lines<'a> {
    /// Line `k` (0-based) with its line break.
    fn at(&self, k: usize) -> &'a [u8] {
        line_at(self.bytes, &self.starts, k)
    }
}

/// The lines before the first data line: the last header line, the number of header lines.
struct Preamble<'a> {
    header: Option<&'a [u8]>,
    header_lines: usize,
    /// Index of the first data line and its number of fields.
    first: usize,
    ncols: usize,
}

/// Header: leading non-skipped lines (from line `from`) whose first `dim` fields are not
/// all numbers (at most 50), up to the first data line.
fn preamble<'a>(lines: &Lines<'a>, from: usize, dim: usize) -> Result<Preamble<'a>> {
    let (style, what) = (lines.style, lines.what);
    let mut k = from;
    let mut header: Option<&[u8]> = None;
    let mut header_lines = 0;
    let mut first_data = None;
    while k < lines.nlines {
        let line = lines.at(k);
        if !is_skipped(line) {
            let f = fields(line, style);
            if f.len() >= dim && f[..dim].iter().all(|x| parse_num(x, style).is_some()) {
                first_data = Some((k, f.len()));
                break;
            }
            if header_lines >= 50 {
                return Err(GkError::invalid(format!(
                    "{what}: line {}: expected numbers (x y z), found {:?}",
                    k + 1,
                    String::from_utf8_lossy(trim(line))
                )));
            }
            header = Some(line);
            header_lines += 1;
        }
        k += 1;
    }
    let Some((first, ncols)) = first_data else {
        return Err(GkError::invalid(format!("{what}: no points found (the file is empty or has only header lines)")));
    };
    Ok(Preamble { header, header_lines, first, ncols })
}

/// The columns of the coordinates and the number of columns a data line needs: a header
/// with one name per data column may name the x, y, z columns, else the first `dim`.
fn coordinate_columns(lines: &Lines, pre: &Preamble, dim: usize) -> Result<(Vec<usize>, usize)> {
    let (style, what, ncols) = (lines.style, lines.what, pre.ncols);
    let columns = pre
        .header
        .filter(|h| fields(h, style).len() == ncols)
        .and_then(|h| header_columns(h, dim, style))
        .unwrap_or_else(|| (0..dim).collect());
    let need = columns.iter().max().copied().unwrap_or(0) + 1;
    if ncols < need {
        return Err(GkError::invalid(format!(
            "{what}: line {}: expected at least {need} columns, found {ncols}",
            pre.first + 1
        )));
    }
    Ok((columns, need))
}

/// The coordinates (`columns`, finite numbers) of the non-skipped lines `lo..hi`.
fn parse_lines(lines: &Lines, lo: usize, hi: usize, columns: &[usize], need: usize, dim: usize) -> Result<Vec<f64>> {
    let (style, what) = (lines.style, lines.what);
    let mut out = Vec::with_capacity((hi - lo) * dim);
    for k in lo..hi {
        let line = lines.at(k);
        if is_skipped(line) {
            continue;
        }
        let f = fields(line, style);
        for &c in columns {
            let v = f.get(c).and_then(|x| parse_num(x, style)).ok_or_else(|| {
                GkError::invalid(format!(
                    "{what}: line {}: expected {} numbers, found {:?}",
                    k + 1,
                    need,
                    String::from_utf8_lossy(trim(line))
                ))
            })?;
            if !v.is_finite() {
                return Err(GkError::invalid(format!(
                    "{what}: line {}: non-finite coordinate ({v}); remove NaN/inf values",
                    k + 1
                )));
            }
            out.push(v);
        }
    }
    Ok(out)
}

/// Parallel parse of lines `first..` in chunks ([`parse_lines`]), concatenated in order;
/// the error of the first failing chunk.
fn parse_data(lines: &Lines, first: usize, columns: &[usize], need: usize, dim: usize) -> Result<Vec<f64>> {
    let nlines = lines.nlines;
    let data_lines = nlines - first;
    let chunk = (data_lines / (rayon::current_num_threads() * 8)).clamp(4096, 1 << 20);
    let parts: Vec<Result<Vec<f64>>> = (first..nlines)
        .step_by(chunk)
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|lo| parse_lines(lines, lo, (lo + chunk).min(nlines), columns, need, dim))
        .collect();
    let mut coords = Vec::with_capacity(data_lines * dim);
    for p in parts {
        coords.extend(p?);
    }
    Ok(coords)
}

/// Parse an ASCII point cloud. `what` names the file in error messages.
///
/// A UTF-8 byte-order mark (as Excel writes "CSV UTF-8") is skipped; UTF-16 text is
/// refused with a hint. The separator style (decimal comma or not) is decided once from
/// the first line that starts like a number ([`detect_style`]).
pub fn parse_ascii(bytes: &[u8], opts: &AsciiOptions, what: &str) -> Result<Parsed> {
    let dim = opts.dim;
    let bytes = checked_text(bytes, dim, what)?;
    let starts = line_starts(bytes);
    let nlines = if bytes.is_empty() { 0 } else { starts.len() };
    let style = style_of((opts.skip_lines.min(nlines)..nlines).map(|k| line_at(bytes, &starts, k)));
    let lines = Lines { bytes, starts, nlines, style, what };
    let pre = preamble(&lines, opts.skip_lines.min(nlines), dim)?;
    let (columns, need) = coordinate_columns(&lines, &pre, dim)?;
    let coords = parse_data(&lines, pre.first, &columns, need, dim)?;
    let (header_lines, ncols) = (pre.header_lines, pre.ncols);
    Ok(Parsed { coords, header_lines, columns, ncols, decimal_comma: style == Style::DecimalComma })
}

/// Write points as ASCII, one per line, values separated by `sep`, with an
/// optional header line. Shortest round-trip representation (ryu).
pub fn write_ascii(coords: &[f64], dim: usize, sep: u8, header: Option<&str>) -> Result<Vec<u8>> {
    gagekit_core::check_finite(coords, dim, "points to write")?;
    let rows: Vec<Vec<u8>> = coords
        .par_chunks(dim * 65536)
        .map(|block| {
            let mut out = Vec::with_capacity(block.len() * 12);
            let mut buf = ryu::Buffer::new();
            for p in block.chunks_exact(dim) {
                for (i, v) in p.iter().enumerate() {
                    if i > 0 {
                        out.push(sep);
                    }
                    let s = buf.format_finite(*v);
                    out.extend_from_slice(s.strip_suffix(".0").unwrap_or(s).as_bytes());
                }
                out.push(b'\n');
            }
            out
        })
        .collect();
    let mut out = Vec::with_capacity(rows.iter().map(Vec::len).sum::<usize>() + 64);
    if let Some(h) = header {
        out.extend_from_slice(h.as_bytes());
        out.push(b'\n');
    }
    for r in rows {
        out.extend(r);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Parsed> {
        parse_ascii(s.as_bytes(), &AsciiOptions::default(), "t.xyz")
    }

    #[test]
    fn separators_and_extra_columns() {
        let p = parse("1 2 3\n4,5,6,7\n7\t8\t9 10 11\r\n\n# c\n1e3;-2.5;+3\n").unwrap();
        assert_eq!(p.coords, vec![1., 2., 3., 4., 5., 6., 7., 8., 9., 1e3, -2.5, 3.]);
        assert_eq!(p.header_lines, 0);
    }

    #[test]
    fn header_names_columns() {
        let p = parse("id,Z,Y,X\n1,3,2,1\n2,6,5,4\n").unwrap();
        assert_eq!(p.header_lines, 1);
        assert_eq!(p.columns, vec![3, 2, 1]);
        assert_eq!(p.coords, vec![1., 2., 3., 4., 5., 6.]);
        let q = parse("X[mm],Y[mm],Z[mm],intensity\n1,2,3,0.5\n").unwrap();
        assert_eq!(q.coords, vec![1., 2., 3.]);
        let r = parse("X (mm) Y (mm) Z (mm)\n1 2 3\n").unwrap();
        assert_eq!((r.header_lines, r.coords), (1, vec![1., 2., 3.]));
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse("1 2 3\n4 5\n").unwrap_err();
        assert!(e.message.contains("line 2"), "{}", e.message);
        let e = parse("1 2 3\n4 nan 6\n").unwrap_err();
        assert!(e.message.contains("line 2") && e.message.contains("non-finite"), "{}", e.message);
        let e = parse("1 2 x\n").unwrap_err();
        assert!(e.message.contains("no points"), "{}", e.message);
        assert!(parse("").is_err());
        assert!(parse("\n\n").is_err());
        assert!(parse_ascii(b"\x00\x01", &AsciiOptions::default(), "b").is_err());
    }

    #[test]
    fn skip_lines_for_nist_ds() {
        let opts = AsciiOptions { dim: 3, skip_lines: 1 };
        let p = parse_ascii(b"2\n1 2 3\n4 5 6", &opts, "a.ds").unwrap();
        assert_eq!(p.coords.len(), 6);
    }

    #[test]
    fn many_lines_parallel_roundtrip() {
        let n = 50_000;
        let coords: Vec<f64> = (0..3 * n).map(|i| (i as f64) * 0.001 - 17.25).collect();
        let text = write_ascii(&coords, 3, b' ', Some("x y z")).unwrap();
        let p = parse_ascii(&text, &AsciiOptions::default(), "big").unwrap();
        assert_eq!(p.coords, coords);
    }

    #[test]
    fn data_columns_reads_as_the_parser() {
        assert_eq!(data_columns(b"1,5;2,5\n3,5;4,5\n", 1000), 2);
        assert_eq!(data_columns(b"1,5 2,5\n", 1000), 2);
        assert_eq!(data_columns(b"1,5,2\n", 1000), 3);
        assert_eq!(data_columns(b"\xEF\xBB\xBF# c\nx;y\n1,5;2,5;3\n", 1000), 3);
        assert_eq!(data_columns(b"1 2 3 4\n", 1000), 4);
        assert_eq!(data_columns(b"x y\nfoo bar\n", 1000), 0);
        assert_eq!(data_columns(b"x y\n1 2\n", 1), 0);
    }

    #[test]
    fn decimal_comma_files() {
        // issue 12: `1,5;2,5;3,5` was read as (1, 5, 2)
        let p = parse("1,5;2,5;3,5\n-4,25;5;6,0e1\n").unwrap();
        assert_eq!(p.coords, vec![1.5, 2.5, 3.5, -4.25, 5., 60.]);
        assert!(p.decimal_comma);
        let q = parse("X;Y;Z\n1,5;2;3\n").unwrap();
        assert_eq!(q.coords, vec![1.5, 2., 3.]);
        let r = parse("1,5 2,5 3,5\n1,0\t2,0\t3,0\n").unwrap();
        assert_eq!(r.coords, vec![1.5, 2.5, 3.5, 1., 2., 3.]);
        // plain comma-separated files keep their meaning
        let s = parse("1,5,2\n1, 2, 3\n1;2;3\n").unwrap();
        assert_eq!(s.coords, vec![1., 5., 2., 1., 2., 3., 1., 2., 3.]);
        assert!(!s.decimal_comma);
        // a decimal-comma file whose later line has two commas in a field is an error
        assert!(parse("1,5;2,5;3,5\n1,2,3;4;5\n").is_err());
    }

    #[test]
    fn byte_order_marks() {
        let p = parse_ascii(b"\xEF\xBB\xBFx,y,z\n1,2,3\n", &AsciiOptions::default(), "bom.csv").unwrap();
        assert_eq!((p.header_lines, p.coords), (1, vec![1., 2., 3.]));
        let e = parse_ascii(b"\xFF\xFEx\x00", &AsciiOptions::default(), "u16.csv").unwrap_err();
        assert!(e.message.contains("UTF-16"), "{}", e.message);
    }

    #[test]
    fn two_d() {
        let opts = AsciiOptions { dim: 2, skip_lines: 0 };
        let p = parse_ascii(b"1 2\n3 4\n", &opts, "c").unwrap();
        assert_eq!(p.coords, vec![1., 2., 3., 4.]);
    }
}
