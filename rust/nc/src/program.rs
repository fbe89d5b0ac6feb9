//! Modal interpretation of a program: which lines move, where to, and what to rewrite.
//!
//! Supported: G0/G1 (modal), G90/G91 (G91 is converted: the output is absolute), G17/G18/G19,
//! G21, G40, G49, G80, G94, G61, G64, G4 with P; N block numbers; F, S, T, M words (not M98/M99);
//! `O` program numbers alone on a line; the machine's joint letters. G2/G3 only with an arc
//! tolerance (then linearised, `arc` module). Everything else is an error naming the line.

use crate::arc;
use crate::lexer::{words, Word};
use gagekit_core::{GkError, Result};

/// What the interpreter needs to know about the machine and the run.
#[derive(Clone, Debug)]
pub struct Options {
    /// Joint letters (upper-case ASCII), in command order.
    pub letters: Vec<u8>,
    /// Position of each joint before the program, when known.
    pub start: Vec<Option<f64>>,
    /// Chord tolerance (mm) to linearise G2/G3; `None`: arcs are errors.
    pub arc_tolerance: Option<f64>,
}

/// A change to the text of a line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Edit {
    /// Joint word (joint index) to rewrite with the (corrected, absolute) value.
    Coord(usize, usize, usize),
    /// `G91` to write as `G90` (span of the number).
    Absolute(usize, usize),
    /// `G2`/`G3` to write as `G1` (span of the number).
    Linear(usize, usize),
    /// A word to drop (I, J, K, R of a linearised arc).
    Drop(usize, usize),
}

/// A move: `count` new points (arc points, then the end point) appended after `first - 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    pub rapid: bool,
    /// Index of the start point (the previous end), if every joint was known.
    pub from: Option<usize>,
    pub first: usize,
    pub count: usize,
    /// Byte offset after which missing joint words are inserted.
    pub insert_at: usize,
    /// Feed word span to repeat on the first inserted line.
    pub feed: Option<(usize, usize)>,
    /// The block's coordinates were incremental (G91): every joint word is rewritten.
    pub incremental: bool,
    /// The motion mode in force before the block (0, 1, 2, 3), if any.
    pub prev_motion: Option<u8>,
}

/// One input line: byte range (without the line break) and how to rewrite it.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    pub start: usize,
    pub end: usize,
    pub edits: Vec<Edit>,
    pub mv: Option<Move>,
}

/// The interpreted program: lines and the nominal points (row-major, J per point).
#[derive(Clone, Debug, Default)]
pub struct Program {
    pub lines: Vec<Line>,
    pub points: Vec<f64>,
    pub n_joints: usize,
    /// The joints in the order the program first writes them (joints it never writes follow,
    /// in machine order): the order of the words gagekit writes.
    pub order: Vec<usize>,
}

const ALLOWED_G: [f64; 15] = [0.0, 1.0, 4.0, 17.0, 18.0, 19.0, 21.0, 40.0, 49.0, 80.0, 90.0, 91.0, 94.0, 61.0, 64.0];

fn g_error(g: f64) -> String {
    let gi = g as i64;
    let what = match gi {
        2 | 3 => "arcs (G2/G3) are not supported: use --linearize-arcs TOL",
        20 => "inch programs (G20) are not supported: gagekit works in millimetres",
        28 | 29 | 30 => "reference-point returns (G28/G29/G30) are not supported",
        41 | 42 | 43 | 44 => "cutter radius or tool length compensation (G41-G44) is not supported",
        52..=59 | 92 => "coordinate systems and work offsets (G52-G59, G92) are not supported: program in machine coordinates",
        73 | 74 | 76 | 81..=89 => "canned cycles are not supported",
        65 | 66 | 67 => "macro calls are not supported",
        _ => "",
    };
    if what.is_empty() {
        format!("G{} is not supported", fmt_g(g))
    } else {
        format!("G{}: {what}", fmt_g(g))
    }
}

fn fmt_g(g: f64) -> String {
    if g.fract() == 0.0 {
        format!("{}", g as i64)
    } else {
        format!("{g}")
    }
}

/// Interpret `text` (lines separated by `\n`): each line is read into its words
/// ([`Interpreter::read_block`]), the modal state is updated, and a line that moves gets its
/// end point ([`Interpreter::end_point`]) and its move ([`Interpreter::push_move`]).
pub fn interpret(text: &[u8], opts: &Options) -> Result<Program> {
    let mut it = Interpreter::new(opts);
    let mut offset = 0usize;
    for (k, raw) in text.split(|&b| b == b'\n').enumerate() {
        let start = offset;
        offset += raw.len() + 1;
        if start >= text.len() && raw.is_empty() {
            break;
        }
        it.line(raw, start, k + 1)?;
    }
    let mut prog = it.prog;
    for j in 0..prog.n_joints {
        if !prog.order.contains(&j) {
            prog.order.push(j);
        }
    }
    Ok(prog)
}

/// The error for line `lineno`.
fn at(lineno: usize, m: impl std::fmt::Display) -> GkError {
    GkError::invalid(format!("line {lineno}: {m}"))
}

/// The words of one block, sorted by what they do.
struct Block {
    /// Per joint: (value, word start, word end).
    coords: Vec<Option<(f64, usize, usize)>>,
    new_motion: Option<u8>,
    dwell: bool,
    has_p: bool,
    /// I, J, K, R of an arc to linearise.
    ijkr: [Option<f64>; 4],
    feed: Option<(usize, usize)>,
    last_word_end: usize,
}

/// Modal state and output of the interpretation.
struct Interpreter<'a> {
    opts: &'a Options,
    nj: usize,
    /// Joint index of each (upper-case) letter, `usize::MAX` for none.
    joint_of: [usize; 256],
    xyz: Vec<usize>,
    prog: Program,
    /// Last known position of each joint.
    pos: Vec<Option<f64>>,
    /// Index of the last point, once every joint is known.
    last_point: Option<usize>,
    motion: Option<u8>,
    incremental: bool,
    plane: u8,
    ws: Vec<Word>,
    block: Block,
    end: Vec<f64>,
}

impl<'a> Interpreter<'a> {
    fn new(opts: &'a Options) -> Self {
        let nj = opts.letters.len();
        let mut joint_of = [usize::MAX; 256];
        for (j, &l) in opts.letters.iter().enumerate() {
            joint_of[l.to_ascii_uppercase() as usize] = j;
        }
        let xyz: Vec<usize> = [b'X', b'Y', b'Z'].iter().map(|&c| joint_of[c as usize]).collect();
        let mut prog = Program { n_joints: nj, ..Default::default() };
        let pos: Vec<Option<f64>> = opts.start.clone();
        let last_point = if pos.iter().all(|p| p.is_some()) {
            prog.points.extend(pos.iter().map(|p| p.unwrap_or(0.0)));
            Some(0)
        } else {
            None
        };
        let block = Block {
            coords: Vec::with_capacity(nj),
            new_motion: None,
            dwell: false,
            has_p: false,
            ijkr: [None; 4],
            feed: None,
            last_word_end: 0,
        };
        Interpreter {
            opts,
            nj,
            joint_of,
            xyz,
            prog,
            pos,
            last_point,
            motion: None,
            incremental: false,
            plane: 17,
            ws: Vec::new(),
            block,
            end: vec![0.0; nj],
        }
    }

    /// One line: its words, the modal state, and its move if it has one.
    fn line(&mut self, raw: &[u8], start: usize, lineno: usize) -> Result<()> {
        let mut line = Line { start, end: start + raw.len(), edits: Vec::new(), mv: None };
        if !words(raw, lineno, &mut self.ws)? || self.ws.is_empty() {
            self.prog.lines.push(line);
            return Ok(());
        }
        self.read_block(raw, lineno, &mut line)?;
        let b = &self.block;
        if b.has_p && !b.dwell {
            return Err(at(lineno, "a P word is only supported with G4 (dwell)"));
        }
        let prev_motion = self.motion;
        if let Some(m) = b.new_motion {
            self.motion = Some(m);
        }
        let moving = b.coords.iter().any(|c| c.is_some());
        if b.dwell && moving {
            return Err(at(lineno, "G4 with an axis word (dwell time as X?): give the dwell time with P"));
        }
        if !moving {
            if b.ijkr.iter().any(|v| v.is_some()) {
                return Err(at(lineno, "arc words without an end point"));
            }
            self.prog.lines.push(line);
            return Ok(());
        }
        let m = self.motion.ok_or_else(|| at(lineno, "axis words without a motion mode (G0, G1)"))?;
        self.end_point(lineno, &mut line)?;
        self.push_move(m, prev_motion, lineno, &mut line)?;
        self.prog.lines.push(line);
        Ok(())
    }

    /// Sort the block's words: joint coordinates, G/M/F/S/T/P words, arc words; errors for
    /// what is not supported. G91 and G2/G3 (when linearised) get their edits here.
    fn read_block(&mut self, raw: &[u8], lineno: usize, line: &mut Line) -> Result<()> {
        let b = &mut self.block;
        b.coords.clear();
        b.coords.resize(self.nj, None);
        b.new_motion = None;
        b.dwell = false;
        b.has_p = false;
        b.ijkr = [None; 4];
        b.feed = None;
        b.last_word_end = 0;
        let arcs = self.opts.arc_tolerance.is_some();
        let n_words = self.ws.len();
        for (i, w) in self.ws.iter().enumerate() {
            b.last_word_end = w.end;
            let j = self.joint_of[w.letter as usize];
            if j != usize::MAX {
                if b.coords[j].is_some() {
                    return Err(at(lineno, format!("{} appears twice", w.letter as char)));
                }
                b.coords[j] = Some((w.value, w.start, w.end));
                if !self.prog.order.contains(&j) {
                    self.prog.order.push(j);
                }
                continue;
            }
            match w.letter {
                b'N' if i == 0 => {}
                b'N' => return Err(at(lineno, "a block number N must come first")),
                b'O' if n_words == 1 => {}
                b'O' => return Err(at(lineno, "O words (subprograms, macros) are not supported")),
                b'G' => Self::g_word(w, arcs, lineno, b, line, &mut self.plane, &mut self.incremental)?,
                b'M' => {
                    let m = w.value as i64;
                    if m == 98 || m == 99 || m == 198 {
                        return Err(at(lineno, format!("M{m}: subprogram calls are not supported")));
                    }
                }
                b'F' => b.feed = Some((w.start, w.end)),
                b'S' | b'T' => {}
                b'P' => b.has_p = true,
                b'I' | b'J' | b'K' | b'R' if arcs => {
                    let k = b"IJKR".iter().position(|&c| c == w.letter).unwrap_or(0);
                    b.ijkr[k] = Some(w.value);
                    line.edits.push(Edit::Drop(w.start, w.end));
                }
                _ => {
                    let names: Vec<String> = self.opts.letters.iter().map(|&c| (c as char).to_string()).collect();
                    return Err(at(
                        lineno,
                        format!(
                            "word '{}' is not supported: the machine's axes are {}",
                            String::from_utf8_lossy(&raw[w.start..w.end]).trim(),
                            names.join(", ")
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// A G word: motion mode, dwell, plane, absolute/incremental.
    fn g_word(
        w: &Word,
        arcs: bool,
        lineno: usize,
        b: &mut Block,
        line: &mut Line,
        plane: &mut u8,
        incremental: &mut bool,
    ) -> Result<()> {
        let g = w.value;
        let gi = g as i64;
        if (g == 2.0 || g == 3.0) && arcs {
            b.new_motion = Some(gi as u8);
            line.edits.push(Edit::Linear(w.start + 1, w.end));
            return Ok(());
        }
        if !ALLOWED_G.contains(&g) {
            return Err(at(lineno, g_error(g)));
        }
        match gi {
            0 | 1 => b.new_motion = Some(gi as u8),
            4 => b.dwell = true,
            17..=19 => *plane = gi as u8,
            90 => *incremental = false,
            91 => {
                *incremental = true;
                line.edits.push(Edit::Absolute(w.start + 1, w.end));
            }
            _ => {}
        }
        Ok(())
    }

    /// The block's end point in absolute coordinates (G91 added to the last position,
    /// joints without a word keep theirs), with an edit for every joint word.
    fn end_point(&mut self, lineno: usize, line: &mut Line) -> Result<()> {
        for j in 0..self.nj {
            self.end[j] = match (self.block.coords[j], self.pos[j]) {
                (Some((v, s, e)), p) => {
                    line.edits.push(Edit::Coord(j, s, e));
                    if self.incremental {
                        p.ok_or_else(|| {
                            at(
                                lineno,
                                format!(
                                    "incremental {} move from an unknown position (give --start)",
                                    self.opts.letters[j] as char
                                ),
                            )
                        })? + v
                    } else {
                        v
                    }
                }
                (None, Some(p)) => p,
                (None, None) => {
                    return Err(at(
                        lineno,
                        format!(
                            "{} has no position yet: program it before the first move or give --start",
                            self.opts.letters[j] as char
                        ),
                    ))
                }
            };
        }
        Ok(())
    }

    /// Append the move's points (a linearised arc's, then the end point) and its record.
    fn push_move(&mut self, m: u8, prev_motion: Option<u8>, lineno: usize, line: &mut Line) -> Result<()> {
        let nj = self.nj;
        let first = self.prog.points.len() / nj;
        let mut count = 1;
        if m == 2 || m == 3 {
            let tol = self.opts.arc_tolerance.unwrap_or(0.0);
            let from = self.last_point.ok_or_else(|| at(lineno, "an arc needs a known start point"))?;
            let p0: Vec<f64> = self.prog.points[from * nj..(from + 1) * nj].to_vec();
            let pts = arc::linearize(&p0, &self.end, &self.xyz, self.plane, m == 2, self.block.ijkr, tol)
                .map_err(|m| at(lineno, m))?;
            count += pts.len() / nj;
            self.prog.points.extend(pts);
        }
        self.prog.points.extend_from_slice(&self.end);
        line.edits.sort_by_key(|e| match *e {
            Edit::Coord(_, a, _) | Edit::Absolute(a, _) | Edit::Linear(a, _) | Edit::Drop(a, _) => a,
        });
        line.mv = Some(Move {
            rapid: m == 0,
            from: self.last_point,
            first,
            count,
            insert_at: self.block.last_word_end,
            feed: self.block.feed,
            incremental: self.incremental,
            prev_motion,
        });
        self.last_point = Some(first + count - 1);
        for j in 0..nj {
            self.pos[j] = Some(self.end[j]);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts() -> Options {
        Options { letters: b"BXZYW".to_vec(), start: vec![Some(0.0), None, None, None, Some(-500.0)], arc_tolerance: None }
    }

    #[test]
    fn modal_coordinates_and_incremental_moves() {
        let p = interpret(b"%\nN1 G90 G0 X10 Y20 Z1000\nG1 X15 F100\nG91 Y5\n(only a comment)\n%\n", &opts()).unwrap();
        assert_eq!(p.lines.len(), 6);
        let pts: Vec<&[f64]> = p.points.chunks(5).collect();
        assert_eq!(pts, vec![&[0.0, 10.0, 1000.0, 20.0, -500.0][..], &[0.0, 15.0, 1000.0, 20.0, -500.0], &[0.0, 15.0, 1000.0, 25.0, -500.0]]);
        assert!(p.lines[1].mv.unwrap().rapid && p.lines[1].mv.unwrap().from.is_none());
        assert_eq!(p.lines[2].mv.unwrap().from, Some(0));
        assert!(p.lines[3].edits.contains(&Edit::Absolute(1 + p.lines[3].start - p.lines[3].start, 3)));
    }

    #[test]
    fn errors_name_the_line() {
        for (text, want) in [
            (&b"G0 X1 Y1 Z1000\nG2 X2 Y2 I1 J0\n"[..], "line 2: G2: arcs"),
            (b"G0 X1 Y1 Z1000\nG81 X1 Y1 Z900 R1\n", "line 2: G81: canned"),
            (b"G0 X1 Y1 Z1000 A30\n", "line 1: word 'A30' is not supported"),
            (b"G1 X1\n", "line 1: Z has no position"),
            (b"X1\n", "line 1: axis words without a motion mode"),
            (b"G0 X1 Y1 Z1\nM98 P100\n", "line 2: M98"),
            (b"G54 G0 X1\n", "line 1: G54"),
            (b"G0 X1 Y1 Z1\nG4 X2\n", "line 2: G4 with an axis word"),
        ] {
            let e = interpret(text, &opts()).unwrap_err().message;
            assert!(e.starts_with(want), "{e} / {want}");
        }
    }
}
