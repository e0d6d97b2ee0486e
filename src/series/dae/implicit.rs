//! The implicit two-point Taylor (Hermite–Obreshkov) step, and the per-step
//! choice between it and the explicit series.
//!
//! Why the explicit step is bounded by stiffness: it expands the solution at
//! t0, y(t0 + a) = sum y_p a^p. Near a slow manifold the computed terms carry
//! a fast component d λ^p / p! (λ < 0 the fast rate, d the distance of y0 to
//! the manifold, at least round-off: every order multiplies the round-off of
//! the lower ones by about |λ|/p), which dominates the last orders, so the
//! ratio rule a = (eps |y_1| / |y_N|)^(1/(N-1)) gives a ≈ 10–20/|λ| for
//! N = 20. On friction-plane before contact |λ| ≈ k / (f |R_N|_reg g′), and
//! the steps grow like 1/ζ. Moving y0 onto the manifold does not help: the
//! required shift is below the round-off of y0 itself.
//!
//! The step used where the explicit one is stiffness-bound is the
//! Hermite–Obreshkov formula [m/n] (Hairer & Wanner, Solving ODEs II,
//! §IV.7 / Obreshkov 1940), written with the Taylor coefficients u0_j at t0
//! and u1_j at t1 = t0 + h, both computed as in the explicit step (eqs. 8–9:
//! one factorization of dF/d(v, z), one solve per order; at t1 from the
//! consistent (v, z) at (u1, t1)):
//!   sum_{j=0}^{n} γ(n, m, j) u1_j (-h)^j = sum_{j=0}^{m} γ(m, n, j) u0_j h^j,   (I2)
//!   γ(m, n, j) = m! (m + n - j)! / ((m + n)! (m - j)!).
//! On y' = λ y it gives y1 = R(λh) y0 with R the [m/n] Padé approximant of
//! the exponential: local order m + n, A-stable, and for n = m + 1 also
//! L-stable (R(z) → 0 as z → -∞), so a fast mode is damped whatever h |λ|.
//! We take m = 5, n = 6 (order 11). (I2) is solved for u1 by a quasi-Newton
//! iteration whose first matrix is that of the linear constant-coefficient
//! case, M = sum_j γ(n, m, j) (-h A)^j / j! with A = dv/du = -[J^-1 F_u]_v at the
//! first iterate, then Broyden updates; each iteration costs a consistent
//! initialization (Newton on F(u1, ., t1) = 0 from the linear prediction
//! (v, z) + d(v, z)/du Δu1) and a series of order n at t1. It starts from
//! the series at t0 summed to its smallest term, moved onto the slow
//! manifold in the stiff directions ([`onto_slow_manifold`]).
//!
//! Error and step length: u1 against the [m-1/n] formula (order m + n - 1,
//! also L-stable), |M'^-1 G'(u1)| with M' its matrix of the linear case,
//! against eps max(|u0_1| h, |u1|) (eps of the explicit ratio rule; |u1|
//! when u barely moves; u0_1 the step start's first-order term, not the
//! iterate's, which is large exactly where the iterate is off the slow
//! manifold), on the differential unknowns; the algebraic ones
//! are solved consistently at t1 (as IDA's suppress-alg,
//! docs/reference-solvers.md) and their own formula defects count where
//! their fast content is small; the fast amplitude left at t1 counts too.
//! Next h = h clamp(0.9 ratio^(-1/(m+n)), 0.2, 2), capped by Gustafsson's
//! predictive controller ([`Chooser::growth`]). On a fast mode the defect
//! is about the fast amplitude at t0 (u1 carries d0 R(λh)), small on the
//! manifold, so h follows the slow solution.
//!
//! Dense output: at the caller's output times inside the step
//! (`DaeConfig::output_times`) the Hermite interpolant of orders 0..3 at
//! both ends is the output where it agrees with that of orders 0..4 to the
//! step's tolerance, (v, z) then solved consistent with its u
//! ([`hermite_point`]); elsewhere the output time is solved by (I2) from t0
//! (started from that interpolant, then from the series at t0) and must
//! pass its own error test: a step that misses one is retried to end
//! before it.
//! Between the output times, per unknown, the two-point Hermite
//! interpolant of the Taylor coefficients of orders 0..k at both ends, k = 1
//! in a stiff step (h |A| > 1), min(m, n) otherwise. The series at t1 alone,
//! evaluated back to t < t1, would carry the fast terms (h |A|)^p.
//!
//! Candidates measured before this choice (README "Stiffness in time"):
//! scalar Padé approximants of the explicit series (`time_pade.rs`:
//! [N/2 / N/2] against [N/2-1 / N/2]) agree only a few fast time constants
//! further; the one-point implicit Taylor step (m = 0, n = N: the series at
//! t1 evaluated back to t0) is limited to h |λ| ≲ 30, where the backward sum
//! of the fast terms, ~ e^(h|λ|) ε, reaches the state; (I2) with n ≈ 6
//! keeps that sum polynomial, (h|λ|)^n, and is balanced by the same power
//! on the left.
//!
//! Per step (`Stepping::Auto`): the series at t0 is computed as for an
//! explicit step; its ratio-rule length a_exp and |A| (row-sum norm) say
//! whether a fast mode limits it (|A| a_exp > 5). If so, and if no singular
//! point is in sight (geometric test on the series at t0) and no fast
//! transient is under way (the fast amplitude that would explain u_N,
//! |u_N| N! / |A|^N, below eps), (I2) is tried from the last implicit length
//! (or 4 × cost × a_exp), shrinking on rejection down to a_exp. The step is
//! kept if it reaches PAYS = 2 times its cost (series, consistent
//! initializations; in explicit steps) further than a_exp; otherwise the
//! explicit step is taken and the next 8, 16, 32 ... steps are explicit.
//! `Stepping::Implicit` skips the stiffness and cost tests. Singular points
//! are reported by explicit steps only. With several differential unknowns,
//! |A| is a bound and M a dense nd × nd matrix: fine for a handful.
//!
//! A quasi-Newton iteration that stalls (its update at the round-off of u1)
//! is accepted: G's round-off floor, ε |u1| |M| with |M| ~ (h |A|)^n, is far
//! above 16 ε times its terms. A stall off the slow manifold is refused by
//! the fast amplitude left at t1 (the step-start transient test, applied to
//! the end). At an output time, whose series is not read further, the
//! iteration ends one series earlier: when the next update would be at
//! that round-off and G at its floor (a step end iterates on: its series
//! starts the next step and the output times' guesses).

use super::{
    DaeConfig, DaeProblem, Engine, Stepping, TimeStep, consistent_point, copy_series,
    explicit_step, series_at, solve_series,
};
// (geometric_distance is reached as super::geometric_distance)
use crate::error::{Error, Result};
use crate::linalg::{DenseLu, norm};

/// Orders (m, n) of the two-point formula (I2): L-stable (n = m + 1),
/// local order m + n = 11 (choice measured, README "Stiffness in time").
const HO_M: usize = 5;
const HO_N: usize = 6;
/// |A| a_exp above which a fast mode is taken to limit the explicit step.
const STIFF: f64 = 5.0;
/// An implicit step is kept (auto) when it reaches PAYS times further than
/// its cost in explicit steps.
const PAYS: f64 = 2.0;
/// Largest growth of the implicit step from one step to the next.
const MAX_GROWTH: f64 = 2.0;
/// Orders at both ends of the Hermite interpolant that starts the
/// iterations of the output times inside an implicit step.
const GUESS: usize = 3;
/// Quasi-Newton iterations per implicit try.
const MAX_ITERATIONS: usize = 10;

/// State of the per-step choice between the explicit and implicit steps.
#[derive(Clone, Debug, Default)]
pub(super) struct Chooser {
    /// Next implicit step length (from the last accepted implicit step).
    h: Option<f64>,
    /// Length and error ratio of the last accepted implicit step of the
    /// current run of implicit steps ([`Chooser::growth`]).
    last_accepted: Option<(f64, f64)>,
    /// Explicit steps before the next implicit try.
    cooldown: usize,
    /// Consecutive implicit tries that ended explicit.
    failures: u32,
    /// Quasi-Newton iterations of implicit tries (accepted or not).
    pub iterations: usize,
    /// Quasi-Newton iterations of the output times inside implicit steps,
    /// and how many output times they solved: [`Chooser::cost`] charges a
    /// step for the outputs it covers (an explicit step gets them from its
    /// series for free), per output, not averaged into the step: averaged,
    /// they grew with the outputs long steps cover, and on the closed-form
    /// test (tau = 1e-2 s) a step's cost reached 147 explicit steps, so
    /// `auto` went back to explicit steps (32 steps instead of 9).
    pub output_iterations: usize,
    pub output_points: usize,
    /// Output times taken from the Hermite interpolant ([`hermite_point`]).
    pub hermite_points: usize,
    pub accepted: usize,
    pub rejected: usize,
    /// The weights γ of the run's (m, n), and the LU of the Hermite
    /// interpolation matrix per (k0, k1): the same for every step.
    gammas: Option<Gammas>,
    hermite: Vec<((usize, usize), DenseLu)>,
    /// ln N! = sum_{k=2}^{N} ln k at index N, summed in that order (cached:
    /// a logarithm per order and step otherwise).
    ln_fact: Vec<f64>,
}

impl Chooser {
    /// ln n! as [`fast_amplitude`] sums it.
    fn ln_factorial(&mut self, n: usize) -> f64 {
        if self.ln_fact.is_empty() {
            // The empty sums (n = 0, 1) as `Iterator::sum` gives them.
            self.ln_fact = vec![std::iter::empty::<f64>().sum(); 2];
        }
        while self.ln_fact.len() <= n {
            let k = self.ln_fact.len();
            let last = self.ln_fact[k - 1];
            self.ln_fact.push(last + (k as f64).ln());
        }
        self.ln_fact[n]
    }

    /// The weights γ of (I2) [m/n] and of its error estimate (cached).
    fn gammas(&mut self, m: usize, n: usize) -> &Gammas {
        if self.gammas.as_ref().is_none_or(|g| (g.m, g.n) != (m, n)) {
            self.gammas = Some(Gammas::new(m, n));
        }
        self.gammas.as_ref().expect("set above")
    }

    /// [`hermite_data`] with the matrix's LU cached per (k0, k1).
    fn hermite_data(
        &mut self,
        y0: &[Vec<f64>],
        y1: &[Vec<f64>],
        h: f64,
        k0: usize,
        k1: usize,
    ) -> Vec<Vec<f64>> {
        let at = match self.hermite.iter().position(|(k, _)| *k == (k0, k1)) {
            Some(at) => at,
            None => {
                self.hermite.push(((k0, k1), hermite_matrix(k0, k1)));
                self.hermite.len() - 1
            }
        };
        hermite_solve(&self.hermite[at].1, y0, y1, h, k0, k1)
    }

    /// Growth of the next implicit step after one of length h accepted
    /// at error ratio `ratio` (≤ 1), the error ∝ h^order: the standard
    /// 0.9 ratio^(−1/order), and no more than Gustafsson's predictive
    /// controller (as in RADAU5, Hairer & Wanner II §IV.8), which also
    /// follows the trend from the previous accepted step:
    ///   0.9 ratio^(−1/order) (h / h_prev) (ratio_prev / ratio)^(1/order).
    /// Where the error grows from step to step (friction-plane before
    /// contact closes) the standard rule alone overshoots every time and
    /// each step's first try is rejected.
    fn growth(&mut self, h: f64, ratio: f64, order: usize) -> f64 {
        let k = order as f64;
        let standard = 0.9 * ratio.powf(-1.0 / k);
        let grow = match self.last_accepted {
            Some((h_prev, ratio_prev)) if ratio > 0.0 && ratio_prev > 0.0 => {
                standard.min(standard * (h / h_prev) * (ratio_prev / ratio).powf(1.0 / k))
            }
            _ => standard,
        };
        self.last_accepted = Some((h, ratio));
        grow.clamp(0.2, MAX_GROWTH)
    }

    /// Explicit steps for 8, 16, 32 ... steps after an implicit try that
    /// did not pay; the next try starts again from the explicit length.
    fn back_off(&mut self) {
        self.h = None;
        self.last_accepted = None;
        self.cooldown = 8 << self.failures.min(10);
        self.failures += 1;
    }

    /// Cost of an implicit step that covers `outputs` output times, in
    /// explicit steps (series of order N): the series at t0, then per
    /// iteration (of the step, and of each output time it covers) a series
    /// of order n and the consistent initialization (about two
    /// factorizations).
    fn cost(&self, n_ord: usize, outputs: usize) -> f64 {
        let per_step = if self.accepted == 0 {
            4.0
        } else {
            self.iterations as f64 / self.accepted as f64
        };
        let per_output = if self.output_points == 0 {
            2.0
        } else {
            self.output_iterations as f64 / self.output_points as f64
        };
        1.0 + (per_step + outputs as f64 * per_output) * (HO_N + 2) as f64 / n_ord as f64
    }
}

/// One step from (u0, vz0) at t0: explicit or implicit as `cfg.stepping`
/// and the series say.
pub(super) fn step<P: DaeProblem + ?Sized>(
    eng: &mut Engine<P>,
    ch: &mut Chooser,
    u0: &[f64],
    vz0: &[f64],
    t0: f64,
    index: usize,
    cfg: &DaeConfig,
) -> Result<TimeStep> {
    if matches!(cfg.stepping, Stepping::Explicit | Stepping::Pade) {
        return explicit_step(eng, u0, vz0, t0, index, cfg, None);
    }
    let n_ord = cfg.order;
    let series0 = series_at(eng, u0, vz0, t0, index, n_ord)?;
    let remaining = cfg.t_end - t0;
    let a_exp = super::ratio_length(&series0, cfg.eps, n_ord).min(remaining);
    let fast = jacobian_size(eng);
    // A singular point ahead (geometric tail of the series at t0): the
    // explicit step reports it.
    let singular = super::geometric_distance(eng, &series0, n_ord).is_some();
    // A fast transient not yet decayed: the explicit steps resolve it (an
    // L-stable step would damp it at once, right at its end but not inside).
    let d0 = fast_amplitude(&series0, eng.nd, n_ord, fast, ch.ln_factorial(n_ord));
    let scale0 =
        norm(u0).max(norm(&(0..eng.nd).map(|i| series0[i][1]).collect::<Vec<_>>()) * a_exp);
    let transient = d0 > cfg.eps * scale0;
    let try_implicit = match cfg.stepping {
        _ if singular || transient => false,
        Stepping::Implicit => true,
        _ if ch.cooldown > 0 => {
            ch.cooldown -= 1;
            false
        }
        _ => a_exp < remaining && fast * a_exp > STIFF,
    };
    if try_implicit {
        let (m, n) = (HO_M.min(n_ord - 1), HO_N.min(n_ord));
        let mut h =
            ch.h.unwrap_or(4.0 * ch.cost(n_ord, 0) * a_exp)
                .max(a_exp)
                .min(remaining);
        loop {
            // Once tried, the implicit step is kept down to the explicit length.
            if h <= a_exp || h < cfg.min_step {
                break;
            }
            match attempt(
                eng,
                ch,
                u0,
                vz0,
                t0,
                h,
                (m, n),
                index,
                cfg,
                &series0,
                None,
                Target::StepEnd,
            ) {
                Ok((series, ratio)) if ratio <= 1.0 => {
                    let inside: Vec<f64> = cfg
                        .output_times
                        .iter()
                        .copied()
                        .filter(|&t| t > t0 && t < t0 + h)
                        .collect();
                    if cfg.stepping == Stepping::Auto
                        && h < PAYS * ch.cost(n_ord, inside.len()) * a_exp
                    {
                        // Not paying for itself: the explicit step, and
                        // explicit steps for a while.
                        break;
                    }
                    let end_residual = eng.output_norm(0);
                    // Dense output between the output times: Hermite of
                    // orders 0..k at both ends, k = 1 in a stiff step (the
                    // higher orders at t0 carry the fast mode times (h|A|)^k).
                    let k = if h * fast > 1.0 { 1 } else { m.min(n) };
                    let dense = ch.hermite_data(&series0, &series, h, k, k);
                    // The starting guess of the output times' iterations:
                    // orders 0..3 at both ends. Its fast content, about
                    // d (h |A|)^3 / 3! with d the ends' fast amplitude,
                    // leaves it off by 1e-10 … 1e-8 where the cubic (k = 1)
                    // is off by 1e-7 … 1e-4 (friction-plane, zeta = 1e-4 N,
                    // h |A| up to 4e4), and only the solved points are
                    // output. Quasi-Newton iterations of the run from orders
                    // 1 / 2 / 3 / 4: 968 / 844 / 734 / 738.
                    let start = ch.hermite_data(&series0, &series, h, GUESS.min(m), GUESS.min(n));
                    // One order more at both ends: the estimate of the
                    // guess's error, where the guess is the output.
                    let finer = ch.hermite_data(
                        &series0,
                        &series,
                        h,
                        (GUESS + 1).min(m),
                        (GUESS + 1).min(n),
                    );
                    // Output times inside: the Hermite guess where its
                    // estimate passes, else solved by (I2) over t0 -> t.
                    let mut points = Vec::new();
                    let before = ch.iterations;
                    let mut missed = None;
                    let mut from_hermite = 0;
                    for t in inside {
                        // From the Hermite value (near the right root of
                        // (I2)); kept where it passes its own error test.
                        let s = (t - t0) / h;
                        let guess: Vec<f64> = start
                            .iter()
                            .map(|c| crate::series::taylor::eval(c, s))
                            .collect();
                        if let Some(point) =
                            hermite_point(eng, &series0, &finer, &guess, (t, h, s), index, cfg)
                        {
                            points.push(point);
                            from_hermite += 1;
                            continue;
                        }
                        // Then from the tangent at t0 if that fails.
                        let mut solve = |g: Option<&[f64]>| {
                            attempt(
                                eng,
                                ch,
                                u0,
                                vz0,
                                t0,
                                t - t0,
                                (m, n),
                                index,
                                cfg,
                                &series0,
                                g,
                                Target::OutputTime,
                            )
                            .ok()
                            .filter(|r| r.1 <= 1.0)
                        };
                        match solve(Some(&guess)).or_else(|| solve(None)) {
                            Some((p, _)) => {
                                let y: Vec<f64> = p.iter().map(|c| c[0]).collect();
                                let dy: Vec<f64> = p.iter().map(|c| c[1]).collect();
                                points.push((t, y, dy));
                            }
                            None => {
                                missed = Some(t);
                                break;
                            }
                        }
                    }
                    ch.output_iterations += ch.iterations - before;
                    ch.output_points += points.len();
                    ch.hermite_points += from_hermite;
                    ch.iterations = before;
                    if let Some(t) = missed {
                        // An output time (I2) cannot reach: the Hermite
                        // interpolant (k = 1) is not accurate over a long
                        // stiff step (friction-roller, order 10: 1.3e-4 at
                        // t = 0.59 s inside a 0.33 s step). The step is
                        // retried to end just before it.
                        ch.rejected += 1;
                        eng.stats.step_cuts += 1;
                        h = 0.99 * (t - t0);
                        continue;
                    }
                    let grow = ch.growth(h, ratio, m + n);
                    ch.h = Some(h * grow);
                    ch.accepted += 1;
                    ch.failures = 0;
                    return Ok(TimeStep {
                        index,
                        t0,
                        length: h,
                        origin: t0 + h,
                        implicit: true,
                        pade: None,
                        dense: Some(dense),
                        points,
                        series,
                        end_residual,
                        geometric: None,
                    });
                }
                Ok((_, ratio)) => {
                    ch.rejected += 1;
                    eng.stats.step_cuts += 1;
                    h *= (0.9 * ratio.powf(-1.0 / (m + n) as f64)).clamp(0.2, 0.9);
                }
                Err(_) => {
                    // The quasi-Newton iteration or the consistent
                    // initialization failed: the predictor was too far.
                    ch.rejected += 1;
                    eng.stats.step_cuts += 1;
                    h *= 0.25;
                }
            }
        }
        if cfg.stepping == Stepping::Auto {
            ch.back_off();
        } else {
            ch.h = None;
            ch.last_accepted = None;
        }
    }
    explicit_step(eng, u0, vz0, t0, index, cfg, Some(series0))
}

/// Amplitude d of a fast mode e^(λ t) (|λ| = `fast`) that would explain the
/// last term of the differential unknowns: |u_N| = d |λ|^N / N!, i.e.
/// d = |u_N| N! / |λ|^N (in logarithms: |λ|^N overflows). An upper bound
/// of the fast amplitude when the last term is fast-dominated. `ln_fact`:
/// ln N! ([`Chooser::ln_factorial`]).
fn fast_amplitude(series: &[Vec<f64>], nd: usize, n_ord: usize, fast: f64, ln_fact: f64) -> f64 {
    let last = norm(&(0..nd).map(|i| series[i][n_ord]).collect::<Vec<_>>());
    if last == 0.0 || fast == 0.0 {
        return 0.0;
    }
    (last.ln() + ln_fact - n_ord as f64 * fast.ln()).exp()
}

/// max_i sum_j |A_ij|, A = dv/du at the loaded point (J factorized there).
fn jacobian_size<P: DaeProblem + ?Sized>(eng: &mut Engine<P>) -> f64 {
    let (a, _) = ode_jacobian(eng);
    row_sum_norm(&a, eng.nd)
}

/// max_i sum_j |A_ij| of an nd × nd row-major matrix.
fn row_sum_norm(a: &[f64], nd: usize) -> f64 {
    (0..nd)
        .map(|i| (0..nd).map(|j| a[i * nd + j].abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// d(v, z)/du = -J^-1 F_u at the loaded point (J already in `eng.lu`):
/// returns A = dv/du (nd × nd, row-major) and d(v, z)/du (n × nd, row-major).
fn ode_jacobian<P: DaeProblem + ?Sized>(eng: &mut Engine<P>) -> (Vec<f64>, Vec<f64>) {
    let (nd, n) = (eng.nd, eng.n());
    // The tangents alone: no lists, nothing allocated.
    eng.tape
        .update_dense_tangents(&eng.u_cols, &mut eng.u_tangents);
    let mut dvz = vec![0.0; n * nd];
    let mut col = vec![0.0; n];
    for j in 0..nd {
        for (r, c) in col.iter_mut().enumerate() {
            *c = -eng.tape.jacobian_entry(&eng.u_tangents, r, j);
        }
        if !eng.lu.solve_in_place(&mut col) {
            col.fill(f64::NAN);
        }
        eng.stats.solves += 1;
        for r in 0..n {
            dvz[r * nd + j] = col[r];
        }
    }
    (dvz[..nd * nd].to_vec(), dvz)
}

/// What an (I2) solve is for: a step's end, whose series the next step
/// and the dense output read, or an output time, whose value and first
/// derivative alone are kept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Target {
    StepEnd,
    OutputTime,
}

/// Solves (I2) for a step of length h. Returns the series (order n) at
/// t0 + h and the error ratio (accept at ≤ 1).
#[allow(clippy::too_many_arguments)]
fn attempt<P: DaeProblem + ?Sized>(
    eng: &mut Engine<P>,
    ch: &mut Chooser,
    u0: &[f64],
    vz0: &[f64],
    t0: f64,
    h: f64,
    (m, n): (usize, usize),
    index: usize,
    cfg: &DaeConfig,
    series0: &[Vec<f64>],
    guess: Option<&[f64]>,
    target: Target,
) -> Result<(Vec<Vec<f64>>, f64)> {
    let nd = eng.nd;
    let t1 = t0 + h;
    // The weights γ (once per run) and the powers of h and -h (once per
    // try): the same values as computed in place.
    let gw = *ch.gammas(m, n);
    let w = Powers::new(m.max(n), h);
    // Right side of (I2): sum_j γ(m, n, j) u0_j h^j.
    let rhs: Vec<f64> = (0..nd)
        .map(|i| (0..=m).map(|j| gw.mn[j] * series0[i][j] * w.h[j]).sum())
        .collect();
    // Predictor: the series at t0 summed up to its smallest term (orders
    // 1..=m, the first local minimum of |u_j| h^j over the differential
    // unknowns), the optimal truncation of a series used beyond its radius:
    // past it the terms grow with the fast mode's (h |A|)^j. The tangent
    // alone (order 1) left the iteration outside its basin at twice the
    // step, so steps grew by 2 and fell back by 4 (friction-plane, zeta =
    // 1e-4 N: 1,129 steps, accepted with error ratios ~1e-6; 179 with this
    // predictor, README "Stiffness in time").
    // A given guess (y at t0 + h) replaces it.
    let term = |j: usize| norm(&(0..nd).map(|i| series0[i][j] * w.h[j]).collect::<Vec<_>>());
    let mut order = 1;
    while order < m && term(order + 1) < term(order) {
        order += 1;
    }
    let increment = |c: &[f64]| -> f64 {
        (1..=order.min(c.len() - 1))
            .map(|j| c[j] * w.h[j])
            .sum::<f64>()
    };
    let mut u1: Vec<f64> = (0..nd).map(|i| u0[i] + increment(&series0[i])).collect();
    let mut vz1: Vec<f64> = (0..vz0.len())
        .map(|k| vz0[k] + increment(&series0[nd + k]))
        .collect();
    if let Some(y) = guess {
        u1.copy_from_slice(&y[..nd]);
        vz1.copy_from_slice(&y[nd..]);
    }
    onto_slow_manifold(eng, &mut u1, &mut vz1, t1, h, cfg.newton_tol, index);
    let mut mat = vec![0.0; nd * nd];
    // |M| of the linear case (the first matrix), for G's round-off floor.
    let mut lin_norm = 0.0;
    let mut dvz = Vec::new();
    // A = dv/du at the first iterate.
    let mut a: Vec<f64> = Vec::new();
    let mut lu = DenseLu::default();
    let mut last: Option<(Vec<f64>, Vec<f64>)> = None;
    // The iterate's series and its G (reused).
    let mut s = Vec::new();
    let mut r = vec![0.0; nd];
    let first_h = first_increment(series0, nd, h);
    // The next update, computed before the convergence test.
    let mut next = vec![0.0; nd];
    for _ in 0..MAX_ITERATIONS {
        eng.newton(&u1, &mut vz1, t1, cfg.newton_tol, index)?;
        solve_series(eng, &u1, &vz1, t1, index, n)?;
        copy_series(eng, &mut s);
        ch.iterations += 1;
        // G(u1) of (I2), and the magnitude of its terms (its round-off floor).
        let mut mag = 0.0f64;
        for i in 0..nd {
            let terms = (0..=n).map(|j| gw.nm[j] * s[i][j] * w.minus_h[j]);
            r[i] = terms.clone().sum::<f64>() - rhs[i];
            mag = mag.max(terms.map(f64::abs).sum::<f64>());
        }
        // Scale of the local error: the first-order increment, or |u1|
        // itself when u barely moves (a relative tolerance per step). The
        // increment is the step start's, on the slow manifold: the
        // iterate's own velocity would widen its own tests where it is
        // off the manifold (friction-roller, ζ = 1e-6 N, ω = 1e-4, order
        // 20, eps 1e-8: an end at t = 0.1808 s with v = −2.4e-2 rad/s
        // against −1.8e-4 on the manifold passed its fast-amplitude test
        // at 0.95 of the tolerance that this velocity set).
        let scale = first_h.max(norm(&u1));
        let tol = (0.1 * cfg.eps * scale).max(16.0 * f64::EPSILON * mag);
        // The last update moved u1 by round-off only: G is at its floor
        // (if within 1e3 of the tolerance; otherwise the iteration failed).
        let stalled = last
            .as_ref()
            .is_some_and(|(du, _)| norm(du) <= 4.0 * f64::EPSILON * norm(&u1));
        if a.is_empty() {
            let (a1, d) = ode_jacobian(eng);
            dvz = d;
            mat = two_point_matrix(&a1, nd, h, n, m);
            lin_norm = row_sum_norm(&mat, nd);
            a = a1;
        }
        let mut converged = norm(&r) <= tol || stalled;
        // The next update (quasi-Newton, Broyden-corrected), computed before
        // the test at an output time: one that would move u1 by round-off
        // only ends the iteration here, at the point whose series is at
        // hand, instead of after one more series to see the stall.
        let mut pending = false;
        if !converged {
            if !r.iter().all(|x| x.is_finite()) {
                break;
            }
            if let Some((du, r_old)) = &last {
                broyden(&mut mat, du, &r, r_old, nd);
            }
            lu.factorize(nd, |i, j| mat[i * nd + j]);
            for (d, x) in next.iter_mut().zip(&r) {
                *d = -x;
            }
            if !lu.solve_in_place(&mut next) || !next.iter().all(|x| x.is_finite()) {
                break;
            }
            // ... and only where G itself is at its round-off floor,
            // ε |u1| |M| (M that of the linear case): a quasi-Newton update
            // can vanish at a point off the root.
            let round_off = f64::EPSILON * norm(&u1);
            converged = target == Target::OutputTime
                && norm(&next) <= 4.0 * round_off
                && norm(&r) <= (16.0 * round_off * lin_norm).max(tol);
            pending = true;
        }
        if converged {
            // Local error: u1 against the [m-1/n] formula (order m + n - 1,
            // also L-stable), err = |M'^-1 G'(u1)| with M' its matrix of the
            // linear case. Fast modes enter G' as in G, damped by M'.
            let mut g = vec![0.0; nd];
            for i in 0..nd {
                g[i] = (0..=n)
                    .map(|j| gw.nm1[j] * s[i][j] * w.minus_h[j])
                    .sum::<f64>()
                    - (0..m)
                        .map(|j| gw.m1n[j] * series0[i][j] * w.h[j])
                        .sum::<f64>();
            }
            let mp = two_point_matrix(&a, nd, h, n, m - 1);
            lu.factorize(nd, |i, j| mp[i * nd + j]);
            if !lu.solve_in_place(&mut g) {
                g.fill(f64::INFINITY);
            }
            let err = norm(&g);
            let mut ratio = if err == 0.0 {
                0.0
            } else {
                err / (cfg.eps * scale + f64::MIN_POSITIVE)
            };
            // The end must lie on the slow manifold: a fast amplitude left at
            // t1 (the one that the step-start test calls a transient) means
            // the iteration stopped at a point (I2) does not pin down. That
            // happens when it stalls at a G inflated by the fast terms of an
            // off-manifold iterate (ζ = 1e-6 N on friction-plane: end
            // amplitude 2.5e-11 against 1e-26 on accepted steps, v_x 150
            // times the slow velocity, a wrong Hermite interpolant inside).
            let d1 = fast_amplitude(&s, nd, n, row_sum_norm(&a, nd), ch.ln_factorial(n));
            ratio = ratio.max(d1 / (cfg.eps * scale + f64::MIN_POSITIVE));
            // The algebraic unknowns (and velocities) that the fast mode does
            // not reach: the same formula defect on their own series, so that
            // an event only they feel (a contact closing) is not stepped over.
            // Trusted where their fast content, |d y_k/du| δ (h |A|)^(m-1),
            // is below 0.1 eps of their scale, δ the uncertainty of u1: its
            // round-off ε |u1|, or the iteration's last update if larger. (With
            // ε |u1| alone, an iteration stopped by |G| ≤ tol at a loose eps
            // left u1 uncertain by far more, the defect of a velocity measured
            // that, and every implicit try failed: friction-plane at ζ = ω =
            // 1e-4 N, eps 1e-6 took 24,625 explicit steps, now 108.)
            let x = h * row_sum_norm(&a, nd);
            let uncertainty = last
                .as_ref()
                .map_or(0.0, |(du, _)| norm(du))
                .max(if pending { norm(&next) } else { 0.0 })
                .max(f64::EPSILON * norm(&u1));
            for k in 0..s.len() - nd {
                let y = &s[nd + k];
                let y0 = &series0[nd + k];
                let scale_k = (y[1] * h).abs().max(y[0].abs());
                let coupling: f64 = (0..nd).map(|j| dvz[k * nd + j].abs()).sum();
                let fast = coupling * uncertainty * x.powi(m as i32 - 1);
                if !(fast <= 0.1 * cfg.eps * scale_k) {
                    continue;
                }
                let defect = (0..=n)
                    .map(|j| gw.nm1[j] * y[j] * w.minus_h[j])
                    .sum::<f64>()
                    - (0..m).map(|j| gw.m1n[j] * y0[j] * w.h[j]).sum::<f64>();
                ratio = ratio.max(defect.abs() / (cfg.eps * scale_k + f64::MIN_POSITIVE));
            }
            return Ok((s, ratio));
        }
        // Δu and G of this iterate into the previous one's vectors.
        let (du, r_old) = last.get_or_insert_with(|| (vec![0.0; nd], vec![0.0; nd]));
        du.copy_from_slice(&next);
        for i in 0..nd {
            u1[i] += du[i];
        }
        // Linear prediction of the consistent (v, z) for the next iterate.
        for (k, x) in vz1.iter_mut().enumerate() {
            *x += (0..nd).map(|j| dvz[k * nd + j] * du[j]).sum::<f64>();
        }
        r_old.copy_from_slice(&r);
    }
    Err(Error::NoConvergence {
        step: index,
        param: "t",
        at: t1,
        iterations: MAX_ITERATIONS,
        residual: f64::NAN,
        tolerance: cfg.eps,
    })
}

/// The first-order increment of the differential unknowns over h, |u_1| h,
/// from the step start's series: with |u| (when u barely moves), the scale
/// of a step's local error.
fn first_increment(series0: &[Vec<f64>], nd: usize, h: f64) -> f64 {
    norm(&series0[..nd].iter().map(|c| c[1]).collect::<Vec<_>>()) * h
}

/// An output time inside an implicit step from the Hermite guess itself,
/// without solving (I2) there: where the guess's positions u agree with
/// the interpolant of one order more at both ends (`finer`) to the step's
/// own tolerance, eps max(|u_1| h, |u|) (the test of [`attempt`], on that
/// difference as the error estimate), (v, z) are solved consistent with u
/// at t and dy/dt read from their series of order 1, as a DAE's dense
/// output does. The difference also holds the fast content of both
/// interpolants, ~ d (h |A|)^k / k! for an end amplitude d, larger in the
/// finer one, so a guess that carries the fast mode is not taken.
/// Measured against the points (I2) solves (friction-plane and -roller,
/// ω = 1e-4, ζ = 1e-2 and 1e-6 N): 6–52% of the output times pass, and of
/// those 1 in 108 is further from the solved point than the tolerance
/// (1.19 of it, estimated at 0.74).
/// None where the test fails or the consistent (v, z) is not found.
fn hermite_point<P: DaeProblem + ?Sized>(
    eng: &mut Engine<P>,
    series0: &[Vec<f64>],
    finer: &[Vec<f64>],
    guess: &[f64],
    (t, h, s): (f64, f64, f64),
    index: usize,
    cfg: &DaeConfig,
) -> Option<(f64, Vec<f64>, Vec<f64>)> {
    let nd = eng.nd;
    let u = &guess[..nd];
    let scale = first_increment(series0, nd, h).max(norm(u));
    let estimate = norm(
        &(0..nd)
            .map(|i| guess[i] - crate::series::taylor::eval(&finer[i], s))
            .collect::<Vec<_>>(),
    );
    if !(estimate <= cfg.eps * scale) {
        return None;
    }
    consistent_point(eng, u, &guess[nd..], t, index, cfg)
}

/// Broyden's update of the quasi-Newton matrix after the step `du` that
/// changed G from `r_old` to `r`: M += (ΔG − M Δu) Δuᵀ / (Δuᵀ Δu).
fn broyden(mat: &mut [f64], du: &[f64], r: &[f64], r_old: &[f64], nd: usize) {
    let dd: f64 = du.iter().map(|x| x * x).sum();
    if dd > 0.0 {
        for i in 0..nd {
            let mdu: f64 = (0..nd).map(|k| mat[i * nd + k] * du[k]).sum();
            let y = r[i] - r_old[i] - mdu;
            for j in 0..nd {
                mat[i * nd + j] += y * du[j] / dd;
            }
        }
    }
}

/// Moves the predicted u1 (with its predicted (v, z) in `vz1`) toward the
/// slow manifold: one Newton step on v(u1) = v_pred in the stiff directions,
///   (I + h² AᵀA) Δu = h² Aᵀ (v_pred − v(u1)),   A = dv/du at u1,
/// i.e. Δu ≈ A^-1 (v_pred − v) where h |A| ≫ 1 and Δu ≈ 0 where h |A| ≪ 1.
/// Why: near a slow manifold v = u' is slow and the series at t0 predicts
/// it about as well, relatively, as it predicts u; but an error δ in u1
/// moves the consistent v by A δ, far into the friction law's nonlinear
/// range (friction-plane, ζ = ω = 1e-4 N, h = 0.068 s: the predicted u1 was
/// 2e-8 m off, its consistent v 0.044 m/s against 2.1e-4 on the manifold,
/// with ω Vc = 1e-4 m/s), and the quasi-Newton iteration on (I2) spent its
/// first 3–4 iterations getting back. Taking v from the prediction and u
/// from the law puts the iterate within v_pred's error / |A| of the
/// manifold. Costs one consistent initialization and nd solves; where that
/// initialization fails, or Δu is not finite, the prediction is kept.
fn onto_slow_manifold<P: DaeProblem + ?Sized>(
    eng: &mut Engine<P>,
    u1: &mut [f64],
    vz1: &mut [f64],
    t1: f64,
    h: f64,
    newton_tol: f64,
    index: usize,
) {
    let nd = eng.nd;
    let predicted = vz1.to_vec();
    if eng.newton(u1, vz1, t1, newton_tol, index).is_err() {
        vz1.copy_from_slice(&predicted);
        return;
    }
    let (a, dvz) = ode_jacobian(eng);
    let mut lhs = identity(nd);
    let mut du = vec![0.0; nd];
    for i in 0..nd {
        for j in 0..nd {
            lhs[i * nd + j] += h * h * (0..nd).map(|k| a[k * nd + i] * a[k * nd + j]).sum::<f64>();
        }
        du[i] = h
            * h
            * (0..nd)
                .map(|k| a[k * nd + i] * (predicted[k] - vz1[k]))
                .sum::<f64>();
    }
    let mut lu = DenseLu::default();
    lu.factorize(nd, |i, j| lhs[i * nd + j]);
    if !lu.solve_in_place(&mut du) || !du.iter().all(|x| x.is_finite()) {
        return;
    }
    for (u, d) in u1.iter_mut().zip(&du) {
        *u += d;
    }
    // Linear prediction of the consistent (v, z) at the moved u1.
    for (k, x) in vz1.iter_mut().enumerate() {
        *x += (0..nd).map(|j| dvz[k * nd + j] * du[j]).sum::<f64>();
    }
}

/// Dense output of an implicit step: per unknown, the two-point Hermite
/// interpolant in s = (t - t0)/h of degree k0 + k1 + 1 matching the Taylor
/// coefficients of orders 0..k0 at t0 and 0..k1 at t0 + h (monomial
/// coefficients in s). Inside a stiff step the high orders carry the fast
/// mode's amplitude times (h |A|)^k: the caller takes k = 1 there. Used
/// between the output times, which (I2) solves for itself.
#[cfg(test)]
fn hermite_data(y0: &[Vec<f64>], y1: &[Vec<f64>], h: f64, k0: usize, k1: usize) -> Vec<Vec<f64>> {
    hermite_solve(&hermite_matrix(k0, k1), y0, y1, h, k0, k1)
}

/// The LU of the matrix of [`hermite_data`]: rows 0..=k0: P^(j)(0)/j! =
/// c_j; the next k1 + 1 rows: P^(j)(1)/j! = sum_i C(i, j) c_i.
fn hermite_matrix(k0: usize, k1: usize) -> DenseLu {
    let mut lu = DenseLu::default();
    lu.factorize(k0 + k1 + 2, |r, c| {
        if r <= k0 {
            f64::from(u8::from(r == c))
        } else {
            binomial(c, r - k0 - 1)
        }
    });
    lu
}

/// [`hermite_data`] with the matrix's LU given.
fn hermite_solve(
    lu: &DenseLu,
    y0: &[Vec<f64>],
    y1: &[Vec<f64>],
    h: f64,
    k0: usize,
    k1: usize,
) -> Vec<Vec<f64>> {
    let powers: Vec<f64> = (0..=k0.max(k1)).map(|j| h.powi(j as i32)).collect();
    y0.iter()
        .zip(y1)
        .map(|(a, b)| {
            let mut rhs: Vec<f64> = (0..=k0)
                .map(|j| a[j] * powers[j])
                .chain((0..=k1).map(|j| b[j] * powers[j]))
                .collect();
            lu.solve_in_place(&mut rhs);
            rhs
        })
        .collect()
}

/// dG/du1 of (I2) [m/n] in the linear case y' = A y, whose Taylor
/// coefficients at t1 are u1_j = A^j u1 / j!: sum_j γ(n, m, j) (-h A)^j / j!
/// (nd × nd, row-major), by Horner. (Without the 1/j! the fast direction's
/// entry was n! = 720 times too large: the first quasi-Newton update of a
/// stiff step moved u1 by about 1/720 of the way and the Broyden updates
/// made up for it in 1–2 more iterations; and the error estimate
/// M'^-1 G' was damped up to 6! = 720 times too much in the fast direction.)
fn two_point_matrix(a: &[f64], nd: usize, h: f64, n: usize, m: usize) -> Vec<f64> {
    let mut mat = identity(nd);
    // Horner's partial products alternate between two matrices.
    let mut next = identity(nd);
    for p in (1..=n).rev() {
        next.fill(0.0);
        for i in 0..nd {
            next[i * nd + i] = 1.0;
        }
        let c = -h * gamma(n, m, p) / (gamma(n, m, p - 1) * p as f64);
        for i in 0..nd {
            for j in 0..nd {
                let acc: f64 = (0..nd).map(|k| a[i * nd + k] * mat[k * nd + j]).sum();
                next[i * nd + j] += c * acc;
            }
        }
        std::mem::swap(&mut mat, &mut next);
    }
    mat
}

/// The weights γ of (I2) [m/n] and of its error estimate [m-1/n],
/// j = 0..=max(m, n) (each γ is a product of up to n quotients; m, n are at
/// most HO_M, HO_N).
#[derive(Clone, Copy, Debug)]
struct Gammas {
    m: usize,
    n: usize,
    mn: [f64; HO_N + 1],
    nm: [f64; HO_N + 1],
    m1n: [f64; HO_N + 1],
    nm1: [f64; HO_N + 1],
}

impl Gammas {
    fn new(m: usize, n: usize) -> Self {
        let table = |a: usize, b: usize| std::array::from_fn(|j| gamma(a, b, j));
        Self {
            m,
            n,
            mn: table(m, n),
            nm: table(n, m),
            m1n: table(m.saturating_sub(1), n),
            nm1: table(n, m.saturating_sub(1)),
        }
    }
}

/// h^j and (-h)^j, j = 0..=max(m, n).
struct Powers {
    h: Vec<f64>,
    minus_h: Vec<f64>,
}

impl Powers {
    fn new(top: usize, h: f64) -> Self {
        Self {
            h: (0..=top).map(|j| h.powi(j as i32)).collect(),
            minus_h: (0..=top).map(|j| (-h).powi(j as i32)).collect(),
        }
    }
}

/// C(i, j) (0 when j > i).
fn binomial(i: usize, j: usize) -> f64 {
    if j > i {
        return 0.0;
    }
    (0..j).map(|l| (i - l) as f64 / (j - l) as f64).product()
}

fn identity(n: usize) -> Vec<f64> {
    let mut m = vec![0.0; n * n];
    for i in 0..n {
        m[i * n + i] = 1.0;
    }
    m
}

/// γ(m, n, j) = m! (m + n - j)! / ((m + n)! (m - j)!), the weight of u_j h^j
/// (Taylor coefficients) in the Hermite–Obreshkov [m/n] formula (I2).
fn gamma(m: usize, n: usize, j: usize) -> f64 {
    if j > m {
        return 0.0;
    }
    (0..j)
        .map(|i| (m - i) as f64 / (m + n - i) as f64)
        .product()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_point_weights_give_the_pade_approximant_of_exp() {
        // On y' = λ y the formula gives y1/y0 = P_m(z)/Q_n(-z), the [m/n]
        // Padé approximant of e^z (z = λ h): compare at z = -0.3.
        let (m, n) = (5usize, 6usize);
        let fact = |k: usize| (1..=k).map(|x| x as f64).product::<f64>();
        let r = |z: f64| {
            let p: f64 = (0..=m)
                .map(|j| gamma(m, n, j) * z.powi(j as i32) / fact(j))
                .sum();
            let q: f64 = (0..=n)
                .map(|j| gamma(n, m, j) * (-z).powi(j as i32) / fact(j))
                .sum();
            p / q
        };
        let z = -0.3f64;
        assert!((r(z) - z.exp()).abs() < 1e-13, "{} vs {}", r(z), z.exp());
        // L-stable: |R(z)| -> 0 as z -> -inf (degree m < n).
        assert!(r(-1e8).abs() < 1e-7);
    }

    #[test]
    fn two_point_matrix_is_the_jacobian_of_the_linear_case() {
        // y' = A y: u1_j = A^j u1 / j!, so dG/du1 = sum_j γ(n, m, j) (-h A)^j / j!,
        // summed here from explicit powers of a non-normal 2 × 2 A.
        let (m, n, h) = (5usize, 6usize, 0.7f64);
        let a = [-3.0, 1.5, 0.25, -40.0];
        let mul = |x: &[f64], y: &[f64]| -> Vec<f64> {
            (0..4)
                .map(|k| (0..2).map(|l| x[(k / 2) * 2 + l] * y[l * 2 + k % 2]).sum())
                .collect()
        };
        let mut power = identity(2);
        let mut want = vec![0.0; 4];
        let mut fact = 1.0;
        for j in 0..=n {
            if j > 0 {
                power = mul(&power, &a);
                fact *= j as f64;
            }
            let w = gamma(n, m, j) * (-h).powi(j as i32) / fact;
            for (x, p) in want.iter_mut().zip(&power) {
                *x += w * p;
            }
        }
        let got = two_point_matrix(&a, 2, h, n, m);
        for (g, w) in got.iter().zip(&want) {
            assert!(
                (g - w).abs() <= 1e-12 * w.abs().max(1.0),
                "{got:?} vs {want:?}"
            );
        }
        // The scalar case is the denominator Q_n(-z) of the Padé approximant.
        let z: f64 = -30.0;
        let q: f64 = (0..=n)
            .map(|j| {
                gamma(n, m, j) * (-z).powi(j as i32) / (1..=j).map(|x| x as f64).product::<f64>()
            })
            .sum();
        let got = two_point_matrix(&[z], 1, 1.0, n, m)[0];
        assert!((got - q).abs() <= 1e-12 * q.abs(), "{got} vs {q}");
    }

    #[test]
    fn hermite_data_interpolates_a_polynomial() {
        // y = 1 + 2t - t^3 on [0.5, 0.7]: Taylor coefficients at both ends.
        let coeffs = |t: f64| vec![1.0 + 2.0 * t - t.powi(3), 2.0 - 3.0 * t * t, -3.0 * t, -1.0];
        let (t0, h) = (0.5, 0.2);
        let c = hermite_data(&[coeffs(t0)], &[coeffs(t0 + h)], h, 1, 1);
        for s in [0.0, 0.3, 1.0] {
            let t = t0 + s * h;
            let got = crate::series::taylor::eval(&c[0], s);
            assert!(
                (got - (1.0 + 2.0 * t - t.powi(3))).abs() < 1e-14,
                "{s}: {got}"
            );
        }
        // Orders 0..1 at t0 and 0..2 at t0 + h (degree 4): exact on
        // y = t^4 - t^3, not on y = t^5.
        let quartic = |t: f64| {
            vec![
                t.powi(4) - t.powi(3),
                4.0 * t.powi(3) - 3.0 * t * t,
                6.0 * t * t - 3.0 * t,
            ]
        };
        let quintic = |t: f64| vec![t.powi(5), 5.0 * t.powi(4), 10.0 * t.powi(3)];
        let c = hermite_data(
            &[quartic(t0), quintic(t0)],
            &[quartic(t0 + h), quintic(t0 + h)],
            h,
            1,
            2,
        );
        let t = t0 + 0.4 * h;
        let got = crate::series::taylor::eval(&c[0], 0.4);
        assert!((got - (t.powi(4) - t.powi(3))).abs() < 1e-15, "{got}");
        let got = crate::series::taylor::eval(&c[1], 0.4);
        assert!((got - t.powi(5)).abs() > 1e-7, "{got}");
    }
}
