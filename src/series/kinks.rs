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
//! sign change of any g_k along the step's own representation (polynomial
//! or Padé): the g_k are sampled at SAMPLES points over (0, a_s], then the
//! first interval holding a sign change is bisected down to adjacent
//! floating-point numbers, and the step ends at its far end, just past the
//! zero, so that the next step starts on the new piece and its series are
//! exact again. One step per kink, against the train of short steps that
//! shrink toward a regularized switch and grow back after it (eq. 3 at
//! eta > 0: its branch points h = ±2i sqrt(eta delta / K) sit at the
//! switch).
//!
//! A g_k that starts at exactly 0 takes its sign from the first sample
//! where it is not; two kinks inside one sampling interval are both seen
//! only if their signs differ at the interval's ends (a node touching and
//! lifting off within a sixteenth of a step is missed).

use super::continuation::{ContinuationProblem, PathStep};
use crate::error::Result;

/// Samples of the event functions over (0, a_s].
const SAMPLES: usize = 16;

/// The length at which the step should end: just past the first sign
/// change of an event function on (0, step.length], or None if there is
/// none.
pub fn first_kink<P: ContinuationProblem + ?Sized>(
    problem: &P,
    step: &PathStep,
) -> Result<Option<f64>> {
    let at = |a: f64| -> Result<Vec<f64>> {
        let (u, l) = step.eval(a);
        problem.events(&u, l)
    };
    let mut signs: Vec<f64> = at(0.0)?.iter().map(|g| sign(*g)).collect();
    if signs.is_empty() {
        return Ok(None);
    }
    // A sign change of a function whose start sign is known; a zero start
    // adopts the first nonzero sign it meets.
    let crossed = |signs: &mut [f64], g: &[f64]| -> bool {
        let mut any = false;
        for (s, &v) in signs.iter_mut().zip(g) {
            let now = sign(v);
            if *s == 0.0 {
                *s = now;
            } else if now != 0.0 && now != *s {
                any = true;
            }
        }
        any
    };
    let mut lo = 0.0;
    for i in 1..=SAMPLES {
        let hi = step.length * i as f64 / SAMPLES as f64;
        if !crossed(&mut signs, &at(hi)?) {
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
            let mut probe = signs.clone();
            if crossed(&mut probe, &at(mid)?) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
    }
    Ok(None)
}

/// −1, 0 or 1 (NaN counts as 0: no gap, no sign).
fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}
