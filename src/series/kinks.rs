//! Piecewise-analytic problems: a step ends just past the first kink it
//! meets.
//!
//! A problem may be analytic on each side of the zeros of its event
//! functions g_k(U, lambda) and only continuous across them
//! ([`ContinuationProblem::kinks`]): the penalty contact law, paper eq. (3)
//! at eta = 0, R = max(0, −K h), whose event function is the gap h. A
//! series computed on one piece is exact there and wrong past the kink,
//! and nothing in the series tells where the kink is (the ratio rule sees
//! the piece's own analytic continuation). So the step is cut at the first
//! kink of any g_k along the step's own representation (polynomial or
//! Padé): the g_k are sampled at SAMPLES points over (0, a_s], then the
//! first interval holding a kink is bisected down to adjacent
//! floating-point numbers, and the step ends at its far end, just past the
//! kink, so that the next step starts on the new piece and its series are
//! exact again. One step per kink, against the train of short steps that
//! shrink toward a regularized switch and grow back after it (eq. 3 at
//! eta > 0: its branch points h = ±2i sqrt(eta delta / K) sit at the
//! switch).
//!
//! The pieces are g_k < 0 and g_k >= 0, as the problem's own functions
//! decide them at the step start (the penalty law: in contact for h < 0),
//! and a kink counts when g_k leaves the band |g_k| <= 1 on the other side:
//! the problem scales g_k so that staying on the wrong piece within the
//! band costs less than its accuracy (the penalty law: g = h / band, K band
//! a tenth of the residual test's force). Without the band, nodes resting
//! on the obstacle with reactions near zero, which sit at the kink within
//! the round-off of their position, switch at every step (0.05 m
//! plate-cylinder: 1,237 steps instead of 48). A g_k that is NaN (an
//! undefined gap) takes its piece from the first sample where it is not. A
//! node touching and lifting off within one sixteenth of a step is missed.
//!
//! Few orders. Nodes mirrored across a symmetric model touch ~4e-11 apart
//! in lambda (round-off), so every second step is a ~1e-9 step to the
//! mirror's kink, where a series of order 15 is mostly unused. After a few
//! orders p (super::path, EARLY_KINK_ORDERS) the step looks for a kink
//! within a quarter of their own ratio-rule length; if one is there, the
//! step stops computing orders and ends at it ([`within_orders`]). 0.025 m
//! penalty plate-cylinder: 2,261 → 1,075 solves, 2,044 → 860 series
//! orders, the same curves to 1e-7 of the tight run.

use super::continuation::{ContinuationProblem, PathStep};
use crate::error::Result;

/// Samples of the event functions over (0, a_s].
const SAMPLES: usize = 16;

/// The length at which the step should end: just past the first kink of
/// an event function on (0, step.length], or None if there is none.
pub fn first_kink<P: ContinuationProblem + ?Sized>(
    problem: &P,
    step: &PathStep,
) -> Result<Option<f64>> {
    // Only the unknowns the events read (the contact nodes' translations),
    // in a buffer that keeps the others at their step-start values.
    let unknowns = problem.event_unknowns();
    let mut buffer = step.u[0].clone();
    let mut at = |a: f64| -> Result<Vec<f64>> {
        match &unknowns {
            Some(idx) => {
                let l = step.eval_at(a, idx, &mut buffer);
                problem.events(&buffer, l)
            }
            None => {
                let (u, l) = step.eval(a);
                problem.events(&u, l)
            }
        }
    };
    // The piece of each function at the step start: g < 0 or g >= 0 (NaN:
    // unknown, the piece of its first sample that is not).
    let start = at(0.0)?;
    if start.is_empty() {
        return Ok(None);
    }
    let mut pieces: Vec<Option<bool>> = start.iter().map(|g| piece(*g)).collect();
    // A function leaving the band |g| <= 1 on the other side of its start
    // piece.
    let crossed = |pieces: &mut [Option<bool>], g: &[f64]| -> bool {
        let mut any = false;
        for (s, &v) in pieces.iter_mut().zip(g) {
            match *s {
                None => *s = piece(v),
                Some(true) if v > 1.0 => any = true,
                Some(false) if v < -1.0 => any = true,
                _ => {}
            }
        }
        any
    };
    let mut lo = 0.0;
    for i in 1..=SAMPLES {
        let hi = step.length * i as f64 / SAMPLES as f64;
        if !crossed(&mut pieces, &at(hi)?) {
            lo = hi;
            continue;
        }
        // Bisection: no crossing at lo, a crossing at hi.
        let mut hi = hi;
        loop {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                return Ok(Some(hi));
            }
            let mut probe = pieces.clone();
            if crossed(&mut probe, &at(mid)?) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
    }
    Ok(None)
}

/// The first kink on (0, length] of the series of orders 0..p (U and
/// lambda), when the step is to end before its higher orders would matter:
/// `length` is their ratio-rule length (module docs, "Few orders").
pub fn within_orders<P: ContinuationProblem + ?Sized>(
    problem: &P,
    u: &[Vec<f64>],
    lambda: &[f64],
    length: f64,
) -> Result<Option<f64>> {
    first_kink(
        problem,
        &PathStep::from_series(u.to_vec(), lambda.to_vec(), length),
    )
}

/// The piece g < 0 (true) or g >= 0 (false); None where g is NaN (a gap
/// that is undefined).
fn piece(g: f64) -> Option<bool> {
    (!g.is_nan()).then_some(g < 0.0)
}
