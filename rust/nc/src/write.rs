//! Writing the corrected program: every byte of the input is copied except the words the
//! interpreter marked (joint words, G91, linearised arcs) and the inserted blocks.

use crate::program::{Edit, Program};
use crate::Settings;

fn number(out: &mut Vec<u8>, v: f64, decimals: usize) {
    use std::io::Write;
    // no "-0.000": a value that rounds to zero is written without its sign
    let v = if (v.abs() * 10f64.powi(decimals as i32)).round() == 0.0 { 0.0 } else { v };
    let _ = write!(out, "{v:.decimals$}");
}

/// The output text. `legs`: (line index, from point, to point, pieces) in program order;
/// `ins`: the corrected inserted points in the same order.
pub fn program(text: &[u8], prog: &Program, corr: &[f64], legs: &[(usize, usize, usize, usize)], ins: &[f64], s: &Settings) -> Vec<u8> {
    let nj = prog.n_joints;
    let letters = &s.options.letters;
    let comp = |j: usize| s.joints.contains(&j);
    let mut out = Vec::with_capacity(text.len() + text.len() / 4 + 256);
    let header = format!("({})", s.header.replace('(', "[").replace(')', "]"));
    let mut header_done = false;
    let mut leg = 0usize;
    let mut ins_at = 0usize;
    for (li, line) in prog.lines.iter().enumerate() {
        let raw = &text[line.start..line.end];
        let mut moved_feed = None;
        let eol: &[u8] = if raw.ends_with(b"\r") { b"\r\n" } else { b"\n" };
        let has_newline = line.end < text.len();
        if !header_done && !(li == 0 && raw.iter().copied().filter(|b| !b.is_ascii_whitespace()).eq(*b"%")) {
            out.extend_from_slice(header.as_bytes());
            out.extend_from_slice(eol);
            header_done = true;
        }
        if let Some(mv) = line.mv {
            // inserted points of this block's legs
            let feed = mv.feed.map(|(a, b)| &text[line.start + a..line.start + b]);
            // the first written point carries the block's feed (then in force: the block
            // drops it, F is modal) and G1 where the mode in force is not already linear
            let g1 = !matches!(mv.prev_motion, Some(1..=3));
            let mut first_inserted = true;
            let start = mv.from.unwrap_or(mv.first);
            let moving: Vec<bool> = (0..nj)
                .map(|j| comp(j) || (mv.first..mv.first + mv.count).any(|p| prog.points[p * nj + j] != prog.points[start * nj + j]))
                .collect();
            while leg < legs.len() && legs[leg].0 == li {
                let (_, _, b, pieces) = legs[leg];
                for _ in 1..pieces {
                    write_point(&mut out, &ins[ins_at * nj..(ins_at + 1) * nj], letters, &prog.order, &moving, s.decimals, first_inserted.then_some((g1, feed)));
                    out.extend_from_slice(eol);
                    first_inserted = false;
                    ins_at += 1;
                }
                if b != mv.first + mv.count - 1 {
                    // an arc vertex: written as a point of its own
                    write_point(&mut out, &corr[b * nj..(b + 1) * nj], letters, &prog.order, &moving, s.decimals, first_inserted.then_some((g1, feed)));
                    out.extend_from_slice(eol);
                    first_inserted = false;
                }
                leg += 1;
            }
            moved_feed = if first_inserted { None } else { mv.feed };
        }
        if line.edits.is_empty() && line.mv.is_none() {
            out.extend_from_slice(raw);
        } else {
            rewrite(&mut out, raw, line, prog, corr, s, moved_feed);
        }
        if has_newline {
            out.push(b'\n');
        }
    }
    if !header_done {
        out.extend_from_slice(header.as_bytes());
        out.push(b'\n');
    }
    out
}

/// An inserted point: the moving joints' words in the program's order; the first point of a
/// block (`first`: whether G1 is needed, the block's feed word) carries the modal words.
fn write_point(out: &mut Vec<u8>, p: &[f64], letters: &[u8], order: &[usize], moving: &[bool], decimals: usize, first: Option<(bool, Option<&[u8]>)>) {
    let mut sep = false;
    if let Some((true, _)) = first {
        out.extend_from_slice(b"G1");
        sep = true;
    }
    for &j in order {
        if moving[j] {
            if sep {
                out.push(b' ');
            }
            out.push(letters[j]);
            number(out, p[j], decimals);
            sep = true;
        }
    }
    if let Some((_, Some(f))) = first {
        out.push(b' ');
        out.extend_from_slice(f);
    }
}

fn rewrite(out: &mut Vec<u8>, raw: &[u8], line: &crate::program::Line, prog: &Program, corr: &[f64], s: &Settings, moved_feed: Option<(usize, usize)>) {
    let nj = prog.n_joints;
    let mut edits = line.edits.clone();
    if let Some((a, b)) = moved_feed {
        edits.push(Edit::Drop(a, b));
        edits.sort_by_key(|e| match *e {
            Edit::Coord(_, a, _) | Edit::Absolute(a, _) | Edit::Linear(a, _) | Edit::Drop(a, _) => a,
        });
    }
    let end = line.mv.map(|m| m.first + m.count - 1);
    let incremental = line.edits.iter().any(|e| matches!(e, Edit::Absolute(..))) || line.mv.map(|m| m.incremental).unwrap_or(false);
    let mut seen = vec![false; nj];
    let mut at = 0usize;
    for e in &edits {
        match *e {
            Edit::Coord(j, a, b) => {
                out.extend_from_slice(&raw[at..a]);
                seen[j] = true;
                let p = end.unwrap();
                if s.joints.contains(&j) || incremental {
                    out.push(raw[a]);
                    let v = if s.joints.contains(&j) { corr[p * nj + j] } else { prog.points[p * nj + j] };
                    number(out, v, s.decimals);
                } else {
                    out.extend_from_slice(&raw[a..b]);
                }
                at = b;
            }
            Edit::Absolute(a, b) => {
                out.extend_from_slice(&raw[at..a]);
                out.extend_from_slice(b"90");
                at = b;
            }
            Edit::Linear(a, b) => {
                out.extend_from_slice(&raw[at..a]);
                out.push(b'1');
                at = b;
            }
            Edit::Drop(a, b) => {
                out.extend_from_slice(&raw[at..a]);
                if a > 0 && raw[a - 1] == b' ' && out.last() == Some(&b' ') {
                    out.pop();
                }
                at = b;
            }
        }
        if let Some(mv) = line.mv {
            if at == mv.insert_at {
                missing(out, &mut seen, corr, end.unwrap(), s, prog);
            }
        }
    }
    if let Some(mv) = line.mv {
        if at <= mv.insert_at {
            out.extend_from_slice(&raw[at..mv.insert_at]);
            at = mv.insert_at;
            missing(out, &mut seen, corr, end.unwrap(), s, prog);
        }
    }
    out.extend_from_slice(&raw[at..]);
}

/// The corrected joints' words the block lacks, appended in the program's word order.
fn missing(out: &mut Vec<u8>, seen: &mut [bool], corr: &[f64], p: usize, s: &Settings, prog: &Program) {
    let nj = prog.n_joints;
    for &j in &prog.order {
        if s.joints.contains(&j) && !seen[j] {
            out.push(b' ');
            out.push(s.options.letters[j]);
            number(out, corr[p * nj + j], s.decimals);
            seen[j] = true;
        }
    }
}
