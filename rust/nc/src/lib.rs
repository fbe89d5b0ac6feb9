//! G-code programs (RS-274 / ISO 6983) corrected through a machine's inverse error model.
//!
//! [`compensate_program`] interprets a program ([`program`]: modal G0/G1, G90/G91, comments,
//! block numbers, F/S/T/M words; arcs linearised on request, [`arc`]), corrects every
//! programmed point with the inverse of the first-order error model
//! (`gagekit_kinematics::Machine::compensate`), subdivides linear moves whose correction changes
//! by more than `max_step` along them (or bends away from the straight line by more), and writes
//! the program back: inserted points first, as `G1` blocks without numbers; the original block
//! with its number and words, ending at the corrected end point; every other byte copied.

pub mod arc;
pub mod lexer;
pub mod program;
mod write;

use gagekit_core::{GkError, Result};
use gagekit_kinematics::Machine;
pub use program::{interpret, Edit, Line, Move, Options, Program};

/// How to correct a program.
#[derive(Clone, Debug)]
pub struct Settings {
    pub options: Options,
    /// Factor from file units to the kernel's (1 for mm, pi/180 for degrees), per joint.
    pub unit: Vec<f64>,
    /// Compensating joints (indices into the letters).
    pub joints: Vec<usize>,
    /// Largest change of the correction between consecutive points of a linear move, mm.
    pub max_step: f64,
    /// Decimals of the written coordinates.
    pub decimals: usize,
    /// Text of the leading comment (parentheses are replaced).
    pub header: String,
    /// Gauss-Newton iterations of the inverse model.
    pub iterations: usize,
    /// Joint ranges (file units) to check the programmed and corrected points against;
    /// empty: not checked.
    pub ranges: Vec<(f64, f64)>,
}

/// The most points one linear move may be split into: a smaller max step than this allows
/// (1e-9 mm on a 1 m move: 10^12 points) is refused, not allocated.
pub const MAX_PIECES_PER_MOVE: usize = 100_000;
/// The most points inserted into one program.
pub const MAX_INSERTED: usize = 20_000_000;

/// Joints whose range a program leaves: how many programmed points (nominal or corrected)
/// are outside, and the first line with one.
#[derive(Clone, Debug, PartialEq)]
pub struct OutOfRange {
    pub joint: usize,
    pub count: usize,
    pub first_line: usize,
}

/// What was done.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// Lines read.
    pub lines: usize,
    /// Lines written (with the leading comment and the inserted blocks).
    pub lines_written: usize,
    pub moves: usize,
    pub inserted: usize,
    pub subdivided: usize,
    /// Largest correction of a programmed point, mm (or file units for rotary joints).
    pub max_correction: f64,
    /// Largest predicted error left at a written point, mm.
    pub max_remaining: f64,
    /// Joints whose range the programmed or corrected points leave (empty when no ranges).
    pub outside: Vec<OutOfRange>,
    /// The joints in the program's word order (see [`Program::order`]).
    pub order: Vec<usize>,
}

/// Corrected points: (corrected (n, J), remaining (n, 3)) in file units.
fn correct(m: &Machine, params: &[f64], s: &Settings, points: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
    let nj = s.unit.len();
    let internal: Vec<f64> = points.iter().enumerate().map(|(i, v)| v * s.unit[i % nj]).collect();
    let (mut c, left) = m.compensate(&internal, params, &s.joints, s.iterations)?;
    for (i, v) in c.iter_mut().enumerate() {
        *v /= s.unit[i % nj];
    }
    Ok((c, left))
}

/// A leg of a linear move between two points (indices), split into `pieces`.
#[derive(Clone, Copy, Debug)]
struct Leg {
    a: usize,
    b: usize,
    pieces: usize,
    curved: bool,
}

/// Correct `text` for `machine` with parameters `params`; returns the new program text.
pub fn compensate_program(text: &[u8], machine: &Machine, params: &[f64], s: &Settings) -> Result<(Vec<u8>, Report)> {
    let nj = s.options.letters.len();
    if nj != machine.n_joints() || s.unit.len() != nj {
        return Err(GkError::invalid(format!("{nj} joint letters for a machine with {} joints", machine.n_joints())));
    }
    if !(s.max_step.is_finite() && s.max_step > 0.0) {
        return Err(GkError::invalid(format!("max step must be a positive number of mm, got {}", s.max_step)));
    }
    let prog = interpret(text, &s.options)?;
    let (corr, left) = correct(machine, params, s, &prog.points)?;
    let delta = |pts: &[f64], cor: &[f64], i: usize, j: usize| cor[i * nj + j] - pts[i * nj + j];
    let rotary: Vec<bool> = s.unit.iter().map(|&u| u != 1.0).collect();
    // legs of the linear moves
    let mut legs: Vec<(usize, Leg)> = Vec::new();
    for (li, line) in prog.lines.iter().enumerate() {
        let Some(mv) = line.mv else { continue };
        let Some(from) = mv.from else { continue };
        if mv.rapid {
            continue;
        }
        let mut a = from;
        for b in mv.first..mv.first + mv.count {
            let mut change: f64 = 0.0;
            for &j in &s.joints {
                change = change.max((delta(&prog.points, &corr, b, j) - delta(&prog.points, &corr, a, j)).abs());
            }
            let length: f64 = (0..nj).filter(|&j| !rotary[j]).map(|j| (prog.points[b * nj + j] - prog.points[a * nj + j]).powi(2)).sum::<f64>().sqrt();
            let turns = (0..nj).any(|j| rotary[j] && prog.points[b * nj + j] != prog.points[a * nj + j]);
            let pieces = (change / s.max_step).ceil().max(1.0);
            if pieces > MAX_PIECES_PER_MOVE as f64 {
                return Err(too_many(li, change, pieces, s.max_step));
            }
            let pieces = pieces as usize;
            legs.push((li, Leg { a, b, pieces, curved: turns || length > 100.0 }));
            a = b;
        }
    }
    // refine legs whose correction bends away from the chord by more than max_step
    for _ in 0..12 {
        let check: Vec<usize> = (0..legs.len()).filter(|&k| legs[k].1.curved).collect();
        if check.is_empty() {
            break;
        }
        // corrections at the pieces' ends and midpoints: f = i / (2 n), i = 0..=2n
        let mut pts = Vec::new();
        for &k in &check {
            let l = legs[k].1;
            for i in 0..=2 * l.pieces {
                let f = i as f64 / (2 * l.pieces) as f64;
                pts.extend((0..nj).map(|j| lerp(&prog.points, l.a, l.b, j, nj, f)));
            }
        }
        let (c, _) = correct(machine, params, s, &pts)?;
        let d = |i: usize, j: usize| c[i * nj + j] - pts[i * nj + j];
        let mut at = 0;
        for &k in &check {
            let l = legs[k].1;
            let mut worst: f64 = 0.0;
            for i in 0..l.pieces {
                let (p0, pm, p1) = (at + 2 * i, at + 2 * i + 1, at + 2 * i + 2);
                for &j in &s.joints {
                    worst = worst.max((d(pm, j) - 0.5 * (d(p0, j) + d(p1, j))).abs());
                }
            }
            at += 2 * l.pieces + 1;
            if worst > s.max_step {
                if 2 * l.pieces > MAX_PIECES_PER_MOVE {
                    return Err(too_many(legs[k].0, worst, (2 * l.pieces) as f64, s.max_step));
                }
                legs[k].1.pieces *= 2;
            } else {
                legs[k].1.curved = false;
            }
        }
    }
    // the inserted points
    let total: usize = legs.iter().map(|(_, l)| l.pieces - 1).sum();
    if total > MAX_INSERTED {
        return Err(GkError::invalid(format!(
            "the program would grow by {total} points (more than {MAX_INSERTED}) at a max step of {} mm: raise the max step",
            s.max_step
        )));
    }
    let mut inserted = Vec::with_capacity(total * nj);
    for (_, l) in &legs {
        for i in 1..l.pieces {
            let f = i as f64 / l.pieces as f64;
            inserted.extend((0..nj).map(|j| lerp(&prog.points, l.a, l.b, j, nj, f)));
        }
    }
    let (ins_corr, ins_left) = correct(machine, params, s, &inserted)?;
    let mut report = Report { lines: prog.lines.len(), ..Default::default() };
    report.moves = prog.lines.iter().filter(|l| l.mv.is_some()).count();
    report.inserted = inserted.len() / nj.max(1);
    report.subdivided = legs.iter().filter(|(_, l)| l.pieces > 1).count();
    report.max_correction = corr.iter().zip(&prog.points).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    report.max_remaining = left.chunks(3).chain(ins_left.chunks(3)).map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()).fold(0.0, f64::max);
    report.outside = outside(&prog, &corr, &s.ranges);
    report.order = prog.order.clone();
    let out = write::program(text, &prog, &corr, &legs.iter().map(|(li, l)| (*li, l.a, l.b, l.pieces)).collect::<Vec<_>>(), &ins_corr, s);
    report.lines_written = out.split(|&b| b == b'\n').count() - usize::from(out.ends_with(b"\n"));
    Ok((out, report))
}

/// The refusal of a move that would be split into more than [`MAX_PIECES_PER_MOVE`] points.
fn too_many(line: usize, change: f64, pieces: f64, max_step: f64) -> GkError {
    GkError::invalid(format!(
        "line {}: the correction changes by {change:.3e} mm along this move; at a max step of {max_step} mm it would be \
         split into {pieces:.3e} points, more than {MAX_PIECES_PER_MOVE}: raise the max step",
        line + 1
    ))
}

/// Joints whose range the programmed (nominal) or corrected points of the moves leave.
fn outside(prog: &Program, corr: &[f64], ranges: &[(f64, f64)]) -> Vec<OutOfRange> {
    let nj = prog.n_joints;
    if ranges.len() != nj {
        return Vec::new();
    }
    let mut out: Vec<OutOfRange> = Vec::new();
    for (li, line) in prog.lines.iter().enumerate() {
        let Some(mv) = line.mv else { continue };
        for p in mv.first..mv.first + mv.count {
            for (j, &(lo, hi)) in ranges.iter().enumerate() {
                let (a, b) = (prog.points[p * nj + j], corr[p * nj + j]);
                if a < lo || a > hi || b < lo || b > hi {
                    match out.iter_mut().find(|o| o.joint == j) {
                        Some(o) => o.count += 1,
                        None => out.push(OutOfRange { joint: j, count: 1, first_line: li + 1 }),
                    }
                }
            }
        }
    }
    out.sort_by_key(|o| prog.order.iter().position(|&j| j == o.joint));
    out
}

fn lerp(points: &[f64], a: usize, b: usize, j: usize, nj: usize, f: f64) -> f64 {
    points[a * nj + j] + (points[b * nj + j] - points[a * nj + j]) * f
}
