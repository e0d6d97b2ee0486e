//! Cost of one element's series over an ANM step (start, then per order the
//! completion and the right-hand side; the tangent once), in isolation from
//! assembly and solves: `cargo run --release --example element_series_kernel`.
//! Prints nanoseconds per element-step.

use anm::shell::kinematics::Vec3;
use anm::shell::series::ElementSeries;
use anm::shell::{Material, ShellElement};
use std::time::Instant;

fn main() {
    let x = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.11, 0.01, 0.02),
        Vec3::new(0.12, 0.09, 0.01),
        Vec3::new(-0.01, 0.1, 0.03),
    ];
    let d = [
        Vec3::new(0.1, 0.0, 1.0),
        Vec3::new(-0.1, 0.05, 1.0),
        Vec3::new(0.0, -0.1, 1.0),
        Vec3::new(0.05, 0.05, 1.0),
    ]
    .map(|v| v.normalize());
    let material = Material {
        young: 2e11,
        poisson: 0.3,
    };
    let e = ShellElement::new(0, [0, 1, 2, 3], &x, &d, 0.01, &material).expect("element");
    let order = 15;
    let reps = 20_000;
    let incr = |p: usize, k: usize| {
        Vec3::from_fn(|i, _| 1e-3 * ((p * 7 + k * 3 + i) as f64).sin() / p as f64)
    };
    let mut checksum = 0.0;
    let (mut t_start, mut t_tangent, mut t_orders) = (0.0, 0.0, 0.0);
    for _ in 0..reps {
        let t = Instant::now();
        let mut st = ElementSeries::start(&e, &x, &d);
        t_start += t.elapsed().as_secs_f64();
        let t = Instant::now();
        checksum += st.tangent(&e)[(0, 0)];
        t_tangent += t.elapsed().as_secs_f64();
        let t = Instant::now();
        for p in 1..=order {
            let xs = std::array::from_fn(|k| incr(p, k));
            let ds = std::array::from_fn(|k| incr(p, k + 4));
            st.complete(&e, &xs, &ds);
            if p < order {
                checksum += st.rhs(&e)[3];
            }
        }
        t_orders += t.elapsed().as_secs_f64();
    }
    let ns = |s: f64| 1e9 * s / reps as f64;
    println!(
        "per element-step: start {:.0} ns, tangent {:.0} ns, {order} orders {:.0} ns (checksum {checksum:.6e})",
        ns(t_start),
        ns(t_tangent),
        ns(t_orders)
    );
}
