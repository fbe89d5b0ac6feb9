//! Words of one RS-274 / ISO 6983 block: `N10 G1 X1.5 (comment) Y-2 ; comment`.
//!
//! A word is an address letter and a decimal number (spaces allowed between them); comments
//! are `( ... )` and everything after `;`. `%` alone on a line marks the tape start or end.
//! Anything else (macro variables `#1`, expressions `[...]`, `GOTO`, block delete `/`) is an
//! error naming the line.

use gagekit_core::{GkError, Result};

/// One word: address letter (upper case), value, and its byte span in the line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Word {
    pub letter: u8,
    pub value: f64,
    pub start: usize,
    pub end: usize,
}

/// The words of a line (``None`` for a `%` tape mark).
pub fn words(line: &[u8], lineno: usize, out: &mut Vec<Word>) -> Result<bool> {
    out.clear();
    let n = line.len();
    let mut i = 0;
    let err = |msg: String| GkError::invalid(format!("line {lineno}: {msg}"));
    while i < n {
        let c = line[i];
        match c {
            b' ' | b'\t' | b'\r' => i += 1,
            b'(' => match line[i..].iter().position(|&b| b == b')') {
                Some(k) => i += k + 1,
                None => return Err(err("comment '(' is not closed".into())),
            },
            b';' => break,
            b'%' => {
                if out.is_empty() && line[i + 1..].iter().all(|b| b.is_ascii_whitespace()) {
                    return Ok(false);
                }
                return Err(err("'%' inside a block".into()));
            }
            b'#' => return Err(err("macro variables (#) are not supported".into())),
            b'/' => return Err(err("block delete (/) is not supported".into())),
            c if c.is_ascii_alphabetic() => {
                let start = i;
                i += 1;
                while i < n && (line[i] == b' ' || line[i] == b'\t') {
                    i += 1;
                }
                let num = i;
                if i < n && (line[i] == b'+' || line[i] == b'-') {
                    i += 1;
                }
                let mut digits = 0;
                while i < n && (line[i].is_ascii_digit() || line[i] == b'.') {
                    digits += line[i].is_ascii_digit() as usize;
                    i += 1;
                }
                let text = std::str::from_utf8(&line[num..i]).unwrap_or("");
                let value = match text.parse::<f64>() {
                    Ok(v) if digits > 0 && v.is_finite() => v,
                    _ => {
                        let shown: String = String::from_utf8_lossy(&line[start..(start + 12).min(n)]).into_owned();
                        return Err(err(format!("cannot read the word '{}' (macros and expressions are not supported)", shown.trim())));
                    }
                };
                out.push(Word { letter: c.to_ascii_uppercase(), value, start, end: i });
            }
            _ => {
                return Err(err(format!("unexpected character '{}'", String::from_utf8_lossy(&line[i..i + 1]))));
            }
        }
    }
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_comments_and_spans() {
        let mut w = Vec::new();
        assert!(words(b"N10 g1 X 1.5 (cut) y-2. ; end", 1, &mut w).unwrap());
        let l: Vec<(u8, f64)> = w.iter().map(|w| (w.letter, w.value)).collect();
        assert_eq!(l, vec![(b'N', 10.0), (b'G', 1.0), (b'X', 1.5), (b'Y', -2.0)]);
        assert_eq!(&b"N10 g1 X 1.5 (cut) y-2. ; end"[w[2].start..w[2].end], b"X 1.5");
        assert!(!words(b"%", 1, &mut w).unwrap());
        for bad in [&b"G1 X#1"[..], b"/N1 G1", b"GOTO 10", b"G1 X[1+2]", b"(open", b"X--1"] {
            assert!(words(bad, 7, &mut w).unwrap_err().message.starts_with("line 7: "));
        }
    }
}
