//! Cost of the element series over an ANM step (start, then per order the
//! completion and the next right-hand side; the tangent once), in isolation
//! from assembly and solves, for one element in cache and for the 16,000
//! elements of the 400×40 strip streamed through memory:
//! `cargo run --release --example element_series_kernel`. Prints
//! nanoseconds per element-step.

use anm::shell::element::FullMapCache;
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
    let order = 15;
    let incr = |p: usize, k: usize| {
        Vec3::from_fn(|i, _| 1e-3 * ((p * 7 + k * 3 + i) as f64).sin() / p as f64)
    };
    // One element many times (its data stay in cache), then the elements
    // of the 400×40 strip (16,000: every order streams all of them through
    // memory, as a run does), one thread.
    for (count, reps) in [(1usize, 20_000usize), (16_000, 2)] {
        let elements: Vec<ShellElement> = (0..count)
            .map(|i| {
                let shift = Vec3::new(0.1 * i as f64, 0.0, 0.0);
                let xi = x.map(|v| v + shift);
                ShellElement::new(i, [0, 1, 2, 3], &xi, &d, 0.01, &material).expect("element")
            })
            .collect();
        let mut checksum = 0.0;
        let (mut t_start, mut t_tangent, mut t_orders, mut t_inner) = (0.0, 0.0, 0.0, 0.0);
        for _ in 0..reps {
            let t = Instant::now();
            let mut series: Vec<ElementSeries> = elements
                .iter()
                .map(|e| ElementSeries::start(e, &x, &d))
                .collect();
            t_start += t.elapsed().as_secs_f64();
            let t = Instant::now();
            // Each element here has its own map: no reuse of the unpacked one.
            let mut cache = FullMapCache::default();
            for (e, st) in elements.iter().zip(&series) {
                checksum += st.tangent(e, &mut cache)[(0, 0)];
            }
            t_tangent += t.elapsed().as_secs_f64();
            let t = Instant::now();
            // Orders 1 … N − 1 completed, each with the next right-hand
            // side (ShellModel::series_rhs), as in a step of order N.
            for p in 1..order {
                let xs = std::array::from_fn(|k| incr(p, k));
                let ds = std::array::from_fn(|k| incr(p, k + 4));
                let t_in = Instant::now();
                for st in series.iter_mut() {
                    st.prepare(p + 1);
                }
                t_inner += t_in.elapsed().as_secs_f64();
                for (e, st) in elements.iter().zip(&mut series) {
                    checksum += st.complete_and_rhs(e, &xs, &ds, &mut cache)[3];
                }
            }
            t_orders += t.elapsed().as_secs_f64();
        }
        let ns = |s: f64| 1e9 * s / (reps * count) as f64;
        println!(
            "{count} element(s), per element-step: start {:.0} ns, tangent {:.0} ns, {} orders {:.0} ns ({:.0} ns per order, of which inner terms {:.0} ns; checksum {checksum:.6e})",
            ns(t_start),
            ns(t_tangent),
            order - 1,
            ns(t_orders),
            ns(t_orders) / (order - 1) as f64,
            ns(t_inner) / (order - 1) as f64
        );
    }
}
