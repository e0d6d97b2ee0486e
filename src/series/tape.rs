//! A recorded expression ("tape") whose every intermediate keeps its series.
//!
//! A problem writes its residual once with [`Var`] arithmetic; the tape then
//! propagates Taylor coefficients order by order (coefficient p of each node
//! from coefficients `0..=p` of its arguments, [`super::taylor`]), so the
//! order-p right-hand side of the ANM costs O(p) per operation and nothing is
//! re-evaluated. The same tape gives the order-0 Jacobian by a forward tangent
//! pass (exact, no finite differences) and plain f64 evaluation (order 0).

use super::taylor;
use std::cell::RefCell;
use std::ops::{Add, Div, Mul, Neg, Sub};

mod tangents;
pub use tangents::Tangents;

#[derive(Clone, Copy, Debug)]
enum Op {
    Input,
    Const(f64),
    Add(usize, usize),
    Sub(usize, usize),
    Mul(usize, usize),
    Div(usize, usize),
    Neg(usize),
    Scale(usize, f64),
    Offset(usize, f64),
    Sqrt(usize),
    Powf(usize, f64),
    Exp(usize),
    /// sin of the argument; the next node holds its cosine ([`Op::CosOfPrevious`]).
    Sin(usize),
    CosOfPrevious,
}

/// Records operations; [`TapeBuilder::finish`] turns the record into a [`Tape`].
#[derive(Default)]
pub struct TapeBuilder {
    ops: RefCell<Vec<Op>>,
    inputs: RefCell<Vec<usize>>,
}

/// A node of the expression being recorded.
#[derive(Clone, Copy)]
pub struct Var<'a> {
    id: usize,
    builder: &'a TapeBuilder,
}

impl TapeBuilder {
    pub fn new() -> Self {
        Self::default()
    }

    fn push(&self, op: Op) -> Var<'_> {
        let mut ops = self.ops.borrow_mut();
        ops.push(op);
        Var {
            id: ops.len() - 1,
            builder: self,
        }
    }

    /// A new independent variable; inputs are numbered in creation order.
    pub fn input(&self) -> Var<'_> {
        let v = self.push(Op::Input);
        self.inputs.borrow_mut().push(v.id);
        v
    }

    /// `n` new independent variables.
    pub fn inputs(&self, n: usize) -> Vec<Var<'_>> {
        (0..n).map(|_| self.input()).collect()
    }

    pub fn constant(&self, c: f64) -> Var<'_> {
        self.push(Op::Const(c))
    }

    /// Freezes the record with the given outputs.
    pub fn finish(&self, outputs: &[Var<'_>], order: usize) -> Tape {
        let outputs: Vec<usize> = outputs.iter().map(|v| v.id).collect();
        let ops = self.ops.borrow().clone();
        let inputs = self.inputs.borrow().clone();
        let stride = order + 1;
        Tape {
            coeffs: vec![0.0; ops.len() * stride],
            read_later: tangents::read_later(&ops, &inputs, &outputs),
            code: compile(&ops, stride, true),
            code_high: compile(&ops, stride, false),
            ops,
            inputs,
            outputs,
            stride,
        }
    }
}

impl<'a> Var<'a> {
    fn un(self, op: Op) -> Var<'a> {
        self.builder.push(op)
    }
    pub fn sqrt(self) -> Var<'a> {
        self.un(Op::Sqrt(self.id))
    }
    /// `self^alpha`; the order-0 value must be positive.
    pub fn powf(self, alpha: f64) -> Var<'a> {
        self.un(Op::Powf(self.id, alpha))
    }
    pub fn exp(self) -> Var<'a> {
        self.un(Op::Exp(self.id))
    }
    /// `(sin self, cos self)`, propagated together.
    pub fn sin_cos(self) -> (Var<'a>, Var<'a>) {
        let s = self.un(Op::Sin(self.id));
        let c = self.un(Op::CosOfPrevious);
        (s, c)
    }
    pub fn square(self) -> Var<'a> {
        self * self
    }
}

macro_rules! binary_op {
    ($trait:ident, $method:ident, $op:ident, $scalar_rhs:expr, $scalar_lhs:expr) => {
        impl<'a> $trait for Var<'a> {
            type Output = Var<'a>;
            fn $method(self, rhs: Var<'a>) -> Var<'a> {
                self.builder.push(Op::$op(self.id, rhs.id))
            }
        }
        impl<'a> $trait<f64> for Var<'a> {
            type Output = Var<'a>;
            fn $method(self, rhs: f64) -> Var<'a> {
                #[allow(clippy::redundant_closure_call)]
                ($scalar_rhs)(self, rhs)
            }
        }
        impl<'a> $trait<Var<'a>> for f64 {
            type Output = Var<'a>;
            fn $method(self, rhs: Var<'a>) -> Var<'a> {
                #[allow(clippy::redundant_closure_call)]
                ($scalar_lhs)(self, rhs)
            }
        }
    };
}

binary_op!(
    Add,
    add,
    Add,
    |a: Var<'a>, c: f64| a.un(Op::Offset(a.id, c)),
    |c: f64, a: Var<'a>| a.un(Op::Offset(a.id, c))
);
binary_op!(
    Sub,
    sub,
    Sub,
    |a: Var<'a>, c: f64| a.un(Op::Offset(a.id, -c)),
    |c: f64, a: Var<'a>| {
        let n = a.un(Op::Neg(a.id));
        n.un(Op::Offset(n.id, c))
    }
);
binary_op!(
    Mul,
    mul,
    Mul,
    |a: Var<'a>, c: f64| a.un(Op::Scale(a.id, c)),
    |c: f64, a: Var<'a>| a.un(Op::Scale(a.id, c))
);
binary_op!(
    Div,
    div,
    Div,
    |a: Var<'a>, c: f64| a.un(Op::Scale(a.id, 1.0 / c)),
    |c: f64, a: Var<'a>| {
        let k = a.builder.constant(c);
        k / a
    }
);

impl<'a> Neg for Var<'a> {
    type Output = Var<'a>;
    fn neg(self) -> Var<'a> {
        self.un(Op::Neg(self.id))
    }
}

/// A frozen expression with the Taylor coefficients of every node, up to a
/// fixed order.
#[derive(Clone, Debug)]
pub struct Tape {
    ops: Vec<Op>,
    inputs: Vec<usize>,
    outputs: Vec<usize>,
    /// Node-major storage: coefficient p of node i at `i * stride + p`.
    coeffs: Vec<f64>,
    stride: usize,
    /// Nodes whose coefficient p is read after order p is propagated (see
    /// [`Tape::add_to_order`]).
    read_later: Vec<bool>,
    /// What [`Tape::propagate`] runs at order 0 and at orders >= 1
    /// ([`compile`]).
    code: Vec<(Op, usize)>,
    code_high: Vec<(Op, usize)>,
}

/// The operations that compute a coefficient, each with its arguments and
/// its own node given as offsets into the storage (node * stride): no
/// index product per operand, and no dispatch for the nodes with nothing
/// to compute (inputs; constants past order 0, whose coefficients stay 0).
/// A sine's entry also computes the cosine after it.
fn compile(ops: &[Op], stride: usize, order0: bool) -> Vec<(Op, usize)> {
    let o = |a: usize| a * stride;
    ops.iter()
        .enumerate()
        .filter_map(|(i, op)| {
            let op = match *op {
                Op::Input | Op::CosOfPrevious => return None,
                Op::Const(_) if !order0 => return None,
                Op::Const(k) => Op::Const(k),
                Op::Add(a, b) => Op::Add(o(a), o(b)),
                Op::Sub(a, b) => Op::Sub(o(a), o(b)),
                Op::Mul(a, b) => Op::Mul(o(a), o(b)),
                Op::Div(a, b) => Op::Div(o(a), o(b)),
                Op::Neg(a) => Op::Neg(o(a)),
                Op::Scale(a, k) => Op::Scale(o(a), k),
                Op::Offset(a, k) => Op::Offset(o(a), k),
                Op::Sqrt(a) => Op::Sqrt(o(a)),
                Op::Powf(a, alpha) => Op::Powf(o(a), alpha),
                Op::Exp(a) => Op::Exp(o(a)),
                Op::Sin(a) => Op::Sin(o(a)),
            };
            Some((op, o(i)))
        })
        .collect()
}

impl Tape {
    pub fn n_inputs(&self) -> usize {
        self.inputs.len()
    }
    pub fn n_outputs(&self) -> usize {
        self.outputs.len()
    }
    /// The highest order stored.
    pub fn order(&self) -> usize {
        self.stride - 1
    }
    pub fn n_nodes(&self) -> usize {
        self.ops.len()
    }

    /// Sets coefficient `p` of input `i`.
    pub fn set_input(&mut self, i: usize, p: usize, value: f64) {
        self.coeffs[self.inputs[i] * self.stride + p] = value;
    }

    pub fn input_series(&self, i: usize) -> &[f64] {
        self.series(self.inputs[i])
    }

    pub fn output_series(&self, j: usize) -> &[f64] {
        self.series(self.outputs[j])
    }

    pub fn output(&self, j: usize, p: usize) -> f64 {
        self.coeffs[self.outputs[j] * self.stride + p]
    }

    fn series(&self, node: usize) -> &[f64] {
        &self.coeffs[node * self.stride..(node + 1) * self.stride]
    }

    /// Computes coefficient `p` of every node from the input coefficients
    /// `0..=p` and the node coefficients `0..p` already stored.
    pub fn propagate(&mut self, p: usize) {
        assert!(
            p < self.stride,
            "order {p} beyond the tape's {}",
            self.stride - 1
        );
        let s = self.stride;
        let code = if p == 0 { &self.code } else { &self.code_high };
        let c = &mut self.coeffs;
        // Coefficients 0..=p of the node at offset o: every recurrence reads
        // its arguments (and its own lower coefficients) before the new
        // value is stored.
        fn upto(c: &[f64], o: usize, p: usize) -> &[f64] {
            &c[o..o + p + 1]
        }
        for &(op, i) in code {
            let value = match op {
                Op::Const(k) => k,
                Op::Add(a, b) => c[a + p] + c[b + p],
                Op::Sub(a, b) => c[a + p] - c[b + p],
                Op::Mul(a, b) => taylor::mul_coeff(upto(c, a, p), upto(c, b, p), p),
                Op::Div(a, b) => taylor::div_coeff(upto(c, a, p), upto(c, b, p), upto(c, i, p), p),
                Op::Neg(a) => -c[a + p],
                Op::Scale(a, k) => k * c[a + p],
                Op::Offset(a, k) => c[a + p] + if p == 0 { k } else { 0.0 },
                Op::Sqrt(a) => taylor::sqrt_coeff(upto(c, a, p), upto(c, i, p), p),
                Op::Powf(a, alpha) => taylor::powf_coeff(upto(c, a, p), alpha, upto(c, i, p), p),
                Op::Exp(a) => taylor::exp_coeff(upto(c, a, p), upto(c, i, p), p),
                Op::Sin(a) => {
                    // sin_p reads cos_0..p-1 and cos_p reads sin_0..p-1.
                    let sin = taylor::sin_coeff(upto(c, a, p), upto(c, i + s, p), p);
                    let cos = taylor::cos_coeff(upto(c, a, p), upto(c, i, p), p);
                    c[i + p] = sin;
                    c[i + s + p] = cos;
                    continue;
                }
                Op::Input | Op::CosOfPrevious => unreachable!("not compiled"),
            };
            c[i + p] = value;
        }
    }

    /// Order-0 evaluation: sets the inputs' constant terms and returns the outputs.
    pub fn eval(&mut self, x: &[f64]) -> Vec<f64> {
        for (i, &xi) in x.iter().enumerate() {
            self.set_input(i, 0, xi);
        }
        self.propagate(0);
        (0..self.n_outputs()).map(|j| self.output(j, 0)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Records f(x, y) = sqrt(x*y + 1) / (x - 3) + (y^0.3) * sin(x) - exp(y) * 2.
    fn sample(order: usize) -> Tape {
        let b = TapeBuilder::new();
        let x = b.input();
        let y = b.input();
        let (s, _c) = x.sin_cos();
        let f = (x * y + 1.0).sqrt() / (x - 3.0) + y.powf(0.3) * s - 2.0 * y.exp();
        let g = 1.0 / (1.0 - x) - y;
        b.finish(&[f, g], order)
    }

    fn direct(x: f64, y: f64) -> [f64; 2] {
        [
            (x * y + 1.0).sqrt() / (x - 3.0) + y.powf(0.3) * x.sin() - 2.0 * y.exp(),
            1.0 / (1.0 - x) - y,
        ]
    }

    #[test]
    fn series_along_a_line_matches_direct_evaluation() {
        // Inputs x = 0.4 + 0.2 a, y = 0.7 - 0.1 a: the output series summed at
        // a = 0.3 must equal the direct evaluation there.
        let n = 25;
        let mut t = sample(n);
        let (x0, x1, y0, y1) = (0.4, 0.2, 0.7, -0.1);
        for p in 0..=n {
            let (xp, yp) = match p {
                0 => (x0, y0),
                1 => (x1, y1),
                _ => (0.0, 0.0),
            };
            t.set_input(0, p, xp);
            t.set_input(1, p, yp);
            t.propagate(p);
        }
        let a = 0.3;
        let want = direct(x0 + x1 * a, y0 + y1 * a);
        for (j, w) in want.iter().enumerate() {
            let got = taylor::eval(t.output_series(j), a);
            assert!((got - w).abs() < 1e-13, "output {j}: {got} vs {w}");
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let mut t = sample(3);
        let (x, y) = (0.4, 0.7);
        t.eval(&[x, y]);
        let jac = t.jacobian(&[0, 1]);
        let h = 1e-6;
        for (col, (dx, dy)) in [(h, 0.0), (0.0, h)].into_iter().enumerate() {
            let fp = direct(x + dx, y + dy);
            let fm = direct(x - dx, y - dy);
            for row in 0..2 {
                let fd = (fp[row] - fm[row]) / (2.0 * h);
                assert!(
                    (jac[row][col] - fd).abs() < 1e-8,
                    "J[{row}][{col}] = {} vs {fd}",
                    jac[row][col]
                );
            }
        }
    }

    #[test]
    fn linear_update_equals_a_second_propagation() {
        // Propagating order p with input coefficients x, or with zeros and
        // then adding the order-0 node tangents times x: identical series.
        let n = 8;
        let (mut a, mut b) = (sample(n), sample(n));
        let x0 = [0.4, 0.7];
        for t in [&mut a, &mut b] {
            t.eval(&x0);
        }
        let tangents = b.node_tangents(&[0, 1]);
        for p in 1..=n {
            let xp = [0.3 / p as f64, -0.2 * p as f64];
            a.set_input(0, p, xp[0]);
            a.set_input(1, p, xp[1]);
            a.propagate(p);
            b.set_input(0, p, 0.0);
            b.set_input(1, p, 0.0);
            b.propagate(p);
            b.add_to_order(p, &tangents, &xp);
            for j in 0..2 {
                let (sa, sb) = (a.output(j, p), b.output(j, p));
                assert!(
                    (sa - sb).abs() <= 1e-12 * (1.0 + sa.abs()),
                    "order {p}, output {j}: {sa} vs {sb}"
                );
            }
        }
    }
}
