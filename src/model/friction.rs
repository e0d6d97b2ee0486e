//! The paper's friction cases as index-1 DAEs for the Taylor engine
//! ([`crate::series::dae`]). Each model states which unknowns are differential
//! (u, with v = du/dt) and which are algebraic (z).

use crate::contact::{FrictionLaw, NormalLaw};
use crate::scene::Kind;
use crate::scene::friction::{FrictionScene, Obstacle};
use crate::series::{DaeProblem, TapeBuilder, Var};

/// What a friction model adds to [`DaeProblem`]: its initial state and the
/// mapping from its unknowns to the output columns.
pub trait FrictionModel: DaeProblem {
    /// Output columns of history.csv, starting with "t".
    fn columns(&self) -> &'static [&'static str];
    /// Initial differential state u0.
    fn u0(&self) -> Vec<f64>;
    /// (v0, z0) from the initial velocity along x, exact at t = 0.
    fn exact_start(&self, vx0: f64) -> (Vec<f64>, Vec<f64>);
    /// Newton's default starting guess for (v, z): the system at rest.
    fn guess(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0; self.n_diff()], vec![0.0; self.n_alg()])
    }
    /// One output row from y = (u, v, z) and dy/dt at time t.
    fn row(&self, t: f64, y: &[f64], ydot: &[f64]) -> Vec<f64>;
    /// Slip velocity v_s from y (for diagnostics and plots).
    fn slip(&self, y: &[f64]) -> f64;
    /// dG/dR_N = 2 R_N / K + h of eq. (3) at y, positive on the law's
    /// physical root (None without a contact law). Review 26: at eta =
    /// 1e-16 N friction-plane ended on the other root, the mass 2 m
    /// through the plane with R_N = 8.8e-15 N, exit 0.
    fn contact_branch(&self, _y: &[f64]) -> Option<f64> {
        None
    }
}

/// §3.2, eq. (7): spring k on a plane moving at V, known normal force R_N.
///   k u - R_T(v - V) = 0,  R_T from eq. (5) with R_N as given.
/// u differential; no algebraic unknown.
pub struct Friction1d {
    pub k: f64,
    pub law: FrictionLaw,
    pub v_plane: f64,
    pub rn: f64,
    pub u0: f64,
}

impl DaeProblem for Friction1d {
    fn n_diff(&self) -> usize {
        1
    }
    fn n_alg(&self) -> usize {
        0
    }
    fn record<'a>(
        &self,
        b: &'a TapeBuilder,
        u: &[Var<'a>],
        v: &[Var<'a>],
        _z: &[Var<'a>],
        _t: Var<'a>,
    ) -> Vec<Var<'a>> {
        let rn = b.constant(self.rn);
        let rt = self.law.record(rn, v[0] - self.v_plane);
        vec![self.k * u[0] - rt]
    }
    fn names(&self) -> Vec<String> {
        vec!["u".into(), "v".into()]
    }
}

impl FrictionModel for Friction1d {
    fn columns(&self) -> &'static [&'static str] {
        &["t", "u", "v", "rt"]
    }
    fn u0(&self) -> Vec<f64> {
        vec![self.u0]
    }
    fn exact_start(&self, vx0: f64) -> (Vec<f64>, Vec<f64>) {
        (vec![vx0], vec![])
    }
    fn row(&self, t: f64, y: &[f64], _ydot: &[f64]) -> Vec<f64> {
        vec![t, y[0], y[1], self.law.force(self.rn, y[1] - self.v_plane)]
    }
    fn slip(&self, y: &[f64]) -> f64 {
        y[1] - self.v_plane
    }
}

/// §3.3, eq. (10) with (11): mass on springs k, at delta above a plane moving
/// at V along x, pushed toward it by F t.
///   (a) -k u_x + R_T = 0            (b) -k u_y + R_N - F t = 0
///   (c) R_N (R_N/K + h) = eta (delta - h), h = delta + u_y
///   (d) R_T = -f |R_N|_reg |v_s|_reg^(q-1) / Vc^q v_s, v_s = v_x - V
/// u_x differential; z = (u_y, R_N, R_T).
pub struct FrictionPlane {
    pub k: f64,
    pub law: FrictionLaw,
    pub contact: NormalLaw,
    pub v_plane: f64,
    pub load_rate: f64,
}

impl DaeProblem for FrictionPlane {
    fn n_diff(&self) -> usize {
        1
    }
    fn n_alg(&self) -> usize {
        3
    }
    fn record<'a>(
        &self,
        _b: &'a TapeBuilder,
        u: &[Var<'a>],
        v: &[Var<'a>],
        z: &[Var<'a>],
        t: Var<'a>,
    ) -> Vec<Var<'a>> {
        let (uy, rn, rt) = (z[0], z[1], z[2]);
        let h = uy + self.contact.delta;
        vec![
            -self.k * u[0] + rt,
            -self.k * uy + rn - self.load_rate * t,
            self.contact.record(rn, h),
            rt - self.law.record(rn, v[0] - self.v_plane),
        ]
    }
    fn names(&self) -> Vec<String> {
        ["ux", "vx", "uy", "rn", "rt"].map(String::from).to_vec()
    }
}

impl FrictionModel for FrictionPlane {
    fn columns(&self) -> &'static [&'static str] {
        &["t", "ux", "uy", "vx", "vy", "rn", "rt"]
    }
    fn u0(&self) -> Vec<f64> {
        vec![0.0]
    }
    fn exact_start(&self, vx0: f64) -> (Vec<f64>, Vec<f64>) {
        // At t = 0: no load, so u_y = 0, h = delta, R_N = 0 (eq. c), R_T = k u_x = 0.
        (vec![vx0], vec![0.0, 0.0, 0.0])
    }
    fn row(&self, t: f64, y: &[f64], ydot: &[f64]) -> Vec<f64> {
        // y = (ux, vx, uy, rn, rt); v_y is the time derivative of u_y's series.
        vec![t, y[0], y[2], y[1], ydot[2], y[3], y[4]]
    }
    fn slip(&self, y: &[f64]) -> f64 {
        y[1] - self.v_plane
    }
    fn contact_branch(&self, y: &[f64]) -> Option<f64> {
        // y = (ux, vx, uy, rn, rt), h = uy + delta.
        Some(2.0 * y[3] / self.contact.k + y[2] + self.contact.delta)
    }
}

/// §3.4: the obstacle is a cylinder of radius r, centre C = (0, -(delta + r)),
/// spinning at Omega counterclockwise, so its top drags the mass toward -x.
///
/// We write the mass position in polar coordinates about the roller axis,
/// x = C + rho n(phi), n = (sin phi, cos phi), t = (cos phi, -sin phi) (n turned
/// by -90°). Then dx/dt = rho' n + rho phi' t, so the slip v_s = v.t + Omega r
/// = rho omega + Omega r involves the angular velocity omega = phi' only, and
/// the equilibrium projected on the current (n, t) splits exactly into a
/// normal and a tangential part at every order — the decoupling the paper gets
/// at order 1 from the start-of-step frame (eqs. 12–16), with a Jacobian that
/// stays constant over the step:
///   n: -k u.n + R_N - F t n_y = 0      t: -k u.t + R_T + F t sin(phi) = 0
///   R_N (R_N/K + h) = eta (delta - h), h = rho - r
///   R_T = -f |R_N|_reg |v_s|_reg^(q-1) / Vc^q v_s
/// with u = x - X0 (X0 = origin), u.n = rho - (delta + r) cos phi,
/// u.t = (delta + r) sin phi. phi differential; z = (rho, R_N, R_T).
pub struct FrictionRoller {
    pub k: f64,
    pub law: FrictionLaw,
    pub contact: NormalLaw,
    pub radius: f64,
    pub spin: f64,
    pub load_rate: f64,
}

impl FrictionRoller {
    /// Distance from the start point to the roller axis, delta + r.
    fn axis_distance(&self) -> f64 {
        self.contact.delta + self.radius
    }
}

impl DaeProblem for FrictionRoller {
    fn n_diff(&self) -> usize {
        1
    }
    fn n_alg(&self) -> usize {
        3
    }
    fn record<'a>(
        &self,
        _b: &'a TapeBuilder,
        u: &[Var<'a>],
        v: &[Var<'a>],
        z: &[Var<'a>],
        t: Var<'a>,
    ) -> Vec<Var<'a>> {
        let (phi, omega) = (u[0], v[0]);
        let (rho, rn, rt) = (z[0], z[1], z[2]);
        let d = self.axis_distance();
        let (s, c) = phi.sin_cos();
        let u_dot_n = rho - d * c;
        let u_dot_t = d * s;
        let load = self.load_rate * t;
        let slip = rho * omega + self.spin * self.radius;
        vec![
            -self.k * u_dot_n + rn - load * c,
            -self.k * u_dot_t + rt + load * s,
            self.contact.record(rn, rho - self.radius),
            rt - self.law.record(rn, slip),
        ]
    }
    fn names(&self) -> Vec<String> {
        ["phi", "omega", "rho", "rn", "rt"]
            .map(String::from)
            .to_vec()
    }
}

impl FrictionModel for FrictionRoller {
    fn columns(&self) -> &'static [&'static str] {
        &["t", "ux", "uy", "vx", "vy", "rn", "rt"]
    }
    fn u0(&self) -> Vec<f64> {
        vec![0.0]
    }
    fn exact_start(&self, vx0: f64) -> (Vec<f64>, Vec<f64>) {
        // At the top, t = e_x: omega = v_x / rho; no load, so R_N = R_T = 0.
        let d = self.axis_distance();
        (vec![vx0 / d], vec![d, 0.0, 0.0])
    }
    fn guess(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0], vec![self.axis_distance(), 0.0, 0.0])
    }
    fn row(&self, t: f64, y: &[f64], ydot: &[f64]) -> Vec<f64> {
        // y = (phi, omega, rho, rn, rt); rho' from the series of rho.
        let (phi, omega, rho) = (y[0], y[1], y[2]);
        let (s, c) = phi.sin_cos();
        let d = self.axis_distance();
        let ux = rho * s;
        let uy = rho * c - d;
        let rho_dot = ydot[2];
        // dx/dt = rho' n + rho omega t.
        let vx = rho_dot * s + rho * omega * c;
        let vy = rho_dot * c - rho * omega * s;
        vec![t, ux, uy, vx, vy, y[3], y[4]]
    }
    fn slip(&self, y: &[f64]) -> f64 {
        y[2] * y[1] + self.spin * self.radius
    }
    fn contact_branch(&self, y: &[f64]) -> Option<f64> {
        // y = (phi, omega, rho, rn, rt), h = rho - radius.
        Some(2.0 * y[3] / self.contact.k + y[2] - self.radius)
    }
}

/// Builds the model of a friction scene.
pub fn build(scene: &FrictionScene) -> Box<dyn FrictionModel> {
    match (scene.kind, scene.obstacle) {
        (Kind::Friction1d, Obstacle::Plane { v }) => Box::new(Friction1d {
            k: scene.k,
            law: scene.friction,
            v_plane: v,
            rn: scene.normal_force,
            u0: scene.u0,
        }),
        (Kind::FrictionPlane, Obstacle::Plane { v }) => Box::new(FrictionPlane {
            k: scene.k,
            law: scene.friction,
            contact: scene
                .contact
                .expect("validated: plane scenes have a contact law"),
            v_plane: v,
            load_rate: scene.load_rate,
        }),
        (Kind::FrictionRoller, Obstacle::Roller { r, omega }) => Box::new(FrictionRoller {
            k: scene.k,
            law: scene.friction,
            contact: scene
                .contact
                .expect("validated: roller scenes have a contact law"),
            radius: r,
            spin: omega,
            load_rate: scene.load_rate,
        }),
        _ => unreachable!("scene validation pairs each kind with its obstacle"),
    }
}
