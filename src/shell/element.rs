//! The 4-node ANS + EAS shell element (Büchter, Ramm, Roehl IJNME 37 (1994);
//! Dvorkin, Bathe, Eng. Comput. 1 (1984); Andelfinger, Ramm IJNME 36 (1993)).
//!
//! Locking treatments:
//! - transverse shear (Dvorkin–Bathe ANS): E_13 is interpolated in η from its
//!   values at the edge midpoints A = (0, −1), C = (0, 1); E_23 in ξ from
//!   B = (−1, 0), D = (1, 0) (both the θ3⁰ and θ3¹ parts);
//! - curvature-thickness locking: E⁰_33 is interpolated bilinearly from its
//!   values at the four corners (Betsch, Stein 1995);
//! - Poisson thickness locking: one EAS mode θ3 α5 on E_33 (the 7-parameter
//!   model), so the 3D law needs no plane-stress condensation;
//! - membrane (in-plane bending) locking: four EAS modes on E⁰_αβ,
//!   (E11, E22, E12, E12) = (ξ α1, η α2, ξ α3 + η α4).
//!
//! The enhanced membrane strain Ẽ_ij = (dA0/dA) T_ik M_kl(ξ, η) T_jl,
//! T_ik = G_i · G0^k (centroid contravariant basis G0^k), is orthogonal to
//! constant stresses and keeps the membrane patch test on distorted elements
//! (Simo, Rifai IJNME 29 (1990); Andelfinger, Ramm 1993 eq. 33). The
//! thickness mode θ3 α5 is orthogonal to constant stresses through θ3
//! already; it is mapped without the area ratio so that it stays constant on
//! a distorted element (with the ratio, the bending patch test failed with a
//! 4.4e-3 nodal error; without it the error is 7e-12).
//! The EAS parameters enter the strain linearly and the stress linearly, so
//! their equation ∫ Gᵀ s dA = 0 (paper eq. 4) is solved exactly per element:
//! α = −H⁻¹ ∫ Gᵀ D e_c dA, H = ∫ Gᵀ D G dA (constant), and the condensed
//! tangent is K* = K − L H⁻¹ Lᵀ with L = ∫ Bᵀ D G dA. Since α is a linear map
//! of the compatible strain, the order-p EAS equation has the same matrix H.

// Node/dof/component loops read better with explicit indices.
#![allow(clippy::needless_range_loop)]

use nalgebra::{Matrix3, SMatrix};
use std::sync::{Arc, OnceLock};

use super::geometric_map::GeometricMap;
use super::kinematics::{
    NCOL, NDOF_EL, NDOF_Y, NSTRAIN, NSYM, NodalVectors, PackedSym, Point, PointVectors, SYM_INDEX,
    SYM_PAIRS, Strain, Sym, Vec3, pack, strain,
};
use super::material::Material;
use crate::error::{Error, Result};
use crate::fe::prefetch::prefetch;

/// Number of EAS parameters per element.
pub const NEAS: usize = 5;
type GMatrix = SMatrix<f64, NSTRAIN, NEAS>;
pub type ElementMatrix = SMatrix<f64, NDOF_EL, NDOF_EL>;

/// The full map K on packed matrices (GeometricMap stores it as S P).
type FullMap = SMatrix<f64, NSYM, NSYM>;
/// The full map of the last element that asked for it: congruent elements
/// share one map (geometric_map::share), so a loop over the elements
/// unpacks it once per run of elements that share it.
#[derive(Default)]
pub struct FullMapCache(Option<(Arc<GeometricMap>, Box<FullMap>)>);

/// Packed Kg of the Gram change YᵀδY + δYᵀY, per unknown of Y.
pub type GramJacobian = SMatrix<f64, NSYM, NDOF_Y>;

/// Sampling points: 0..4 Gauss points, 4..8 ANS edge midpoints A, B, C, D,
/// 8..12 corners.
const NPT: usize = 12;

const G: f64 = 0.577_350_269_189_625_8;
const SAMPLING: [(f64, f64); NPT] = [
    (-G, -G),
    (G, -G),
    (G, G),
    (-G, G),
    (0.0, -1.0),
    (-1.0, 0.0),
    (0.0, 1.0),
    (1.0, 0.0),
    (-1.0, -1.0),
    (1.0, -1.0),
    (1.0, 1.0),
    (-1.0, 1.0),
];

/// The interpolation weights at the sampling points: the same for every
/// element (natural coordinates only), so stored once instead of 5.3 kB per
/// element (measured: 85 MB of the 98,400-unknown strip's 1.06 GiB peak).
fn points() -> &'static [Point; NPT] {
    static POINTS: std::sync::LazyLock<[Point; NPT]> = std::sync::LazyLock::new(|| {
        std::array::from_fn(|i| Point::new(SAMPLING[i].0, SAMPLING[i].1))
    });
    &POINTS
}

/// Per strain component, the (sampling point, weight) pairs that give it.
type AnsWeights = [Vec<(usize, f64)>; NSTRAIN];

/// The assumed-strain interpolation at Gauss point `gi`: `[c]` lists the
/// (sampling point, weight) pairs giving strain component c there. Natural
/// coordinates only, so shared by every element (it was stored per element:
/// 12 small vectors per Gauss point, 3.5 kB an element with their headers).
fn ans_weights(gi: usize) -> &'static AnsWeights {
    static WEIGHTS: std::sync::LazyLock<[AnsWeights; 4]> = std::sync::LazyLock::new(|| {
        std::array::from_fn(|gi| {
            let (xi, eta) = SAMPLING[gi];
            let (nn, _, _) = super::kinematics::shape(xi, eta);
            std::array::from_fn(|c| match c {
                3 | 9 => vec![(4, 0.5 * (1.0 - eta)), (6, 0.5 * (1.0 + eta))],
                4 | 10 => vec![(5, 0.5 * (1.0 - xi)), (7, 0.5 * (1.0 + xi))],
                5 => (0..4).map(|i| (8 + i, nn[i])).collect(),
                _ => vec![(gi, 1.0)],
            })
        })
    });
    &WEIGHTS[gi]
}

struct GaussPoint {
    /// Reference area weight |A1 × A2| w.
    da: f64,
    /// The 6×6 material matrix in the natural basis: the shell's 12×12 is
    /// blockdiag(t D, t³/12 D) (Material::d_shell), stored as D alone
    /// (3.5 kB an element less, half the products).
    d: SMatrix<f64, 6, 6>,
    g: GMatrix,
}

impl GaussPoint {
    /// blockdiag(t D, t³/12 D) e with `moments` = (t, t³/12).
    fn stress(
        &self,
        moments: (f64, f64),
        e: &SMatrix<f64, NSTRAIN, 1>,
    ) -> SMatrix<f64, NSTRAIN, 1> {
        let membrane = self.d * e.fixed_rows::<6>(0) * moments.0;
        let bending = self.d * e.fixed_rows::<6>(6) * moments.1;
        let mut s = SMatrix::<f64, NSTRAIN, 1>::zeros();
        s.fixed_rows_mut::<6>(0).copy_from(&membrane);
        s.fixed_rows_mut::<6>(6).copy_from(&bending);
        s
    }
}

/// Reference data of one element.
pub struct ShellElement {
    pub nodes: [usize; 4],
    ref_vec: Vec<PointVectors>,
    gps: Vec<GaussPoint>,
    hinv: SMatrix<f64, NEAS, NEAS>,
    /// Thickness moments (t, t³/12) of the material matrix.
    moments: (f64, f64),
    /// The linear map M ↦ Kg(σ(E(M))) on packed symmetric matrices (see
    /// [`ShellElement::packed_geometric`]), stored symmetric; one copy for
    /// all congruent elements (geometric_map::share).
    kmap: Arc<GeometricMap>,
    /// Whether other elements hold the same map (set by
    /// [`ShellElement::set_map`]): the series then read it unpacked, once
    /// per run of elements ([`ShellElement::packed_geometric_pair`]).
    map_shared: bool,
}

fn to_vec(m: &Matrix3<f64>) -> [f64; 6] {
    [
        m[(0, 0)],
        m[(1, 1)],
        m[(0, 1)],
        m[(0, 2)],
        m[(1, 2)],
        m[(2, 2)],
    ]
}

/// Area ratio below which a face of the shell is taken as folded: 1/2 is a
/// cylinder of radius t (the ratio 1 − t/2R on its inner face); shell
/// kinematics (θ3² terms dropped) need t far below the radii anyway.
const FOLDED_FACE: f64 = 0.5;

/// Why a shell of thickness `t` cannot exist at a point with reference
/// vectors `v` (A1, A2, A3, A3,1, A3,2), or `None`: a face θ3 = ±t/2 whose
/// area element (A1 + θ3 A3,1) × (A2 + θ3 A3,2) · A3 falls below
/// [`FOLDED_FACE`] of the mid-surface's, i.e. t of the order of a radius of
/// curvature or above (review 11: a "40 mm" thickness in a scene in m, on a
/// hemisphere of radius 10, was solved with exit 0).
fn folded_face(v: &PointVectors, t: f64) -> Option<String> {
    let area = |theta: f64| {
        (v[0] + theta * v[3])
            .cross(&(v[1] + theta * v[4]))
            .dot(&v[2])
    };
    // The area is quadratic in θ3, a0 + a1 θ3 + a2 θ3²: its least value
    // across the thickness is at a face or at the vertex (on a sphere both
    // directions fold at θ3 = R, where the faces alone look unfolded).
    let h = 0.5 * t;
    let (mid, up, down) = (area(0.0), area(h), area(-h));
    let (a1, a2) = (
        (up - down) / (2.0 * h),
        (up + down - 2.0 * mid) / (2.0 * h * h),
    );
    let mut least = up.min(down);
    if a2 > 0.0 && (a1 / (2.0 * a2)).abs() < h {
        least = least.min(mid - a1 * a1 / (4.0 * a2));
    }
    let ratio = least / mid;
    // The radius of curvature the directors' rate gives, for the message.
    let rate = (v[3].norm() / v[0].norm()).max(v[4].norm() / v[1].norm());
    (!(ratio > FOLDED_FACE)).then(|| {
        format!(
            "shell.thickness {t:e} is not small against the radius of curvature {:.3e} here: a face of the shell would fold (area ratio {ratio:.3} of the mid-surface's); a length in another unit?",
            1.0 / rate
        )
    })
}

/// The zero map every element holds before its own is set (one shared
/// allocation).
fn placeholder_map() -> Arc<GeometricMap> {
    static ZERO: OnceLock<Arc<GeometricMap>> = OnceLock::new();
    Arc::clone(ZERO.get_or_init(|| Arc::new(GeometricMap::from_full(&FullMap::zeros()))))
}

impl ShellElement {
    /// Builds the element from its reference nodes and unit directors.
    /// Errors name the element (0-based index `id`) for degenerate geometry.
    pub fn new(
        id: usize,
        nodes: [usize; 4],
        x: &[Vec3; 4],
        a3: &[Vec3; 4],
        thickness: f64,
        material: &Material,
    ) -> Result<Self> {
        let (mut el, map) = Self::with_map_apart(id, nodes, x, a3, thickness, material)?;
        el.kmap = Arc::new(map);
        Ok(el)
    }

    /// [`ShellElement::new`] with the element's map returned by value and
    /// not yet in the element (which holds a shared placeholder until
    /// [`ShellElement::set_map`]): a model builds its elements in parallel
    /// and then allocates one map per congruent class
    /// (geometric_map::share), instead of one per element to be freed.
    pub fn with_map_apart(
        id: usize,
        nodes: [usize; 4],
        x: &[Vec3; 4],
        a3: &[Vec3; 4],
        thickness: f64,
        material: &Material,
    ) -> Result<(Self, GeometricMap)> {
        let pts = points();
        let ref_vec: Vec<PointVectors> = pts.iter().map(|p| p.vectors(x, a3)).collect();
        let centre = Point::new(0.0, 0.0).vectors(x, a3);
        let basis = |v: &PointVectors| [v[0], v[1], v[2]];
        let g0 = basis(&centre);
        let da0 = g0[0].cross(&g0[1]).norm();
        let m0 = Matrix3::from_fn(|i, j| g0[i].dot(&g0[j]));
        let m0inv = m0
            .try_inverse()
            .filter(|_| da0 > 0.0)
            .ok_or_else(|| Error::Element {
                element: id,
                problem: "degenerate element: singular metric at the centre".into(),
            })?;
        let g0_contra: [Vec3; 3] =
            std::array::from_fn(|k| (0..3).map(|j| m0inv[(k, j)] * g0[j]).sum());
        let mut gps = Vec::with_capacity(4);
        let mut h = SMatrix::<f64, NEAS, NEAS>::zeros();
        for (gi, &(xi, eta)) in SAMPLING[..4].iter().enumerate() {
            let gb = basis(&ref_vec[gi]);
            let n = gb[0].cross(&gb[1]);
            let da_ratio = n.norm() / da0;
            if !(n.dot(&gb[2]) > 1e-12 * n.norm() && da_ratio > 1e-8) {
                return Err(Error::Element {
                    element: id,
                    problem: format!(
                        "inverted or degenerate element: surface Jacobian {:.3e} (normal · director {:.3e}) at Gauss point ({xi:.3}, {eta:.3})",
                        n.norm(),
                        n.dot(&gb[2])
                    ),
                });
            }
            if let Some(problem) = folded_face(&ref_vec[gi], thickness) {
                return Err(Error::Element {
                    element: id,
                    problem: format!("at Gauss point ({xi:.3}, {eta:.3}): {problem}"),
                });
            }
            let d = material.d_natural(&gb).ok_or_else(|| Error::Element {
                element: id,
                problem: "degenerate metric at a Gauss point".into(),
            })?;
            let t = Matrix3::from_fn(|i, k| gb[i].dot(&g0_contra[k]));
            let f = 1.0 / da_ratio;
            let mut g = GMatrix::zeros();
            let modes: [(usize, usize, f64); 4] =
                [(0, 0, xi), (1, 1, eta), (0, 1, xi), (0, 1, eta)];
            for (mode, &(k, l, val)) in modes.iter().enumerate() {
                let mut m = Matrix3::zeros();
                m[(k, l)] = val;
                m[(l, k)] = val;
                let e = to_vec(&(t * m * t.transpose() * f));
                for c in 0..6 {
                    g[(c, mode)] = e[c];
                }
            }
            // The thickness mode is orthogonal to constant stresses through
            // θ3 already; without the area ratio it stays constant on
            // distorted elements (bending patch test).
            let mut m = Matrix3::zeros();
            m[(2, 2)] = 1.0;
            let e = to_vec(&(t * m * t.transpose()));
            for c in 0..6 {
                g[(6 + c, 4)] = e[c];
            }
            let da = n.norm();
            let d_shell = material
                .d_shell(&gb, thickness)
                .expect("d_natural succeeded");
            h += g.transpose() * d_shell * g * da;
            gps.push(GaussPoint { da, d, g });
        }
        let hinv = h.try_inverse().ok_or_else(|| Error::Element {
            element: id,
            problem: "singular EAS matrix H".into(),
        })?;
        let el = Self {
            nodes,
            ref_vec,
            gps,
            hinv,
            moments: (thickness, thickness * thickness * thickness / 12.0),
            kmap: placeholder_map(),
            map_shared: false,
        };
        let map = GeometricMap::from_full(&el.geometric_map());
        Ok((el, map))
    }

    /// Column k: Kg(σ(E(M))) for M the k-th unit symmetric matrix, through
    /// the same ANS, EAS and stress path as [`ShellElement::internal`].
    fn geometric_map(&self) -> FullMap {
        let mut map = FullMap::zeros();
        for (k, &(a, b)) in SYM_PAIRS.iter().enumerate() {
            let mut m = Sym::zeros();
            m[(a, b)] = 1.0;
            m[(b, a)] = 1.0;
            let e_pt: [Strain; NPT] = std::array::from_fn(|i| points()[i].gram_strain(&m));
            let (sig, _) = self.stresses(&e_pt);
            map.set_column(k, &pack(&self.geometric(&sig)));
        }
        map
    }

    /// Geometric stiffness of the sampling-point stress weights.
    fn geometric(&self, sig: &[Strain; NPT]) -> Sym {
        let mut kg = Sym::zeros();
        for (pt, s) in points().iter().zip(sig) {
            pt.geometric(s, &mut kg);
        }
        kg
    }

    /// Kg(σ) of the stresses σ of the nodal Gram matrix M (packed): strain,
    /// EAS and stresses are linear in M (kinematics::Point::gram_strain), so
    /// this is one precomputed 28×28 product. With M the order-p Gram
    /// coefficient Σ_r Y_rᵀY_(p−r), Y_0 Kg_p + … is the order-p internal
    /// force on Y (B(x)ᵀσ = Y Kg(σ)).
    pub fn packed_geometric(&self, m: &PackedSym) -> PackedSym {
        self.kmap.apply(m)
    }

    /// The element's map (shared with the congruent elements once
    /// geometric_map::share has run).
    pub fn map(&self) -> &Arc<GeometricMap> {
        &self.kmap
    }

    /// Replaces the map by an equal one (geometric_map::share), shared
    /// when other holders of it exist now: its other elements, placed
    /// before or still to be placed.
    pub fn set_map(&mut self, map: Arc<GeometricMap>) {
        self.map_shared = Arc::strong_count(&map) > 1;
        self.kmap = map;
    }

    /// Prefetches the map (fe::prefetch), where the series read it packed:
    /// a shared map is read from the loop's unpacked copy
    /// ([`FullMapCache`]), which stays in cache, so its packed values would
    /// be 51 lines fetched per element and order for nothing.
    pub fn prefetch_map(&self) {
        if !self.map_shared {
            self.kmap.prefetch();
        }
    }

    /// Prefetches what the internal force at a state reads (fe::prefetch):
    /// the element's record, its reference point vectors and Gauss points
    /// (~3 kB, from memory after the solves have streamed the factor).
    pub fn prefetch_state(&self) {
        prefetch(std::slice::from_ref(self));
        prefetch(&self.ref_vec);
        prefetch(&self.gps);
    }

    /// Prefetches the fields the series pass reads before the map: the
    /// nodes and the map's address.
    pub fn prefetch_record(&self) {
        prefetch(std::slice::from_ref(&self.nodes));
        prefetch(std::slice::from_ref(&self.kmap));
    }

    /// [`ShellElement::packed_geometric`] of two matrices, on the full map
    /// of `cache` (unpacked once per run of elements that share the map):
    /// K a and K b summed column by column, Σ_j K_:j a_j in j order. The
    /// rows are independent sums that vectorize, where the packed
    /// triangle's sums below the diagonal are one dependent chain per row
    /// (GeometricMap::apply_pair; with AVX2, the element's whole pass per
    /// order 1,013 → 890 ns in `examples/element_series_kernel.rs`, one
    /// element in cache). Every row is the same sum in
    /// the same order as there, and K = S P with S = 1 or 2 scales exactly:
    /// the same results to the bit.
    pub fn packed_geometric_pair(
        &self,
        a: &PackedSym,
        b: &PackedSym,
        cache: &mut FullMapCache,
    ) -> (PackedSym, PackedSym) {
        // A map of this element alone (no congruent element: an
        // unstructured mesh) would be unpacked for every element and order,
        // which costs more than the packed sums (measured: 3.2 → 3.6 µs per
        // element and order, 16,000 elements streamed).
        if !self.map_shared {
            return self.kmap.apply_pair(a, b);
        }
        let k = self.full_map(cache).as_slice();
        let (mut ka, mut kb) = ([0.0; NSYM], [0.0; NSYM]);
        for (j, col) in k.chunks_exact(NSYM).enumerate() {
            let (aj, bj) = (a[j], b[j]);
            for ((c, x), y) in col.iter().zip(&mut ka).zip(&mut kb) {
                *x += c * aj;
                *y += c * bj;
            }
        }
        (PackedSym::from(ka), PackedSym::from(kb))
    }

    /// Kg(σ) of the stresses at the state (x, d), computed pointwise from
    /// the full strains (no cancellation of the reference Gram matrix).
    pub fn state_geometric(&self, x: &[Vec3; 4], d: &[Vec3; 4]) -> Sym {
        self.geometric(&self.state_stresses(x, d).1)
    }

    /// The assumed strains at Gauss point `gi` from the sampling points.
    fn combine(gi: usize, e_pt: &[Strain; NPT]) -> SMatrix<f64, NSTRAIN, 1> {
        let w = ans_weights(gi);
        SMatrix::from_fn(|c, _| w[c].iter().map(|&(i, w)| w * e_pt[i][c]).sum())
    }

    /// EAS condensation and stresses: from the compatible strains at the
    /// sampling points, the stress weights Σ w dA s at the sampling points
    /// (s = D (e_c + G α), α = −H⁻¹ ∫ Gᵀ D e_c) and the Gauss-point stresses.
    fn stresses(&self, e_pt: &[Strain; NPT]) -> ([Strain; NPT], [SMatrix<f64, NSTRAIN, 1>; 4]) {
        let e_gp: [SMatrix<f64, NSTRAIN, 1>; 4] = std::array::from_fn(|gi| Self::combine(gi, e_pt));
        let mut ra = SMatrix::<f64, NEAS, 1>::zeros();
        for (gp, e) in self.gps.iter().zip(&e_gp) {
            ra += gp.g.transpose() * gp.stress(self.moments, e) * gp.da;
        }
        let alpha = -(self.hinv * ra);
        let mut sig = [[0.0; NSTRAIN]; NPT];
        let mut s_gp = [SMatrix::<f64, NSTRAIN, 1>::zeros(); 4];
        for (k, (gp, e)) in self.gps.iter().zip(&e_gp).enumerate() {
            let s = gp.stress(self.moments, &(e + gp.g * alpha));
            for (c, weights) in ans_weights(k).iter().enumerate() {
                for &(i, w) in weights {
                    sig[i][c] += w * gp.da * s[c];
                }
            }
            s_gp[k] = s;
        }
        (sig, s_gp)
    }

    fn vectors(&self, x: &[Vec3; 4], d: &[Vec3; 4]) -> [PointVectors; NPT] {
        std::array::from_fn(|i| points()[i].vectors(x, d))
    }

    /// [`ShellElement::internal`] and [`ShellElement::state_geometric`]
    /// (packed) from one computation of the strains and stresses: the same
    /// values as the two calls.
    pub fn internal_and_geometric(
        &self,
        x: &[Vec3; 4],
        d: &[Vec3; 4],
    ) -> ([f64; NDOF_EL], PackedSym) {
        let (xv, sig) = self.state_stresses(x, d);
        (Self::force(&xv, &sig), pack(&self.geometric(&sig)))
    }

    /// The point vectors and the sampling-point stress weights at the
    /// state (x, d), from the full strains.
    fn state_stresses(&self, x: &[Vec3; 4], d: &[Vec3; 4]) -> ([PointVectors; NPT], [Strain; NPT]) {
        let xv = self.vectors(x, d);
        let e_pt: [Strain; NPT] = std::array::from_fn(|i| strain(&xv[i], &self.ref_vec[i]));
        let sig = self.stresses(&e_pt).0;
        (xv, sig)
    }

    /// f = Σ Bᵀ σ over the sampling points.
    fn force(xv: &[PointVectors; NPT], sig: &[Strain; NPT]) -> [f64; NDOF_EL] {
        let mut f = [0.0; NDOF_EL];
        for i in 0..NPT {
            points()[i].bt_sigma(&xv[i], &sig[i], &mut f);
        }
        f
    }

    /// Condensed internal force f = ∫ Bᵀ s dA at current nodal positions
    /// `x` and directors `d`. The tangent is the order-1 operator of the
    /// element series ([`super::series::ElementSeries::tangent`]).
    pub fn internal(&self, x: &[Vec3; 4], d: &[Vec3; 4]) -> [f64; NDOF_EL] {
        let (xv, sig) = self.state_stresses(x, d);
        Self::force(&xv, &sig)
    }

    /// Membrane force resultant N (force per unit length) at the state:
    /// N = t S^αβ G_α ⊗ G_β (α, β = 1, 2; S the second Piola–Kirchhoff
    /// stress with its EAS part, G the reference basis), averaged over the
    /// Gauss points with their area weights; a Cartesian 3×3 tensor in the
    /// reference tangent plane (the Cauchy resultant to first order in the
    /// strain). `s` holds (S^11, S^22, 2 S^12) (the conjugate of the tensor
    /// strains, material.rs).
    pub fn membrane_resultant(&self, x: &[Vec3; 4], d: &[Vec3; 4]) -> Matrix3<f64> {
        let xv = self.vectors(x, d);
        let e_pt: [Strain; NPT] = std::array::from_fn(|i| strain(&xv[i], &self.ref_vec[i]));
        let (_, s_gp) = self.stresses(&e_pt);
        let mut n = Matrix3::zeros();
        let mut area = 0.0;
        for (gi, (gp, s)) in self.gps.iter().zip(&s_gp).enumerate() {
            let [g1, g2, ..] = self.ref_vec[gi];
            let ng = g1 * g1.transpose() * s[0]
                + g2 * g2.transpose() * s[1]
                + (g1 * g2.transpose() + g2 * g1.transpose()) * (0.5 * s[2]);
            n += ng * gp.da;
            area += gp.da;
        }
        n / area
    }

    /// The full map K, unpacked unless `cache` holds this element's map.
    fn full_map<'c>(&self, cache: &'c mut FullMapCache) -> &'c FullMap {
        let (map, full) = match cache.0.take() {
            Some((map, full)) if Arc::ptr_eq(&map, &self.kmap) => (map, full),
            _ => (Arc::clone(&self.kmap), Box::new(self.kmap.full())),
        };
        &cache.0.insert((map, full)).1
    }

    /// The linear map from the unknowns δY of Y to the packed
    /// K(YᵀδY + δYᵀY): the change of Kg(σ) along δY at the nodal vectors Y.
    /// The column of the unknown (dim, b) has YᵀδY + δYᵀY nonzero in row
    /// and column b only, so it sums 7 of the 28 columns of K.
    pub fn gram_jacobian(&self, y: &NodalVectors, cache: &mut FullMapCache) -> GramJacobian {
        let kmap = self.full_map(cache).as_slice();
        let mut t = GramJacobian::zeros();
        for (b, out) in t.as_mut_slice().chunks_exact_mut(3 * NSYM).enumerate() {
            for (dim, out) in out.chunks_exact_mut(NSYM).enumerate() {
                // Summed in registers over the 7 columns of K it draws on.
                let mut acc = [0.0; NSYM];
                for a in 0..NCOL {
                    // (YᵀδY + δYᵀY)_ab = Y[dim, a], doubled on the diagonal.
                    let w = if a == b {
                        2.0 * y[(dim, a)]
                    } else {
                        y[(dim, a)]
                    };
                    let col = &kmap[SYM_INDEX[a][b] * NSYM..][..NSYM];
                    for (o, c) in acc.iter_mut().zip(col) {
                        *o += w * c;
                    }
                }
                out.copy_from_slice(&acc);
            }
        }
        t
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A curved, distorted element far from the origin.
    pub(crate) fn element() -> (ShellElement, [Vec3; 4], [Vec3; 4]) {
        let far = Vec3::new(40.0, -25.0, 10.0);
        let x = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.11, 0.01, 0.02),
            Vec3::new(0.12, 0.09, 0.01),
            Vec3::new(-0.01, 0.1, 0.03),
        ]
        .map(|v| v + far);
        let d = [
            Vec3::new(0.1, 0.0, 1.0),
            Vec3::new(-0.1, 0.05, 1.0),
            Vec3::new(0.0, -0.1, 1.0),
            Vec3::new(0.05, 0.05, 1.0),
        ]
        .map(|v| v.normalize());
        let material = Material {
            young: 2e5,
            poisson: 0.3,
        };
        let e = ShellElement::new(0, [0, 1, 2, 3], &x, &d, 0.01, &material).unwrap();
        (e, x, d)
    }

    /// The map K on packed matrices is S times a symmetric matrix (the
    /// premise of GeometricMap's storage), on a curved, distorted element.
    #[test]
    fn geometric_map_is_symmetric_up_to_the_packing_weights() {
        let (e, _, _) = element();
        let k = e.geometric_map();
        let s = crate::shell::geometric_map::weight;
        let scale = k.abs().max();
        for i in 0..NSYM {
            for j in 0..NSYM {
                let asym = (k[(i, j)] / s(i) - k[(j, i)] / s(j)).abs();
                assert!(
                    asym <= 1e-14 * scale,
                    "K[{i},{j}]: asymmetry {asym:.3e} of {scale:.3e}"
                );
            }
        }
        let stored = GeometricMap::from_full(&k).full();
        assert!((stored - k).abs().max() <= 1e-14 * scale);
    }

    /// K a and K b on the unpacked map of a shared map (column sums) equal
    /// the packed triangle's sums to the bit, as the element series'
    /// histories rely on (a run is the same whether its maps are shared).
    #[test]
    fn map_applied_unpacked_equals_the_packed_sums_to_the_bit() {
        let (mut e, _, _) = element();
        let a = PackedSym::from_fn(|i, _| (1.3 * i as f64 + 0.2).sin() * 1e-3);
        let b = PackedSym::from_fn(|i, _| (0.7 * i as f64 - 1.1).cos() * 2e-4);
        let (pa, pb) = e.packed_geometric_pair(&a, &b, &mut FullMapCache::default());
        assert_eq!((pa, pb), e.map().apply_pair(&a, &b));
        // Shared with a congruent element: the unpacked path.
        let twin = Arc::clone(e.map());
        e.set_map(Arc::clone(&twin));
        let mut cache = FullMapCache::default();
        for _ in 0..2 {
            let (fa, fb) = e.packed_geometric_pair(&a, &b, &mut cache);
            assert!(cache.0.is_some(), "the unpacked path was not taken");
            for i in 0..NSYM {
                assert_eq!(fa[i].to_bits(), pa[i].to_bits(), "K a, entry {i}");
                assert_eq!(fb[i].to_bits(), pb[i].to_bits(), "K b, entry {i}");
            }
        }
    }
}
