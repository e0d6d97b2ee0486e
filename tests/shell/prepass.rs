//! The series' inner terms computed during a solve
//! (`ContinuationProblem::rhs_prepass`): the job stops when the engine's
//! solve is done, and the series' pass prepares the elements it did not
//! reach. The right-hand sides must not depend on where it stopped: the
//! same bits whether the job finishes, stops at once, or is stopped while
//! it runs.

use super::shell_common::{add_area_load, fix, model};
use anm::mesh::Vec3;
use anm::mesh::structured::rectangle;
use anm::series::ContinuationProblem;
use std::sync::atomic::{AtomicBool, Ordering};

/// How the job of each order is ended.
#[derive(Clone, Copy, Debug)]
enum Stop {
    Finished,
    AtOnce,
    WhileRunning,
}

/// The right-hand sides of orders 2..=8 of a 50 × 20 plate (1,000
/// elements, the fewest that get a job) with made-up order terms.
fn right_hand_sides(stop: Stop) -> Vec<Vec<f64>> {
    let mesh = rectangle(0.0, 2.0, 0.0, 0.5, 50, 20);
    let mut m = model(&mesh, 0.01, 2e11, 0.3);
    let clamped: Vec<usize> = (0..mesh.nodes.len())
        .filter(|&i| mesh.nodes[i].x < 1e-12)
        .collect();
    let mut fixed = vec![];
    fix(&mut fixed, &clamped, &[0, 1, 2, 3, 4, 5]);
    m.set_constraints(&fixed);
    add_area_load(&mut m, &mesh, Vec3::new(0.0, 0.0, 1e3));
    let n = m.ndof();
    let term = |p: usize| -> Vec<f64> {
        (0..n)
            .map(|i| 1e-3 * ((i * 7 + p * 13) as f64 * 0.37).sin() / p as f64)
            .collect()
    };
    let u0 = vec![0.0; n];
    m.tangent(&u0, 0.0).expect("tangent");
    let mut us = vec![u0, term(1)];
    let mut ls = vec![0.0, 0.7];
    let mut out = vec![];
    for p in 2..=8 {
        out.push(m.series_rhs(p, &us, &ls).expect("right-hand side"));
        if let Some(job) = m.rhs_prepass(p + 1) {
            let done = AtomicBool::new(matches!(stop, Stop::AtOnce));
            match stop {
                Stop::WhileRunning => std::thread::scope(|s| {
                    s.spawn(|| {
                        std::thread::sleep(std::time::Duration::from_micros(100));
                        done.store(true, Ordering::Relaxed);
                    });
                    job(&done);
                }),
                _ => job(&done),
            }
        }
        us.push(term(p));
        ls.push(0.1 / p as f64);
    }
    out
}

#[test]
fn inner_terms_give_the_same_bits_wherever_the_job_stops() {
    let finished = right_hand_sides(Stop::Finished);
    for stop in [Stop::AtOnce, Stop::WhileRunning] {
        let other = right_hand_sides(stop);
        for (p, (a, b)) in finished.iter().zip(&other).enumerate() {
            assert!(a.iter().any(|x| *x != 0.0), "order {} is zero", p + 2);
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                assert_eq!(
                    x.to_bits(),
                    y.to_bits(),
                    "{stop:?}: order {}, entry {i}: {x:e} against {y:e}",
                    p + 2
                );
            }
        }
    }
}
