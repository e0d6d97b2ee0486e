use anm::reference::ida::{Ida, Task};
use anm::reference::run::model;
use std::path::Path;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let path = Path::new(&a[1]);
    let text = anm::scene::read(path).unwrap();
    let kind = anm::scene::kind(path, &text).unwrap();
    let sc = anm::scene::friction::load(path, &text, kind).unwrap();
    let m = model(&sc).unwrap();
    let (y0, yp0) = m.initial_guess();
    let mut ida = Ida::new(m.as_ref(), 0.0, &y0, &yp0, 1e-10, 1e-12).unwrap();
    ida.set_max_num_steps(1_000_000).unwrap();
    ida.set_stop_time(sc.t_end).unwrap();
    if a.len() > 3 { ida.set_suppress_alg(true).unwrap(); }
    ida.calc_ic(0.01).unwrap();
    let t_from: f64 = a[2].parse().unwrap();
    let mut k = 0;
    while ida.t() < sc.t_end {
        let t = ida.solve(sc.t_end, Task::OneStep).unwrap();
        if t > t_from && k < 30 {
            k += 1;
            let c = ida.counters(); let w = ida.weighted_local_errors().unwrap();
            println!("t={t:.9} h={:.3e} q={} etf={} y={:?}\n   werr={:?}", ida.last_step(), ida.last_order(), c.error_test_fails, ida.y(), w);
        }
    }
    println!("{:?}", ida.counters());
}
