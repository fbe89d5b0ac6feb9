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
    let bytes = checked_top(bytes, dim, what)?;
    check_no_nul(bytes, what)?;
    Ok(bytes)
}

/// [`checked_text`] but for the NUL bytes, which the caller then looks for.
fn checked_top<'a>(bytes: &'a [u8], dim: usize, what: &str) -> Result<&'a [u8]> {
    check_dim(dim, what)?;
    if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
        return Err(GkError::file_format(format!(
            "{what}: UTF-16 text (as Excel's \"Unicode Text\"); save it as CSV UTF-8 or plain ASCII"
        )));
    }
    Ok(bytes.strip_prefix(&[0xEF, 0xBB, 0xBF]).unwrap_or(bytes))
}

fn check_dim(dim: usize, what: &str) -> Result<()> {
    if !(2..=3).contains(&dim) {
        return Err(GkError::invalid(format!("{what}: dim must be 2 or 3, got {dim}")));
    }
    Ok(())
}

/// A NUL byte means a binary file, not a point list.
pub(crate) fn check_no_nul(bytes: &[u8], what: &str) -> Result<()> {
    if bytes.par_chunks(1 << 22).any(|c| memchr::memchr(0, c).is_some()) {
        return Err(GkError::file_format(format!(
            "{what}: this is a binary file, not an ASCII point list (XYZ/CSV/TXT)"
        )));
    }
    Ok(())
}

/// The lines of `bytes` from byte `pos` (a line start) and line index `k`: (index, start
/// offset, line with its line break), in order, without any table of line starts.
fn lines_from(bytes: &[u8], mut pos: usize, mut k: usize) -> impl Iterator<Item = (usize, usize, &[u8])> {
    std::iter::from_fn(move || {
        if pos >= bytes.len() {
            return None;
        }
        let end = memchr::memchr(b'\n', &bytes[pos..]).map_or(bytes.len(), |i| pos + i + 1);
        let item = (k, pos, &bytes[pos..end]);
        pos = end;
        k += 1;
        Some(item)
    })
}

/// How the data lines of a file are read: separator style, the coordinate columns, the
/// number of fields a data line needs, and the file's name for messages. Decided once
/// from the top of the file ([`ascii_layout`]).
#[derive(Debug, Clone)]
pub struct Layout {
    pub style: Style,
    pub columns: Vec<usize>,
    pub need: usize,
    pub dim: usize,
    /// For each field index below `need`, the coordinate it holds (`usize::MAX`: none).
    slot: Vec<usize>,
    /// Header lines recognised (after `skip_lines`), and the number of fields of the first data line.
    pub header_lines: usize,
    pub ncols: usize,
}

/// Where the data of a text begins: its [`Layout`], the byte offset of the first data
/// line, and that line's 0-based index (counting the skipped and header lines).
#[derive(Debug, Clone)]
pub struct DataStart {
    pub layout: Layout,
    pub offset: usize,
    pub line: usize,
}

/// Header: leading non-skipped lines (after `skip_lines`) whose first `dim` fields are not
/// all numbers (at most 50), up to the first data line; then the coordinate columns (a
/// header with one name per data column may name the x, y, z columns, else the first
/// `dim`). `bytes` is the checked text ([`checked_text`]); only its top is read.
fn data_start(bytes: &[u8], opts: &AsciiOptions, what: &str) -> Result<DataStart> {
    let dim = opts.dim;
    let skipped = lines_from(bytes, 0, 0).take(opts.skip_lines).last();
    let from = skipped.map_or(0, |(_, s, l)| s + l.len());
    let k0 = skipped.map_or(0, |(k, _, _)| k + 1);
    let style = style_of(lines_from(bytes, from, k0).map(|(_, _, l)| l));
    let mut header: Option<&[u8]> = None;
    let mut header_lines = 0;
    let mut first_data = None;
    for (k, start, line) in lines_from(bytes, from, k0) {
        if is_skipped(line) {
            continue;
        }
        let f = fields(line, style);
        if f.len() >= dim && f[..dim].iter().all(|x| parse_num(x, style).is_some()) {
            first_data = Some((k, start, f.len()));
            break;
        }
        if header_lines >= 50 {
            return Err(GkError::file_format(format!(
                "{what}: line {}: expected numbers (x y z), found {:?}",
                k + 1,
                String::from_utf8_lossy(trim(line))
            )));
        }
        header = Some(line);
        header_lines += 1;
    }
    let Some((first, offset, ncols)) = first_data else {
        return Err(GkError::file_format(format!("{what}: no points found (the file is empty or has only header lines)")));
    };
    let columns = header
        .filter(|h| fields(h, style).len() == ncols)
        .and_then(|h| header_columns(h, dim, style))
        .unwrap_or_else(|| (0..dim).collect());
    let need = columns.iter().max().copied().unwrap_or(0) + 1;
    if ncols < need {
        return Err(GkError::file_format(format!(
            "{what}: line {}: expected at least {need} columns, found {ncols}",
            first + 1
        )));
    }
    let mut slot = vec![usize::MAX; need];
    for (a, &c) in columns.iter().enumerate() {
        if slot[c] == usize::MAX {
            slot[c] = a;
        }
    }
    let layout = Layout { style, columns, need, dim, slot, header_lines, ncols };
    Ok(DataStart { layout, offset, line: first })
}

/// [`data_start`] of the raw bytes of a file's top (the checks of [`parse_ascii`] first);
/// the offset counts the byte-order mark, so it indexes `head` itself.
pub fn ascii_layout(head: &[u8], opts: &AsciiOptions, what: &str) -> Result<DataStart> {
    let text = checked_text(head, opts.dim, what)?;
    let mut d = data_start(text, opts, what)?;
    d.offset += head.len() - text.len();
    Ok(d)
}

/// The coordinates of one data line by the rules of [`fields`] (the reference path:
/// every line the fast path declines comes here, so messages and values are the
/// reader's own). `Ok(false)`: a skipped line (blank, comment). `k` is the 0-based index.
fn slow_line(line: &[u8], lay: &Layout, k: usize, what: &str, out: &mut [f64]) -> Result<bool> {
    if is_skipped(line) {
        return Ok(false);
    }
    let style = lay.style;
    let f = fields(line, style);
    for (a, &c) in lay.columns.iter().enumerate() {
        let v = f.get(c).and_then(|x| parse_num(x, style)).ok_or_else(|| {
            GkError::file_format(format!(
                "{what}: line {}: expected {} numbers, found {:?}",
                k + 1,
                lay.need,
                String::from_utf8_lossy(trim(line))
            ))
        })?;
        if !v.is_finite() {
            return Err(GkError::file_format(format!(
                "{what}: line {}: non-finite coordinate ({v}); remove NaN/inf values",
                k + 1
            )));
        }
        out[a] = v;
    }
    Ok(true)
}

/// The usual data line, read in one pass with no field list, from byte `i` of `block` (a
/// line start) on: fields `0..need` separated by one separator run holding at most one
/// comma or semicolon, each wanted field a finite number (read in place by
/// [`parse_number`]: the token is exactly the bytes it consumes, as the next byte is a
/// separator or the line's end). Returns whether the line holds a point (`false`: a blank
/// or comment line) and the index of its line break (`block.len()` for a last line
/// without one); `None`: anything else (an error, a decimal comma, an empty field,
/// unusual whitespace), which [`slow_line`] then reads.
#[inline]
fn fast_line(block: &[u8], mut i: usize, lay: &Layout, out: &mut [f64]) -> Option<(bool, usize)> {
    let n = block.len();
    let eol = |from: usize| memchr::memchr(b'\n', &block[from..]).map_or(n, |j| from + j);
    while i < n && block[i] != b'\n' && block[i].is_ascii_whitespace() {
        i += 1;
    }
    if i == n || block[i] == b'\n' {
        return Some((false, i));
    }
    if block[i] == b'#' || (block[i] == b'/' && block.get(i + 1) == Some(&b'/')) {
        return Some((false, eol(i)));
    }
    let style = lay.style;
    for (f, &a) in lay.slot.iter().enumerate() {
        if a != usize::MAX {
            let (v, len) = parse_number(block, i)?;
            if !v.is_finite() {
                return None;
            }
            out[a] = v;
            i += len;
        } else {
            let start = i;
            while i < n && block[i] != b'\n' && !is_sep(block[i], style) {
                i += 1;
            }
            if i == start {
                return None;
            }
        }
        if f + 1 == lay.need {
            // the rest (further fields, trailing whitespace) is not read
            if i == n || block[i] == b'\n' {
                return Some((true, i));
            }
            let e = eol(i);
            return (is_sep(block[i], style) || block[i..e].iter().all(u8::is_ascii_whitespace)).then_some((true, e));
        }
        let mut hard = 0;
        let run = i;
        while i < n && is_sep(block[i], style) {
            hard += usize::from(is_hard(block[i], style));
            i += 1;
        }
        if i == run || hard > 1 || i == n || block[i].is_ascii_whitespace() {
            return None;
        }
    }
    Some((true, eol(i)))
}

/// Powers of ten exactly representable as f64.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20,
    1e21, 1e22,
];

/// 10^k as an integer, k <= 8.
const POW10_U64: [u64; 9] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000, 10_000_000, 100_000_000];

/// The 8 bytes of `s` from `i` as a little-endian word (`s[i..i + 8]` must exist).
#[inline(always)]
fn word(s: &[u8], i: usize) -> u64 {
    u64::from_le_bytes(s[i..i + 8].try_into().unwrap())
}

/// The run of ASCII digits at the start of the 8 bytes `w` (first byte lowest): its
/// length (0..=8) and its value. SWAR: a byte is a digit when its high nibble is 3 both
/// before and after adding 6 (no carry crosses into a byte before the first non-digit,
/// as every byte below it is a digit, < 0x3A); the digits are shifted to the top of
/// the word (zeros before them are leading zeros) and combined pairwise, then by fours
/// (two multiplications, as in simdjson / fast_float's eight-digit step).
#[inline(always)]
fn digit_run(w: u64) -> (usize, u64) {
    const HI: u64 = 0xF0F0_F0F0_F0F0_F0F0;
    const THREES: u64 = 0x3030_3030_3030_3030;
    let bad = ((w & HI) ^ THREES) | ((w.wrapping_add(0x0606_0606_0606_0606) & HI) ^ THREES);
    let len = (bad.trailing_zeros() / 8) as usize;
    if len == 0 {
        return (0, 0);
    }
    (len, digits_value(w, len))
}

/// The value of the first `len` (1..=8) bytes of `w` (first byte lowest), all ASCII
/// digits: they are shifted to the top of the word (the bytes after them drop out; zeros
/// before them are leading zeros) and combined pairwise, then by fours.
#[inline(always)]
fn digits_value(w: u64, len: usize) -> u64 {
    const THREES: u64 = 0x3030_3030_3030_3030;
    combine_digits(w.wrapping_sub(THREES) << (8 * (8 - len)))
}

/// The value of the 8 digit values (0..=9) in the bytes of `v`, the first the lowest byte:
/// combined pairwise, then by fours (two multiplications, as in simdjson / fast_float).
#[inline(always)]
fn combine_digits(v: u64) -> u64 {
    let v = v.wrapping_mul(10).wrapping_add(v >> 8);
    ((v & 0x0000_00FF_0000_00FF).wrapping_mul(0x000F_4240_0000_0064)
        .wrapping_add(((v >> 16) & 0x0000_00FF_0000_00FF).wrapping_mul(0x0000_2710_0000_0001)))
        >> 32
}

/// The digits of `s` from `i` on, eight at a time while eight bytes remain (the caller
/// ensures `i + 8 <= s.len()` at the first step; afterwards the byte loop): (index after
/// the digits, the value modulo 2^64, which is exact below 16 digits, number of digits).
#[inline(always)]
fn digits(s: &[u8], mut i: usize, mut m: u64) -> (usize, u64, usize) {
    let start = i;
    loop {
        if i + 8 > s.len() {
            while i < s.len() && s[i].is_ascii_digit() {
                m = m.wrapping_mul(10).wrapping_add(u64::from(s[i] - b'0'));
                i += 1;
            }
            return (i, m, i - start);
        }
        let (len, v) = digit_run(word(s, i));
        m = m.wrapping_mul(POW10_U64[len]).wrapping_add(v);
        i += len;
        if len < 8 {
            return (i, m, i - start);
        }
    }
}

/// The number at byte `at` of `s` and the bytes it takes, as `fast_float2::parse_partial`
/// reads `&s[at..]`. Plain decimals (`-123.4567`: a sign, digits, a point and digits, no
/// exponent, at most 15 digits) are read here, the digits eight at a time
/// ([`digit_run`]): they are an integer m < 2^53 and the value m / 10^k with k <= 22,
/// both exact in binary, so the one correctly rounded division is the correctly rounded
/// value of the decimal (Clinger's fast path, which fast-float2 takes for them too): the
/// same bits. Anything else goes to fast-float2.
#[inline]
fn parse_number(s: &[u8], at: usize) -> Option<(f64, usize)> {
    if at + 32 <= s.len() {
        if let Some(r) = short_decimal(&s[at..at + 32]) {
            return Some(r);
        }
    }
    let n = s.len();
    let mut i = at;
    let neg = match s.get(i) {
        Some(b'-') => {
            i += 1;
            true
        }
        Some(b'+') => {
            i += 1;
            false
        }
        _ => false,
    };
    let (e, m, int_digits) = digits(s, i, 0);
    i = e;
    let mut k = 0;
    let mut point_ok = true;
    let mut m = m;
    if i < n && s[i] == b'.' {
        let (e, m2, frac) = digits(s, i + 1, m);
        (i, m, k) = (e, m2, frac);
        point_ok = k > 0;
    }
    if int_digits > 0 && point_ok && int_digits + k <= 15 && (i == n || !matches!(s[i], b'e' | b'E' | b'.')) {
        // m < 10^15 < 2^63: the signed conversion (one instruction) is exact
        let v = (m as i64) as f64 / POW10[k];
        return Some((if neg { -v } else { v }, i - at));
    }
    fast_float2::parse_partial::<f64, _>(&s[at..]).ok()
}

/// [`parse_number`] of the usual short decimal at the start of `s` (32 bytes): an
/// optional sign, 1 to 7 integer digits, optionally a point and 1 to 7 decimals, then a
/// byte that is neither a digit, a point nor an exponent. Straight-line code: one 8-byte
/// digit run ([`digit_run`]) for each part, no loop and no bounds check (the 32 bytes
/// cover the longest such token and the byte after it). The value is the same correctly
/// rounded division m / 10^k as in [`parse_number`] (m < 10^14, k <= 7), so the same bits;
/// `None` for anything else, which [`parse_number`] then reads.
#[inline(always)]
fn short_decimal(s: &[u8]) -> Option<(f64, usize)> {
    let s: &[u8; 32] = s.try_into().ok()?;
    let c0 = s[0];
    let neg = u64::from(c0 == b'-');
    // no branch on the sign (half the z values of a scan are negative: a branch on it
    // is mispredicted half the time)
    let j = (neg | u64::from(c0 == b'+')) as usize;
    let (l1, v1) = digit_run(u64::from_le_bytes(s[j..j + 8].try_into().ok()?));
    if l1.wrapping_sub(1) >= 7 {
        return None; // no digit, or 8 or more
    }
    let mut end = j + l1;
    let (mut m, mut k) = (v1, 0);
    if s[end] == b'.' {
        let (l2, v2) = digit_run(u64::from_le_bytes(s[end + 1..end + 9].try_into().ok()?));
        if l2.wrapping_sub(1) >= 7 {
            return None;
        }
        m = v1 * POW10_U64[l2] + v2;
        k = l2;
        end += 1 + l2;
    }
    let t = s[end & 31];
    if t | 0x20 == b'e' || t == b'.' {
        return None;
    }
    // m < 10^14 < 2^53: exact in binary, as is 10^k
    let v = (m as i64) as f64 / POW10[k];
    Some((f64::from_bits(v.to_bits() | neg << 63), end))
}

/// Bit masks of the 64 bytes of a window (bit `j` for byte `j`): line breaks (`\n`),
/// separators (space, tab, comma, semicolon), points, minus signs and ASCII digits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Masks {
    nl: u64,
    sep: u64,
    dot: u64,
    minus: u64,
    digit: u64,
}

/// The [`Masks`] of the 64 bytes at `$ptr`, `$lanes` loads of one vector width: the
/// intrinsics of that width (`$set`: broadcast, `$load`: unaligned load, `$eq`, `$or`,
/// `$sub`, `$min`: per byte, `$movemask`: one bit a byte, read as `$bits` bits).
#[cfg(target_arch = "x86_64")]
macro_rules! simd_masks {
    ($ptr:expr, $vec:ty, $lanes:literal, $bits:ty, $set:ident, $load:ident, $eq:ident, $or:ident, $sub:ident, $min:ident, $movemask:ident) => {{
        let mut m = Masks { nl: 0, sep: 0, dot: 0, minus: 0, digit: 0 };
        let set = |b: u8| $set(b as i8);
        let (nl, sp, tab, comma, semi, dot, minus, zero, nine) =
            (set(b'\n'), set(b' '), set(b'\t'), set(b','), set(b';'), set(b'.'), set(b'-'), set(b'0'), set(9));
        let width = 64 / $lanes;
        let bits = |v: $vec, q: usize| u64::from($movemask(v) as $bits) << (width * q);
        for q in 0..$lanes {
            let v = $load($ptr.add(width * q) as *const $vec);
            let s = $or($or($eq(v, sp), $eq(v, tab)), $or($eq(v, comma), $eq(v, semi)));
            // a digit: b - '0' (wrapping) is at most 9 unsigned
            let d = $sub(v, zero);
            m.nl |= bits($eq(v, nl), q);
            m.sep |= bits(s, q);
            m.dot |= bits($eq(v, dot), q);
            m.minus |= bits($eq(v, minus), q);
            m.digit |= bits($eq($min(d, nine), d), q);
        }
        m
    }};
}

/// The [`Masks`] of the 64 bytes `w`. SSE2 (every x86-64) compares 16 bytes at a time,
/// AVX2 32; other targets take the byte loop, which gives the same masks.
///
/// # Safety
/// With `AVX2`, the processor must have AVX2.
#[inline(always)]
unsafe fn window_masks<const AVX2: bool>(w: &[u8; 64]) -> Masks {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        if AVX2 {
            // SAFETY: AVX2 is there (the caller's promise); the two unaligned 32-byte loads
            // stay inside the 64 bytes of `w`.
            return unsafe {
                simd_masks!(w.as_ptr(), __m256i, 2, u32, _mm256_set1_epi8, _mm256_loadu_si256, _mm256_cmpeq_epi8, _mm256_or_si256, _mm256_sub_epi8, _mm256_min_epu8, _mm256_movemask_epi8)
            };
        }
        // SAFETY: SSE2 is part of the x86-64 baseline; the four unaligned 16-byte loads
        // stay inside the 64 bytes of `w`.
        unsafe { simd_masks!(w.as_ptr(), __m128i, 4, u16, _mm_set1_epi8, _mm_loadu_si128, _mm_cmpeq_epi8, _mm_or_si128, _mm_sub_epi8, _mm_min_epu8, _mm_movemask_epi8) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        window_masks_bytes(w)
    }
}

/// [`window_masks`] byte by byte (the other targets' route, and its test oracle).
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
fn window_masks_bytes(w: &[u8; 64]) -> Masks {
    let mut m = Masks { nl: 0, sep: 0, dot: 0, minus: 0, digit: 0 };
    for (j, &b) in w.iter().enumerate() {
        m.nl |= u64::from(b == b'\n') << j;
        m.sep |= u64::from(matches!(b, b' ' | b'\t' | b',' | b';')) << j;
        m.dot |= u64::from(b == b'.') << j;
        m.minus |= u64::from(b == b'-') << j;
        m.digit |= u64::from(b.is_ascii_digit()) << j;
    }
    m
}

/// The value of the field at bytes `from..to` (< 64) of the line at `p` of `block`,
/// whose masks (shifted to the line's start, cut at its end) are `minus` and `dot`, and
/// which [`plain_lines`] has checked to be `-?D+(.D+)?` (`D` an ASCII digit, at most one
/// point is checked here): [`point_decimal`] of it; `None` if it has two points.
#[inline(always)]
fn masked_decimal(block: &[u8], p: usize, from: usize, to: usize, minus: u64, dot: u64) -> Option<f64> {
    let d = dot & ((1u64 << to) - 1) & !((1u64 << from) - 1);
    if d & d.wrapping_sub(1) != 0 {
        return None;
    }
    let dp = if d == 0 { to } else { d.trailing_zeros() as usize };
    point_decimal(block, p, from, dp, to, (minus >> from) & 1)
}

/// The value of the field at bytes `from..to` (< 64) of the line at `p` of `block`, a
/// minus sign first if `neg` (0 or 1), its point at `dp` (`to`: none), checked by
/// [`plain_lines`] to be `-?D+(.D+)?` (`D` an ASCII digit): `None` if it has more than 8
/// integer digits, 8 decimals or 15 digits in all. The digits are an integer
/// m < 10^15 < 2^53 and the value is m / 10^k, k <= 8, both exact in binary, so the one
/// correctly rounded division is the correctly rounded value of the decimal (Clinger's
/// fast path, as in [`parse_number`]): the same bits as fast-float2 and `str::parse`.
/// 8 bytes from each digit run's start must exist.
#[inline(always)]
fn point_decimal(block: &[u8], p: usize, from: usize, dp: usize, to: usize, neg: u64) -> Option<f64> {
    let i0 = from + neg as usize;
    let nint = dp - i0;
    let len = to - i0;
    let nfrac = len - nint - usize::from(dp < to);
    let m = if dp < to && len <= 8 {
        // the digits and the point in one word: the digits before the point moved up one
        // byte over it, so that the first len bytes are a zero and the digits in order
        let w = word(block, p + i0) & 0x0F0F_0F0F_0F0F_0F0F;
        let before = w & ((1u64 << (8 * nint)) - 1);
        let after = w & !((1u64 << (8 * nint + 8)) - 1);
        combine_digits(((before << 8) | after) << (8 * (8 - len)))
    } else {
        if nint > 8 || nfrac > 8 || nint + nfrac > 15 {
            return None;
        }
        let m = digits_value(word(block, p + i0), nint);
        if nfrac > 0 {
            m * POW10_U64[nfrac] + digits_value(word(block, p + dp + 1), nfrac)
        } else {
            m
        }
    };
    // m < 10^15 < 2^63: the signed conversion (one instruction) is exact
    let v = (m as i64) as f64 / POW10[nfrac];
    Some(f64::from_bits(v.to_bits() | neg << 63))
}

/// The most common data lines, read with the least work, from byte `pos` of `block` (a
/// line start) on, as many as follow one another: a line of `dim` (2 or 3) plain
/// decimals (`-?D+(.D+)?`, at most 8 integer digits, 8 decimals and 15 digits: see
/// [`masked_decimal`]), one separator byte (space, tab, comma or semicolon) between them,
/// and the line break (`\n` or `\r\n`) right after the last. The lines are checked and
/// split 64 bytes at a time, with bit operations on the masks of the bytes
/// ([`window_masks`]): no byte-by-byte scan, and where a line and its fields start does
/// not wait on reading the numbers before them. Every token read is a field of
/// [`fields`] (single separators, nothing else on the line) and its value is
/// [`parse_number`]'s. Writes the points from point `*w` of `out` on and counts them in
/// `*w`; returns the start of the first line not read (any other line: leading blanks, a
/// comment, a sign `+`, more columns, a long number, a line of 64 bytes or more...),
/// which [`fast_line`] then reads, or of a line less than 96 bytes from the end of
/// `block` (a window and the 8 bytes read from a digit run's start must lie inside it).
///
/// # Safety
/// With `AVX2`, the processor must have AVX2.
#[inline(always)]
unsafe fn plain_lines<const AVX2: bool>(block: &[u8], mut pos: usize, dim: usize, out: &mut [f64], w: &mut usize) -> usize {
    while pos + 96 <= block.len() {
        // SAFETY: passed on from the caller
        let m = unsafe { window_masks::<AVX2>(block[pos..pos + 64].try_into().unwrap()) };
        let mut base = 0;
        while base < 64 {
            let nlr = m.nl >> base;
            if nlr == 0 {
                break; // the line goes on past the window: a new window from its start
            }
            let p = pos + base;
            let e = nlr.trailing_zeros() as usize; // the line's bytes before its `\n`
            // the fields end before the `\r` of a `\r\n`
            let c = e - usize::from(e > 0 && block[p + e - 1] == b'\r');
            let line = (1u64 << c) - 1;
            let (sep, dot, minus, digit) = ((m.sep >> base) & line, (m.dot >> base) & line, (m.minus >> base) & line, (m.digit >> base) & line);
            let starts = 1 | sep << 1;
            let ok = (digit | dot | minus | sep) == line // nothing else on the line,
                && minus & !starts == 0 // a minus only at a field's start,
                && ((starts & !minus) | minus << 1) & !digit == 0 // a digit first after it (no empty field),
                && (dot << 1) & !digit == 0; // and a digit after a point
            let s2 = sep & sep.wrapping_sub(1);
            let s3 = s2 & s2.wrapping_sub(1);
            // exactly dim - 1 separators
            if !ok || sep == 0 || if dim == 3 { s2 == 0 || s3 != 0 } else { s2 != 0 } {
                return p;
            }
            let o = &mut out[*w * dim..*w * dim + dim];
            // the usual line: each field has a point, so points and separators alternate
            // (the first byte is a digit or a minus: a missing one shows as bit 0 here)
            let st = sep | dot;
            let b1 = st.trailing_zeros();
            let st = st & st.wrapping_sub(1);
            let b2 = st.trailing_zeros();
            let st = st & st.wrapping_sub(1);
            let b3 = st.trailing_zeros();
            let st = st & st.wrapping_sub(1);
            let b4 = st.trailing_zeros();
            let b5 = (st & st.wrapping_sub(1)).trailing_zeros();
            let bit = |b: u32| 1u64.wrapping_shl(b);
            let (points, seps) = if dim == 3 { (bit(b1) | bit(b3) | bit(b5), bit(b2) | bit(b4)) } else { (bit(b1) | bit(b3), bit(b2)) };
            if points == dot && seps == sep {
                let (b1, b2, b3, b4, b5) = (b1 as usize, b2 as usize, b3 as usize, b4 as usize, b5 as usize);
                let neg = |from: usize| (minus >> from) & 1;
                let last = if dim == 3 { b4 + 1 } else { b2 + 1 };
                let (Some(x), Some(y)) = (point_decimal(block, p, 0, b1, b2, neg(0)), point_decimal(block, p, b2 + 1, b3, if dim == 3 { b4 } else { c }, neg(b2 + 1))) else { return p };
                o[0] = x;
                o[1] = y;
                if dim == 3 {
                    let Some(z) = point_decimal(block, p, last, b5, c, neg(last)) else { return p };
                    o[2] = z;
                }
                *w += 1;
                base += e + 1;
                continue;
            }
            let a1 = sep.trailing_zeros() as usize;
            let a2 = if dim == 3 { s2.trailing_zeros() as usize } else { c };
            let (Some(x), Some(y)) = (masked_decimal(block, p, 0, a1, minus, dot), masked_decimal(block, p, a1 + 1, a2, minus, dot)) else { return p };
            o[0] = x;
            o[1] = y;
            if dim == 3 {
                let Some(z) = masked_decimal(block, p, a2 + 1, c, minus, dot) else { return p };
                o[2] = z;
            }
            *w += 1;
            base += e + 1;
        }
        if base == 0 {
            return pos; // a line of 64 bytes or more
        }
        pos += base;
    }
    pos
}

/// Parse the lines of `block` (whole lines; the first has 0-based index `line0`) into
/// `out` (`dim` per data line, at most one slot per line); the number of points written.
fn parse_block(block: &[u8], line0: usize, lay: &Layout, what: &str, out: &mut [f64]) -> Result<usize> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("bmi1")
        && std::arch::is_x86_feature_detected!("bmi2")
        && std::arch::is_x86_feature_detected!("lzcnt")
        && std::arch::is_x86_feature_detected!("popcnt")
    {
        // SAFETY: the processor has the features the function is compiled for (just checked)
        return unsafe { parse_block_avx2(block, line0, lay, what, out) };
    }
    // SAFETY: no AVX2 asked for
    unsafe { parse_block_with::<false>(block, line0, lay, what, out) }
}

/// [`parse_block`] compiled for the processors of the last decade (AVX2: the byte masks 32
/// bytes at a time; BMI1/2: bit scans and shifts in one instruction): the same code, the
/// same results, fewer instructions.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
unsafe fn parse_block_avx2(block: &[u8], line0: usize, lay: &Layout, what: &str, out: &mut [f64]) -> Result<usize> {
    // SAFETY: this function runs only where the processor has AVX2
    unsafe { parse_block_with::<true>(block, line0, lay, what, out) }
}

/// The body of [`parse_block`].
///
/// # Safety
/// With `AVX2`, the processor must have AVX2.
#[inline(always)]
unsafe fn parse_block_with<const AVX2: bool>(block: &[u8], line0: usize, lay: &Layout, what: &str, out: &mut [f64]) -> Result<usize> {
    let dim = lay.dim;
    let mut w = 0;
    let mut pos = 0;
    let mut k = line0;
    let plain = lay.style == Style::Standard && lay.need == dim && lay.slot.iter().enumerate().all(|(f, &a)| a == f);
    // after a line the shortest route declines, the next ones go straight to fast_line
    // (a file of other lines, e.g. more columns, does not pay for the route's window)
    let mut skip = 0usize;
    while pos < block.len() {
        if plain && skip == 0 {
            let w0 = w;
            // SAFETY: passed on from the caller
            pos = unsafe { plain_lines::<AVX2>(block, pos, dim, out, &mut w) };
            // one line a point: the lines read count as many
            k += w - w0;
            if pos >= block.len() {
                break;
            }
            skip = if w == w0 { 16 } else { 1 };
        }
        skip = skip.saturating_sub(1);
        let o = &mut out[w * dim..(w + 1) * dim];
        let (data, end) = match fast_line(block, pos, lay, o) {
            Some(r) => r,
            None => {
                let end = memchr::memchr(b'\n', &block[pos..]).map_or(block.len(), |i| pos + i);
                (slow_line(&block[pos..end], lay, k, what, o)?, end)
            }
        };
        w += usize::from(data);
        pos = end + 1;
        k += 1;
    }
    Ok(w)
}

/// Number of lines of `block` (the last one may lack its line break).
fn count_lines(block: &[u8]) -> usize {
    memchr::memchr_iter(b'\n', block).count() + usize::from(block.last().is_some_and(|&b| b != b'\n'))
}

/// [`count_lines`] of `block`, and whether it holds a NUL byte, 256 KB at a time (the
/// second look at each piece finds it in the cache: one pass over memory, not two).
fn count_lines_nul(block: &[u8]) -> (usize, bool) {
    let (mut n, mut nul) = (0, false);
    for piece in block.chunks(1 << 18) {
        nul |= memchr::memchr(0, piece).is_some();
        n += memchr::memchr_iter(b'\n', piece).count();
    }
    (n + usize::from(block.last().is_some_and(|&b| b != b'\n')), nul)
}

/// Map the file pages under `bytes` (a part of a read-only file map) in one call
/// (`madvise(MADV_POPULATE_READ)`, Linux 5.14+; an older kernel refuses it and the pages
/// fault in as they are read): each thread maps its own part of the file, in parallel,
/// where `MAP_POPULATE` maps the whole file on one thread before the parse starts.
fn populate_read(bytes: &[u8]) {
    #[cfg(target_os = "linux")]
    {
        const PAGE: usize = 4096;
        let (lo, hi) = (bytes.as_ptr() as usize, bytes.as_ptr() as usize + bytes.len());
        let (start, end) = (lo / PAGE * PAGE, hi.next_multiple_of(PAGE));
        if end >= start + 64 * PAGE {
            // SAFETY: whole pages of the map `bytes` lies in (a map covers whole pages);
            // the call only maps them, it changes nothing.
            unsafe { libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_POPULATE_READ) };
        }
    }
}

/// Chunks of `body` of about `target` bytes, each ending after a line break (the last at
/// the end of `body`).
fn line_chunks(body: &[u8], target: usize) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let mut lo = 0;
    while lo < body.len() {
        let probe = (lo + target.max(1)).min(body.len());
        let hi = memchr::memchr(b'\n', &body[probe..]).map_or(body.len(), |i| probe + i + 1);
        out.push(lo..hi);
        lo = hi;
    }
    out
}

/// The chunks of a text body, split at line breaks, and the number of lines of each: what
/// the parallel parse needs to write every chunk straight into its place in one array (a
/// slot per line), so the caller can allocate that array first ([`AsciiFile`]).
#[derive(Debug, Clone)]
pub struct BodyPlan {
    chunks: Vec<std::ops::Range<usize>>,
    counts: Vec<usize>,
    /// Number of lines of the body: an upper bound of its points.
    pub lines: usize,
}

/// [`BodyPlan`] of `body` over chunks of about `target` bytes (lines counted in parallel).
pub fn plan_body(body: &[u8], target: usize) -> BodyPlan {
    let chunks = line_chunks(body, target);
    let counts: Vec<usize> = chunks.par_iter().map(|r| count_lines(&body[r.clone()])).collect();
    BodyPlan { lines: counts.iter().sum(), chunks, counts }
}

/// The chunk size [`parse_body`] uses: 32 chunks a thread, 1 to 32 MB (small enough
/// that the threads finish together: the last chunk is a thirty-second of a thread's share).
fn default_target(len: usize) -> usize {
    (len / (rayon::current_num_threads() * 32)).clamp(1 << 20, 32 << 20)
}

/// Map the pages of `out` writable in one call (`madvise(MADV_POPULATE_WRITE)`, Linux
/// 5.14+; an older kernel refuses it and the pages fault one by one as before), from the
/// thread that then fills it: a fresh result array otherwise takes a page fault at the
/// first write to each 4 KB page, whose entry and exit cost about a fifth of the faults'
/// CPU (336 MB: 0.26 s of CPU against 0.33 s, measured). The contents are unchanged.
fn prefault(out: &mut [f64]) {
    #[cfg(target_os = "linux")]
    {
        const PAGE: usize = 4096;
        let (lo, bytes) = (out.as_mut_ptr() as usize, std::mem::size_of_val(out));
        let (start, end) = (lo.next_multiple_of(PAGE), (lo + bytes) / PAGE * PAGE);
        if end >= start + 64 * PAGE {
            // SAFETY: whole pages inside `out`, which this thread borrows mutably; the call
            // only maps them (writable, contents kept), it writes nothing.
            unsafe { libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_POPULATE_WRITE) };
        }
    }
}

/// Parse `body` by its `plan` into `out` (at least `plan.lines * dim` values): each chunk
/// in parallel into its own slots, then the chunks after a skipped line (blank, comment)
/// moved down once, in place. The number of points; the error is the first failing line's.
pub fn parse_planned(body: &[u8], plan: &BodyPlan, line0: usize, lay: &Layout, what: &str, out: &mut [f64]) -> Result<usize> {
    let dim = lay.dim;
    let mut parts = Vec::with_capacity(plan.chunks.len());
    let (mut rest, mut first_line) = (&mut out[..plan.lines * dim], line0);
    for (r, &c) in plan.chunks.iter().zip(&plan.counts) {
        let (head, tail) = rest.split_at_mut(c * dim);
        parts.push((r.clone(), first_line, head));
        rest = tail;
        first_line += c;
    }
    let written: Vec<Result<usize>> = parts
        .into_par_iter()
        .map(|(r, l0, o)| {
            prefault(o);
            parse_block(&body[r], l0, lay, what, o)
        })
        .collect();
    let (mut pos, mut slot) = (0, 0);
    for (w, &c) in written.into_iter().zip(&plan.counts) {
        let w = w?;
        if pos != slot {
            out.copy_within(slot..slot + w * dim, pos);
        }
        pos += w * dim;
        slot += c * dim;
    }
    Ok(pos / dim)
}

/// The coordinates of the data lines of `body` (whole lines; the first has 0-based index
/// `line0`), parsed in parallel over chunks split at line breaks ([`parse_planned`]).
/// Also returns the number of lines of `body`.
pub fn parse_body(body: &[u8], line0: usize, lay: &Layout, what: &str) -> Result<(Vec<f64>, usize)> {
    parse_chunked(body, line0, lay, what, default_target(body.len()))
}

/// [`parse_body`] over chunks of about `target` bytes.
fn parse_chunked(body: &[u8], line0: usize, lay: &Layout, what: &str, target: usize) -> Result<(Vec<f64>, usize)> {
    let plan = plan_body(body, target);
    let mut out = vec![0.0; plan.lines * lay.dim];
    let n = parse_planned(body, &plan, line0, lay, what, &mut out)?;
    out.truncate(n * lay.dim);
    Ok((out, plan.lines))
}

/// Parse an ASCII point cloud. `what` names the file in error messages.
///
/// A UTF-8 byte-order mark (as Excel writes "CSV UTF-8") is skipped; UTF-16 text is
/// refused with a hint. The separator style (decimal comma or not) is decided once from
/// the first line that starts like a number ([`detect_style`]).
pub fn parse_ascii(bytes: &[u8], opts: &AsciiOptions, what: &str) -> Result<Parsed> {
    let bytes = checked_text(bytes, opts.dim, what)?;
    let start = data_start(bytes, opts, what)?;
    let lay = start.layout;
    let (coords, _) = parse_body(&bytes[start.offset..], start.line, &lay, what)?;
    Ok(Parsed {
        coords,
        header_lines: lay.header_lines,
        columns: lay.columns,
        ncols: lay.ncols,
        decimal_comma: lay.style == Style::DecimalComma,
    })
}

/// An ASCII point file, memory-mapped (no copy of its bytes), checked, its layout read and
/// its lines counted: [`AsciiFile::read_into`] then parses it into an array of
/// [`AsciiFile::max_points`] points the caller allocates.
pub struct AsciiFile {
    map: memmap2::Mmap,
    /// Offset of the data (after the byte-order mark, skipped and header lines).
    offset: usize,
    start: DataStart,
    plan: BodyPlan,
    what: String,
}

impl AsciiFile {
    /// Open, check and plan `path` (the errors of [`parse_ascii`] about its top).
    pub fn open(path: &std::path::Path, opts: &AsciiOptions, what: &str) -> Result<AsciiFile> {
        let io = |e: std::io::Error| crate::read_error(what, e);
        let file = std::fs::File::open(path).map_err(io)?;
        if file.metadata().map_err(io)?.len() == 0 {
            return Err(parse_ascii(b"", opts, what).err().unwrap_or_else(|| GkError::file_format(format!("{what}: no points found"))));
        }
        // SAFETY: read-only map of a file the reader does not write; alive with `self`
        // (see PlyFile::open).
        // not populated here: each thread maps its part as it counts the lines
        let map = unsafe { memmap2::MmapOptions::new().map(&file) }.map_err(io)?;
        // the checks of checked_text, the NUL bytes looked for as the lines are counted
        // (an error about the top is the NUL one if the file holds any, as with checked_text)
        let text = checked_top(&map, opts.dim, what)?;
        let bom = map.len() - text.len();
        let start = data_start(text, opts, what).map_err(|e| check_no_nul(text, what).err().unwrap_or(e))?;
        let offset = bom + start.offset;
        check_no_nul(&map[bom..offset], what)?;
        let body = &map[offset..];
        let chunks = line_chunks(body, default_target(body.len()));
        let counted: Vec<(usize, bool)> = chunks
            .par_iter()
            .map(|r| {
                populate_read(&body[r.clone()]);
                count_lines_nul(&body[r.clone()])
            })
            .collect();
        if counted.iter().any(|&(_, nul)| nul) {
            check_no_nul(&[0], what)?;
        }
        let counts: Vec<usize> = counted.into_iter().map(|(n, _)| n).collect();
        let plan = BodyPlan { lines: counts.iter().sum(), chunks, counts };
        Ok(AsciiFile { offset, start, plan, what: what.to_string(), map })
    }

    /// Points the array given to [`AsciiFile::read_into`] must hold (the data lines,
    /// blank and comment lines among them included).
    pub fn max_points(&self) -> usize {
        self.plan.lines
    }

    /// The layout read from the file's top (header lines, columns, separator style).
    pub fn layout(&self) -> &Layout {
        &self.start.layout
    }

    /// Parse the points into `out` (`dim` values a point, at least [`AsciiFile::max_points`]
    /// points); the number of points written, in file order from the start of `out`.
    pub fn read_into(&self, out: &mut [f64]) -> Result<usize> {
        let lay = &self.start.layout;
        parse_planned(&self.map[self.offset..], &self.plan, self.start.line, lay, &self.what, out)
    }
}

/// [`parse_ascii`] of the file at `path`, memory-mapped (no copy of its bytes).
pub fn read_ascii_file(path: &std::path::Path, opts: &AsciiOptions, what: &str) -> Result<Parsed> {
    let f = AsciiFile::open(path, opts, what)?;
    let mut coords = vec![0.0; f.max_points() * opts.dim];
    let n = f.read_into(&mut coords)?;
    coords.truncate(n * opts.dim);
    let lay = f.layout();
    let parsed = Parsed {
        coords,
        header_lines: lay.header_lines,
        columns: lay.columns.clone(),
        ncols: lay.ncols,
        decimal_comma: lay.style == Style::DecimalComma,
    };
    // the file is unmapped on a thread of its own, which the caller need not wait for (on
    // Linux: Windows keeps a mapped file from being deleted, so there it is unmapped here);
    // if no thread can be started, here too
    #[cfg(target_os = "linux")]
    let _ = std::thread::Builder::new().name("gagekit-unmap".into()).spawn(move || drop(f));
    Ok(parsed)
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

/// The reader before its one-pass rewrite, line by line through [`fields`]: the oracle
/// the fast path, the chunking and the compaction are checked against.
#[cfg(test)]
pub(crate) fn parse_reference(bytes: &[u8], opts: &AsciiOptions, what: &str, target: usize) -> (Result<Parsed>, Result<Parsed>) {
    let reference = (|| {
        let text = checked_text(bytes, opts.dim, what)?;
        let ds = data_start(text, opts, what)?;
        let mut coords = Vec::new();
        for (k, _, line) in lines_from(text, ds.offset, ds.line) {
            let mut o = [0.0; 3];
            if slow_line(line, &ds.layout, k, what, &mut o)? {
                coords.extend_from_slice(&o[..opts.dim]);
            }
        }
        let lay = ds.layout;
        Ok(Parsed { coords, header_lines: lay.header_lines, columns: lay.columns, ncols: lay.ncols, decimal_comma: lay.style == Style::DecimalComma })
    })();
    let fast = (|| {
        let text = checked_text(bytes, opts.dim, what)?;
        let ds = data_start(text, opts, what)?;
        let (coords, _) = parse_chunked(&text[ds.offset..], ds.line, &ds.layout, what, target)?;
        let lay = ds.layout;
        Ok(Parsed { coords, header_lines: lay.header_lines, columns: lay.columns, ncols: lay.ncols, decimal_comma: lay.style == Style::DecimalComma })
    })();
    (reference, fast)
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

    use proptest::prelude::*;

    fn token() -> impl Strategy<Value = String> {
        prop_oneof![
            any::<f64>().prop_map(|v| format!("{v}")),
            any::<f64>().prop_map(|v| format!("{v:e}")),
            (-1e6f64..1e6).prop_map(|v| format!("{v:.4}")),
            (-1e6f64..1e6).prop_map(|v| format!("{v:.17e}")),
            prop::sample::select(vec![
                "0", "-0", "+0", "+.5", "5.", ".", "-", "1e", "1e+", "1E+05", "0x10", "nan", "inf", "-infinity",
                "1,5", "-4,25", "2,5e3", "1.5x", "abc", "x", "", "1e-320", "2.2250738585072011e-308",
                "4.9406564584124654e-324", "1.7976931348623157e308", "1e309", "9007199254740993", "-0.0", "0.30000000000000004", "999999999999999", "9999999999999999", "0.000000000000001", "123456789.012345", "1.5.2", "+-1", "1..2", "5.e3", "-.5",
                "0.1000000000000000055511151231257827", "123456789012345678901234567890", "00012", "1_0",
            ])
            .prop_map(String::from),
        ]
    }

    fn sep() -> impl Strategy<Value = String> {
        prop::sample::select(vec![" ", "  ", ",", ", ", " ,", ";", "; ", "\t", ",,", ";;", ",;", "\r", "\x0b", "\x0c", " \t "])
            .prop_map(String::from)
    }

    fn line() -> impl Strategy<Value = String> {
        prop_oneof![
            8 => (prop::collection::vec((token(), sep()), 1..6), prop::sample::select(vec!["", " ", "\r", "\x0c", ",", " # x"]))
                .prop_map(|(f, end)| {
                    let mut s = String::new();
                    for (i, (t, sp)) in f.iter().enumerate() {
                        if i > 0 {
                            s.push_str(sp);
                        }
                        s.push_str(t);
                    }
                    s + end
                }),
            1 => prop::sample::select(vec!["", "   ", "# comment", "  // note", "x y z", "X;Y;Z", "id,Z,Y,X", "\r"]).prop_map(String::from),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 4000, .. ProptestConfig::default() })]

        /// The one-pass reader (fast path, chunks split at line breaks, compaction) reads
        /// exactly what the line-by-line reader read: the same values bit for bit, the
        /// same error message.
        #[test]
        fn one_pass_equals_line_by_line(lines in prop::collection::vec(line(), 1..40), target in 1usize..64, dim in 2usize..=3, crlf in any::<bool>(), last_nl in any::<bool>()) {
            let nl = if crlf { "\r\n" } else { "\n" };
            let mut text = lines.join(nl);
            if last_nl {
                text.push_str(nl);
            }
            let opts = AsciiOptions { dim, skip_lines: 0 };
            let (want, got) = parse_reference(text.as_bytes(), &opts, "p", target);
            match (want, got) {
                (Ok(a), Ok(b)) => {
                    prop_assert_eq!(a.coords.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), b.coords.iter().map(|v| v.to_bits()).collect::<Vec<_>>());
                    prop_assert_eq!((a.header_lines, a.columns, a.ncols, a.decimal_comma), (b.header_lines, b.columns, b.ncols, b.decimal_comma));
                }
                (Err(a), Err(b)) => prop_assert_eq!(a.message, b.message),
                (a, b) => prop_assert!(false, "{:?} vs {:?}", a, b),
            }
        }

        /// The same on texts of mostly plain lines, read as one chunk, so that the
        /// shortest route ([`plain_lines`], which needs 96 bytes ahead) reads most of them
        /// and hands the others (any token, separator or line end it does not take) on.
        #[test]
        fn plain_lines_equal_line_by_line(lines in prop::collection::vec(prop_oneof![
            6 => prop::collection::vec(((-1e7f64..1e7, 0usize..9).prop_map(|(v, d)| format!("{v:.d$}")),
                 prop::sample::select(vec![" ", ",", "\t", ";", "  ", ", "])), 2..5)
                .prop_map(|f| f.iter().enumerate().map(|(i, (t, sp))| if i > 0 { format!("{sp}{t}") } else { t.clone() }).collect::<String>()),
            1 => line(),
        ], 1..60), dim in 2usize..=3, crlf in any::<bool>(), last_nl in any::<bool>()) {
            let nl = if crlf { "\r\n" } else { "\n" };
            let mut text = lines.join(nl);
            if last_nl {
                text.push_str(nl);
            }
            let opts = AsciiOptions { dim, skip_lines: 0 };
            let (want, got) = parse_reference(text.as_bytes(), &opts, "p", 1 << 20);
            match (want, got) {
                (Ok(a), Ok(b)) => prop_assert_eq!(a.coords.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), b.coords.iter().map(|v| v.to_bits()).collect::<Vec<_>>()),
                (Err(a), Err(b)) => prop_assert_eq!(a.message, b.message),
                (a, b) => prop_assert!(false, "{:?} vs {:?}", a, b),
            }
        }
    }

    #[test]
    fn mapped_file_refuses_nul_bytes_anywhere() {
        // the mapped read (the NUL bytes looked for as the lines are counted, in chunks)
        // gives the errors of parse_ascii: a NUL byte anywhere makes it a binary file,
        // before any other error; a clean file reads the same
        let dir = std::env::temp_dir().join(format!("gagekit_ascii_nul_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let body = "1 2 3\n4.5,-6.25,7\n".repeat(200_000); // 3.6 MB: several chunks
        let cases: Vec<Vec<u8>> = vec![
            [body.as_bytes(), b"4 5\x00 6\n"].concat(),
            [b"x y z\n\x00\n".as_slice(), body.as_bytes()].concat(),
            b"foo\x00\nbar\n".to_vec(),
            [body.as_bytes(), b"# c\x00omment\n", body.as_bytes()].concat(),
            body.clone().into_bytes(),
        ];
        for (i, bytes) in cases.iter().enumerate() {
            let path = dir.join(format!("{i}.xyz"));
            std::fs::write(&path, bytes).unwrap();
            let want = parse_ascii(bytes, &AsciiOptions::default(), "f");
            let got = read_ascii_file(&path, &AsciiOptions::default(), "f");
            match (want, got) {
                (Err(a), Err(b)) => {
                    assert!(a.message.contains("binary file"), "{}", a.message);
                    assert_eq!(a.message, b.message);
                }
                (Ok(a), Ok(b)) => assert!(i == 4 && a == b && a.coords.len() == 1_200_000),
                (a, b) => panic!("case {i}: {a:?} vs {b:?}"),
            }
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn prefault_keeps_the_contents() {
        // fresh (untouched) and written pages, an unaligned slice, one too short to advise
        let mut v = vec![0.0; 1 << 20];
        for (i, x) in v.iter_mut().enumerate().skip(300_000) {
            *x = i as f64 * 0.5 - 7.25;
        }
        let want = v.clone();
        prefault(&mut v[3..]);
        prefault(&mut v[5..9]);
        assert!(v.iter().zip(&want).all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    #[test]
    fn chunk_boundaries_and_skipped_lines() {
        let text = b"x y z\n1 2 3\n\n# c\n4 5 6\n\n\n7 8 9 10\n1e3,-2.5,+3\n4 5 6";
        for target in 1..40 {
            let (want, got) = parse_reference(text, &AsciiOptions::default(), "c", target);
            assert_eq!(want.unwrap().coords, got.unwrap().coords);
        }
        let bad = b"1 2 3\n4 5 6\n\n7 8\n";
        for target in 1..20 {
            let e = parse_reference(bad, &AsciiOptions::default(), "c", target).1.unwrap_err();
            assert!(e.message.contains("line 4"), "{}", e.message);
        }
    }
}

#[cfg(test)]
mod number_tests {
    use super::parse_number;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 20000, .. ProptestConfig::default() })]
        /// The plain-decimal route (eight digits at a time where eight bytes remain, else
        /// byte by byte) reads what fast-float2 reads, bit for bit, and takes the same
        /// bytes, at any offset, with any bytes after it (non-ASCII ones too).
        #[test]
        fn plain_decimals_equal_fast_float(lead in "[ ]{0,3}", int in "[+-]?[0-9]{0,19}", frac in "(\\.[0-9]{0,19})?", tail in "[ ,;eE.x\n\r]?[0-9]?", pad in "(( |\u{e9}|\u{ff}|\u{10ffff})[0-9]{0,9}){0,2}") {
            // as it is, and with 32 more bytes after it (the straight-line route of
            // short_decimal needs 32 bytes ahead)
            for s in [format!("{lead}{int}{frac}{tail}{pad}"), format!("{lead}{int}{frac}{tail}{pad}{}", " 1".repeat(16))] {
                let at = lead.len();
                let a = parse_number(s.as_bytes(), at).map(|(v, n)| (v.to_bits(), n));
                let b = fast_float2::parse_partial::<f64, _>(&s.as_bytes()[at..]).ok().map(|(v, n): (f64, usize)| (v.to_bits(), n));
                prop_assert_eq!(a, b, "{:?}", s);
            }
        }
    }


    /// A plain data line of `dim` decimals (a sign `-` or none, 1 to 9 integer digits, no
    /// point, or a point and 0 to 9 decimals), with its tokens.
    fn plain_row() -> impl Strategy<Value = (String, Vec<String>)> {
        let token = ("-?", "[0-9]{1,9}", "(\\.[0-9]{0,9})?").prop_map(|(s, i, f)| format!("{s}{i}{f}"));
        (prop::collection::vec(token, 2..=3), prop::sample::select(vec![" ", "\t", ",", ";"]), prop::sample::select(vec!["\n", "\r\n"])).prop_map(|(t, sep, end)| (t.join(sep) + end, t))
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 3000, .. ProptestConfig::default() })]
        /// The block parser, in both its builds (the baseline x86-64 one and, where the
        /// processor has it, the AVX2 one), reads each token of plain lines as
        /// `str::parse::<f64>` reads it, bit for bit: the mask route (up to 8 integer
        /// digits, 8 decimals, 15 in all) and the others (longer numbers, `5.`).
        #[test]
        fn plain_lines_equal_str_parse(rows in prop::collection::vec(plain_row(), 1..80), dim3 in any::<bool>()) {
            let dim = if dim3 { 3 } else { 2 };
            let rows: Vec<_> = rows.into_iter().filter(|(_, t)| t.len() == dim).collect();
            prop_assume!(!rows.is_empty());
            let text: String = rows.iter().map(|(l, _)| l.as_str()).collect();
            let want: Vec<u64> = rows.iter().flat_map(|(_, t)| t.iter().map(|x| x.parse::<f64>().unwrap().to_bits())).collect();
            let opts = super::AsciiOptions { dim, skip_lines: 0 };
            let lay = super::data_start(text.as_bytes(), &opts, "p").unwrap().layout;
            let mut out = vec![0.0; rows.len() * dim];
            // SAFETY: no AVX2 asked for
            let n = unsafe { super::parse_block_with::<false>(text.as_bytes(), 0, &lay, "p", &mut out) }.unwrap();
            prop_assert_eq!(n, rows.len());
            prop_assert_eq!(out.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), want.clone());
            let n = super::parse_block(text.as_bytes(), 0, &lay, "p", &mut out).unwrap();
            prop_assert_eq!(n, rows.len());
            prop_assert_eq!(out.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), want);
        }

        /// The byte masks of a window, by SSE2, by AVX2 (where the processor has it) and byte
        /// by byte, are the same.
        #[test]
        fn window_masks_agree(bytes in prop::collection::vec(prop_oneof![
            4 => prop::sample::select(b"0123456789.- \t,;\n\r+e".to_vec()),
            1 => any::<u8>(),
        ], 64)) {
            let w: &[u8; 64] = bytes.as_slice().try_into().unwrap();
            let want = super::window_masks_bytes(w);
            // SAFETY: no AVX2 asked for
            prop_assert_eq!(unsafe { super::window_masks::<false>(w) }, want);
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the processor has AVX2 (just checked)
                prop_assert_eq!(unsafe { super::window_masks::<true>(w) }, want);
            }
        }
    }

    #[test]
    fn digit_runs() {
        for (t, want) in [("12345678", (8, 12345678)), ("1234567x", (7, 1234567)), ("0000001.", (7, 1)), ("x1234567", (0, 0)), ("9\n999999", (1, 9)), ("98765432", (8, 98765432)), ("1/:23456", (1, 1))] {
            assert_eq!(super::digit_run(u64::from_le_bytes(t.as_bytes().try_into().unwrap())), want, "{t}");
        }
    }
}
