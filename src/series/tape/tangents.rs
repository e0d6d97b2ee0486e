//! Order-0 derivatives of a tape: forward tangents of every node with respect
//! to chosen inputs, the dense Jacobian they hold, and the exact linear update
//! of an order's coefficients they allow ([`Tape::add_to_order`]).

use super::{Op, Tape};

/// d node / d input at the order-0 point for some input columns
/// ([`Tape::node_tangents`]).
#[derive(Clone, Debug, Default)]
pub struct Tangents {
    n_cols: usize,
    /// d node i / d column j at `i * n_cols + j`.
    dense: Vec<f64>,
    /// Per column, the nodes with a nonzero tangent (as the offset of their
    /// series in the tape's storage) and that tangent, in node order: most
    /// nodes do not depend on a given unknown.
    nonzero: Vec<Vec<(usize, f64)>>,
    /// Whether `nonzero` belongs to `dense` ([`Tape::update_dense_tangents`]
    /// leaves it stale).
    lists: bool,
}

impl Tangents {
    pub fn n_cols(&self) -> usize {
        self.n_cols
    }
    /// d node / d column j.
    pub fn get(&self, node: usize, j: usize) -> f64 {
        self.dense[node * self.n_cols + j]
    }
}

impl Tape {
    /// Directional derivative of the outputs at the order-0 point (forward
    /// tangent pass on the stored constant terms): returns J * `dx`.
    pub fn jvp(&self, dx: &[f64]) -> Vec<f64> {
        let mut dot = vec![0.0; self.ops.len()];
        self.tangent_pass(1, |input, _| dx[input], &mut dot);
        self.outputs.iter().map(|&o| dot[o]).collect()
    }

    /// d node / d inputs[col] at the order-0 point, for every node and each
    /// of `cols`.
    pub fn node_tangents(&self, cols: &[usize]) -> Tangents {
        let mut t = Tangents::default();
        self.update_tangents(cols, &mut t);
        t
    }

    /// [`Tape::node_tangents`] into `t`, reusing its storage (once per step).
    pub fn update_tangents(&self, cols: &[usize], t: &mut Tangents) {
        self.update_dense_tangents(cols, t);
        let k = t.n_cols;
        t.nonzero.resize(k, Vec::new());
        t.nonzero.iter_mut().for_each(Vec::clear);
        let rows = t.dense.chunks_exact(k.max(1));
        for ((i, row), _) in rows.enumerate().zip(&self.read_later).filter(|(_, r)| **r) {
            for (list, &d) in t.nonzero.iter_mut().zip(row) {
                if d != 0.0 {
                    list.push((i * self.stride, d));
                }
            }
        }
        t.lists = true;
    }

    /// The tangents alone, without the per-column lists of
    /// [`Tape::add_to_order`]: enough for a Jacobian (a Newton iterate), and
    /// building the lists costs about as much as the pass (callgrind, friction
    /// grid: 48.7 M against 51.5 M instructions over 31,401 calls).
    pub fn update_dense_tangents(&self, cols: &[usize], t: &mut Tangents) {
        let k = cols.len();
        t.lists = false;
        t.n_cols = k;
        t.dense.resize(self.ops.len() * k, 0.0);
        let seed = |input: usize, j: usize| if cols[j] == input { 1.0 } else { 0.0 };
        // A constant direction count lets the compiler unroll the per-node
        // loops for the usual handful of unknowns.
        match k {
            1 => self.tangent_pass(1, seed, &mut t.dense),
            2 => self.tangent_pass(2, seed, &mut t.dense),
            3 => self.tangent_pass(3, seed, &mut t.dense),
            4 => self.tangent_pass(4, seed, &mut t.dense),
            5 => self.tangent_pass(5, seed, &mut t.dense),
            6 => self.tangent_pass(6, seed, &mut t.dense),
            _ => self.tangent_pass(k, seed, &mut t.dense),
        }
    }

    /// Adds sum_j tangents[j] * x[j] to coefficient p of every node that is
    /// read later (see [`read_later`]).
    ///
    /// Coefficient p of each node is affine in the inputs' coefficients p,
    /// with the order-0 derivatives as slopes (every recurrence of
    /// [`super::taylor`] weights its arguments' top coefficient by the
    /// derivative at order 0). So after propagating order p with some inputs'
    /// coefficient p at zero, setting them to x is this update, exactly.
    pub fn add_to_order(&mut self, p: usize, tangents: &Tangents, x: &[f64]) {
        assert!(tangents.lists, "add_to_order needs the tangents' lists");
        for (list, &xj) in tangents.nonzero.iter().zip(x) {
            if xj == 0.0 {
                continue;
            }
            for &(offset, ti) in list {
                self.coeffs[offset + p] += ti * xj;
            }
        }
    }

    /// Forward tangent pass in `k` directions at once: `out[i * k + j]` =
    /// d node i / d direction j, direction j seeding input m with `dx(m, j)`.
    /// Each node's local derivative (a pow, a cosine) is computed once for
    /// all directions.
    #[inline(always)]
    fn tangent_pass(&self, k: usize, dx: impl Fn(usize, usize) -> f64, out: &mut [f64]) {
        let v = |j: usize| self.coeffs[j * self.stride];
        let mut next_input = 0;
        for (i, op) in self.ops.iter().enumerate() {
            let (before, rest) = out.split_at_mut(i * k);
            let own = &mut rest[..k];
            let d = |a: usize| &before[a * k..(a + 1) * k];
            match *op {
                Op::Input => {
                    for (j, o) in own.iter_mut().enumerate() {
                        *o = dx(next_input, j);
                    }
                    next_input += 1;
                }
                Op::Const(_) => own.fill(0.0),
                Op::Add(a, b) => each2(own, d(a), d(b), |x, y| x + y),
                Op::Sub(a, b) => each2(own, d(a), d(b), |x, y| x - y),
                Op::Mul(a, b) => {
                    let (va, vb) = (v(a), v(b));
                    each2(own, d(a), d(b), |x, y| x * vb + va * y)
                }
                Op::Div(a, b) => {
                    let (vi, vb) = (v(i), v(b));
                    each2(own, d(a), d(b), |x, y| (x - vi * y) / vb)
                }
                Op::Neg(a) => each(own, d(a), |x| -x),
                Op::Scale(a, c) => each(own, d(a), |x| c * x),
                Op::Offset(a, _) => each(own, d(a), |x| x),
                Op::Sqrt(a) => {
                    let den = 2.0 * v(i);
                    each(own, d(a), |x| x / den)
                }
                Op::Powf(a, alpha) => {
                    let slope = alpha * v(a).powf(alpha - 1.0);
                    each(own, d(a), |x| slope * x)
                }
                Op::Exp(a) => {
                    let vi = v(i);
                    each(own, d(a), |x| vi * x)
                }
                Op::Sin(a) => {
                    let slope = v(a).cos();
                    each(own, d(a), |x| slope * x)
                }
                Op::CosOfPrevious => match self.ops[i - 1] {
                    Op::Sin(a) => {
                        let slope = -v(a).sin();
                        each(own, d(a), |x| slope * x)
                    }
                    _ => unreachable!("a cosine node always follows its sine"),
                },
            }
        }
    }

    /// Dense Jacobian d outputs / d inputs[cols] at the order-0 point, row-major.
    pub fn jacobian(&self, cols: &[usize]) -> Vec<Vec<f64>> {
        let t = self.node_tangents(cols);
        (0..self.n_outputs())
            .map(|r| {
                (0..t.n_cols())
                    .map(|c| self.jacobian_entry(&t, r, c))
                    .collect()
            })
            .collect()
    }

    /// d output[row] / d cols[col] read off node tangents.
    pub fn jacobian_entry(&self, tangents: &Tangents, row: usize, col: usize) -> f64 {
        tangents.get(self.outputs[row], col)
    }
}

/// The nodes whose coefficient p is read once order p has been propagated:
/// inputs and outputs (the series and the residual), the arguments of the
/// nonlinear operations (their recurrences read every lower coefficient of
/// their arguments) and the nonlinear operations that read their own.
/// Anything else (a linear node feeding only linear nodes) has its
/// coefficient p read by order p's propagation alone, so the linear update
/// may skip it.
pub(super) fn read_later(ops: &[Op], inputs: &[usize], outputs: &[usize]) -> Vec<bool> {
    let mut read = vec![false; ops.len()];
    for &i in inputs.iter().chain(outputs) {
        read[i] = true;
    }
    for (i, op) in ops.iter().enumerate() {
        match *op {
            Op::Mul(a, b) => {
                read[a] = true;
                read[b] = true;
            }
            Op::Div(a, b) => {
                read[a] = true;
                read[b] = true;
                read[i] = true;
            }
            Op::Sqrt(a) | Op::Powf(a, _) | Op::Exp(a) | Op::Sin(a) => {
                read[a] = true;
                read[i] = true;
            }
            Op::CosOfPrevious => read[i] = true,
            Op::Input
            | Op::Const(_)
            | Op::Add(..)
            | Op::Sub(..)
            | Op::Neg(_)
            | Op::Scale(..)
            | Op::Offset(..) => {}
        }
    }
    read
}

fn each(own: &mut [f64], a: &[f64], f: impl Fn(f64) -> f64) {
    for (o, &x) in own.iter_mut().zip(a) {
        *o = f(x);
    }
}

fn each2(own: &mut [f64], a: &[f64], b: &[f64], f: impl Fn(f64, f64) -> f64) {
    for ((o, &x), &y) in own.iter_mut().zip(a).zip(b) {
        *o = f(x, y);
    }
}
