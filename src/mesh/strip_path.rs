//! The strip of a processing line as a built-in mesh: a strip that runs
//! from a start point over a sequence of rollers to an end point, straight
//! between them (their common tangents) and wrapped on arcs around each.
//!
//! The rollers are cylinders with axes parallel to x; the path lies in the
//! (y, z) plane and the strip spans the width [x0, x1] along x. Each roller
//! is wrapped clockwise (`cw`) or counterclockwise (`ccw`) as seen from +x
//! (y to the right, z up): a strip running along +y over the top of a
//! roller turns down, clockwise. The mid-surface runs at the distance
//! `offset` from each roller (eq. 3 needs an initial gap), so the arcs have
//! the radius r = R + offset.
//!
//! Tangent from circle A to circle B (centres c, signed radii ρ = ±r, +
//! for ccw, 0 for a point): the direction d and the contact points
//! p = c − ρ J d (J the rotation by +90°, the centre of a ccw wrap lies to
//! the left J d of the strip) satisfy (p_B − p_A) · J d = 0, i.e.
//! Δ · J d = ρ_B − ρ_A with Δ = c_B − c_A; so
//! d = √(1 − a²) Δ̂ − a J Δ̂, a = (ρ_B − ρ_A) / |Δ| (the root with
//! d · Δ > 0). No tangent exists where |a| ≥ 1 (the circles overlap or a
//! point lies inside a roller).
//!
//! Mesh: [`super::structured::grid`] with s across the width (i) and t
//! along the path (j), so `t0` is the start edge and `t1` the end edge;
//! each straight piece and arc gets ⌈L / h⌉ elements along the path. Node
//! groups per roller `<name>`: `<name>_in` and `<name>_out` (the rows where
//! the strip meets and leaves it: cross-sections for tension probes) and
//! `<name>_arc` (every node on the arc); `wrapped`, the nodes of every arc
//! (contact candidates).

use super::structured::grid;
use super::{Mesh, Vec3};
use nalgebra::Vector2;
use std::f64::consts::TAU;

type V2 = Vector2<f64>;

/// The rotation by +90° in the (y, z) plane (from +y toward +z).
fn rot90(d: V2) -> V2 {
    V2::new(-d.y, d.x)
}

/// How the strip goes around a roller, seen from +x.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Turn {
    Clockwise,
    Counterclockwise,
}

impl Turn {
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "cw" => Some(Self::Clockwise),
            "ccw" => Some(Self::Counterclockwise),
            _ => None,
        }
    }

    fn sign(self) -> f64 {
        match self {
            Self::Clockwise => -1.0,
            Self::Counterclockwise => 1.0,
        }
    }
}

/// A roller the strip wraps: its centre (y, z) and radius R.
#[derive(Clone, Debug)]
pub struct Roller {
    pub name: String,
    pub centre: [f64; 2],
    pub radius: f64,
    pub turn: Turn,
}

/// A piece of the path: a straight line, or an arc about a roller's centre
/// from the polar angle `start` by `sweep` (signed, + ccw).
#[derive(Clone, Debug)]
enum Piece {
    Line {
        from: V2,
        to: V2,
    },
    Arc {
        centre: V2,
        r: f64,
        start: f64,
        sweep: f64,
    },
}

impl Piece {
    fn length(&self) -> f64 {
        match self {
            Piece::Line { from, to } => (to - from).norm(),
            Piece::Arc { r, sweep, .. } => r * sweep.abs(),
        }
    }

    /// Position and unit direction of travel at the fraction f ∈ [0, 1].
    fn at(&self, f: f64) -> (V2, V2) {
        match self {
            Piece::Line { from, to } => (from + (to - from) * f, (to - from).normalize()),
            Piece::Arc {
                centre,
                r,
                start,
                sweep,
            } => {
                let a = start + sweep * f;
                let radial = V2::new(a.cos(), a.sin());
                (centre + radial * *r, rot90(radial) * sweep.signum())
            }
        }
    }
}

/// The path: lines and arcs in order, the wrap angle of each roller
/// (radians) and the index of its arc in `pieces`.
#[derive(Clone, Debug)]
pub struct StripPath {
    pieces: Vec<Piece>,
    pub wraps: Vec<f64>,
    arcs: Vec<usize>,
}

impl StripPath {
    /// Length of the whole path.
    pub fn length(&self) -> f64 {
        self.pieces.iter().map(Piece::length).sum()
    }

    /// Whether a straight piece passes within the circle of `centre` and
    /// `radius` (an obstacle the path does not wrap, which the strip would
    /// then start inside of).
    pub fn crosses(&self, centre: [f64; 2], radius: f64) -> bool {
        let c = V2::from(centre);
        self.pieces.iter().any(|p| match *p {
            Piece::Line { from, to } => distance_to_segment(c, from, to) < radius,
            Piece::Arc { .. } => false,
        })
    }
}

/// The common tangent of two circles (centre, signed radius): the direction
/// and the two contact points (module doc).
fn tangent(ca: V2, ra: f64, cb: V2, rb: f64) -> Option<(V2, V2, V2)> {
    let delta = cb - ca;
    let l = delta.norm();
    if l == 0.0 {
        return None;
    }
    let a = (rb - ra) / l;
    if a.abs() >= 1.0 {
        return None;
    }
    let dh = delta / l;
    let d = dh * (1.0 - a * a).sqrt() - rot90(dh) * a;
    Some((d, ca - rot90(d) * ra, cb - rot90(d) * rb))
}

/// Distance from the point c to the segment [from, to].
fn distance_to_segment(c: V2, from: V2, to: V2) -> f64 {
    let f = ((c - from).dot(&(to - from)) / (to - from).norm_squared()).clamp(0.0, 1.0);
    (from + (to - from) * f - c).norm()
}

/// The path from `start` over the rollers to `end`, with the strip at
/// `offset` from each roller surface. Errors say what is wrong in words.
pub fn path(
    start: [f64; 2],
    end: [f64; 2],
    rollers: &[Roller],
    offset: f64,
) -> Result<StripPath, String> {
    // Circles: the start point, each roller (signed radius), the end point.
    let mut circles: Vec<(V2, f64, String)> =
        vec![(V2::from(start), 0.0, "the start point".into())];
    for r in rollers {
        circles.push((
            V2::from(r.centre),
            r.turn.sign() * (r.radius + offset),
            format!("roller `{}`", r.name),
        ));
    }
    circles.push((V2::from(end), 0.0, "the end point".into()));
    let mut lines = Vec::with_capacity(circles.len() - 1);
    for w in circles.windows(2) {
        let (ca, ra, na) = &w[0];
        let (cb, rb, nb) = &w[1];
        let t = tangent(*ca, *ra, *cb, *rb).ok_or_else(|| {
            format!("no straight strip runs from {na} to {nb}: they overlap (or a point lies inside a roller)")
        })?;
        lines.push(t);
    }
    let mut pieces = Vec::new();
    let mut wraps = Vec::new();
    let mut arcs = Vec::new();
    for (k, &(d, from, to)) in lines.iter().enumerate() {
        if k > 0 {
            let roller = &rollers[k - 1];
            let (centre, _, name) = &circles[k];
            let d_in = lines[k - 1].0;
            let s = roller.turn.sign();
            let turned = d.y.atan2(d.x) - d_in.y.atan2(d_in.x);
            let wrap = (s * turned).rem_euclid(TAU);
            if !(wrap > 1e-9 && wrap < TAU - 1e-9) {
                return Err(format!(
                    "the strip does not wrap {name} (wrap angle {:.3e} degrees): check `turn` and the positions",
                    // + 0: rem_euclid keeps the sign of a −0 turn.
                    wrap.to_degrees() + 0.0
                ));
            }
            let p_in = lines[k - 1].2;
            let radial = p_in - centre;
            pieces.push(Piece::Arc {
                centre: *centre,
                r: roller.radius + offset,
                start: radial.y.atan2(radial.x),
                sweep: s * wrap,
            });
            arcs.push(pieces.len() - 1);
            wraps.push(wrap);
        }
        pieces.push(Piece::Line { from, to });
        // A straight piece must not cross another roller.
        for (m, r) in rollers.iter().enumerate() {
            if m + 1 == k || m == k {
                continue;
            }
            let gap = distance_to_segment(V2::from(r.centre), from, to) - r.radius;
            if gap < offset {
                return Err(format!(
                    "the straight strip from {} to {} passes through roller `{}`",
                    circles[k].2,
                    circles[k + 1].2,
                    r.name
                ));
            }
        }
    }
    let path = StripPath {
        pieces,
        wraps,
        arcs,
    };
    if let Some((a, b, at)) = path.self_crossing() {
        // Names of the straight pieces: line k runs from circle k to k + 1.
        let line = |k: usize| format!("from {} to {}", circles[k].2, circles[k + 1].2);
        let what = match b {
            Crossed::Line(b) => format!("the straight strip {}", line(b)),
            Crossed::Arc(m) => format!("the strip's wrap of {}", circles[m + 1].2),
        };
        return Err(format!(
            "the strip's path crosses itself: the straight strip {} meets {what} at (y, z) = ({:.4}, {:.4}); a roller wrapped the wrong way round does this: check `turn`",
            line(a),
            at.x,
            at.y
        ));
    }
    Ok(path)
}

/// What a straight piece of the path crosses ([`StripPath::self_crossing`]):
/// another straight piece (by its index among the lines) or a roller's wrap
/// (by the roller's index).
enum Crossed {
    Line(usize),
    Arc(usize),
}

impl StripPath {
    /// The first crossing of a straight piece with a later straight piece
    /// or with a wrap it does not join (review 10: `turn = ["cw", "cw",
    /// "cw"]` for an S-line made two spans cross, and the run solved that
    /// impossible line with exit 0): the indices of the line and of what it
    /// meets, and the point. Arcs are tested as chords of 1/2 degree.
    fn self_crossing(&self) -> Option<(usize, Crossed, V2)> {
        let lines: Vec<(usize, V2, V2)> = self
            .pieces
            .iter()
            .enumerate()
            .filter_map(|(i, p)| match *p {
                Piece::Line { from, to } => Some((i, from, to)),
                Piece::Arc { .. } => None,
            })
            .collect();
        for (a, &(ia, p, q)) in lines.iter().enumerate() {
            for (b, &(_, r, s)) in lines.iter().enumerate().skip(a + 1) {
                if let Some(x) = segments_cross(p, q, r, s) {
                    return Some((a, Crossed::Line(b), x));
                }
            }
            for (m, &ic) in self.arcs.iter().enumerate() {
                // The wraps that this line leaves or reaches share its ends.
                if ic + 1 == ia || ia + 1 == ic {
                    continue;
                }
                let chords = ((self.pieces[ic].length() / self.radius_of(ic)).to_degrees() * 2.0)
                    .ceil()
                    .max(1.0) as usize;
                for k in 0..chords {
                    let (c0, _) = self.pieces[ic].at(k as f64 / chords as f64);
                    let (c1, _) = self.pieces[ic].at((k + 1) as f64 / chords as f64);
                    if let Some(x) = segments_cross(p, q, c0, c1) {
                        return Some((a, Crossed::Arc(m), x));
                    }
                }
            }
        }
        None
    }

    fn radius_of(&self, piece: usize) -> f64 {
        match self.pieces[piece] {
            Piece::Arc { r, .. } => r,
            Piece::Line { .. } => f64::INFINITY,
        }
    }
}

/// The point where the segments [p, q] and [r, s] cross (touching ends
/// included), if they do.
fn segments_cross(p: V2, q: V2, r: V2, s: V2) -> Option<V2> {
    let cross = |a: V2, b: V2| a.x * b.y - a.y * b.x;
    let (d1, d2) = (q - p, s - r);
    let den = cross(d1, d2);
    if den == 0.0 {
        return None;
    }
    let t = cross(r - p, d2) / den;
    let u = cross(r - p, d1) / den;
    ((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u)).then(|| p + d1 * t)
}

/// The strip mesh of `path`: width [x0, x1] in `across` elements, pieces
/// cut into ⌈L / h⌉ elements with h = `line_h` on lines, `arc_h` on arcs.
/// `names` are the rollers' names (the groups of the module doc).
pub fn mesh(
    path: &StripPath,
    x: [f64; 2],
    across: usize,
    line_h: f64,
    arc_h: f64,
    names: &[String],
) -> Mesh {
    // Stations (position, direction) of the node rows along the path.
    let mut stations: Vec<(V2, V2)> = Vec::new();
    let mut arc_rows = Vec::new();
    for (k, piece) in path.pieces.iter().enumerate() {
        let h = if path.arcs.contains(&k) {
            arc_h
        } else {
            line_h
        };
        let n = ((piece.length() / h).ceil() as usize).max(1);
        let first = stations.len().saturating_sub(1);
        let from = if stations.is_empty() { 0 } else { 1 };
        for e in from..=n {
            stations.push(piece.at(e as f64 / n as f64));
        }
        if path.arcs.contains(&k) {
            arc_rows.push((first, stations.len() - 1));
        }
    }
    let ny = stations.len() - 1;
    let mut m = grid("strip path", across, ny, |i, j| {
        let xi = x[0] + (x[1] - x[0]) * i as f64 / across as f64;
        let (p, d) = stations[j];
        let normal = rot90(d);
        (Vec3::new(xi, p.x, p.y), Vec3::new(0.0, normal.x, normal.y))
    });
    m.notes.push(format!(
        "strip path {:.6} long (in the scene's length unit); wrap angles: {}",
        path.length(),
        names
            .iter()
            .zip(&path.wraps)
            .map(|(n, w)| format!("{n} {:.6} deg", w.to_degrees()))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    let g = m.grid.expect("a structured mesh");
    let mut wrapped: Vec<usize> = arc_rows
        .iter()
        .flat_map(|&(a, b)| (a..=b).flat_map(|j| g.row(j)))
        .collect();
    wrapped.sort_unstable();
    wrapped.dedup();
    m.groups.insert("wrapped".into(), wrapped);
    for (name, &(j_in, j_out)) in names.iter().zip(&arc_rows) {
        m.groups.insert(format!("{name}_in"), g.row(j_in));
        m.groups.insert(format!("{name}_out"), g.row(j_out));
        let mut arc: Vec<usize> = (j_in..=j_out).flat_map(|j| g.row(j)).collect();
        arc.sort_unstable();
        m.groups.insert(format!("{name}_arc"), arc);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn roller(name: &str, centre: [f64; 2], turn: Turn) -> Roller {
        Roller {
            name: name.into(),
            centre,
            radius: 0.3,
            turn,
        }
    }

    /// Over one roller from a point 1 m to its left to a point 1 m to its
    /// right, both level with its centre: the strip rises along the tangent
    /// from the point, at β = asin(r / 1) above the horizontal, and comes
    /// down symmetrically, so the wrap is 2 β and the length
    /// 2 √(1 − r²) + 2 β r (closed form).
    #[test]
    fn a_point_to_roller_tangent_has_the_closed_form_wrap() {
        let r = roller("r", [0.0, 0.0], Turn::Clockwise);
        let p = path([-1.0, 0.0], [1.0, 0.0], &[r], 0.0).unwrap();
        let beta = (0.3f64).asin();
        assert!(
            (p.wraps[0] - 2.0 * beta).abs() < 1e-14,
            "{} vs {}",
            p.wraps[0],
            2.0 * beta
        );
        let line = (1.0f64 - 0.09).sqrt();
        let expect = 2.0 * line + 0.3 * 2.0 * beta;
        assert!((p.length() - expect).abs() < 1e-14);
    }

    /// An S over two rollers of equal radius (cw then ccw): the inner
    /// tangent; the wraps are equal and the straight piece's direction makes
    /// asin(2 r / |Δ|) with the line of centres.
    #[test]
    fn an_s_wrap_takes_the_inner_tangent() {
        let a = roller("a", [0.0, 0.0], Turn::Clockwise);
        let b = roller("b", [1.0, -0.5], Turn::Counterclockwise);
        let p = path([-1.0, 0.3], [2.0, -0.8], &[a, b], 0.0).unwrap();
        let (d, from, to) = match (&p.pieces[2], &p.pieces[0]) {
            (Piece::Line { from, to }, _) => ((to - from).normalize(), *from, *to),
            _ => panic!("a line between the arcs"),
        };
        // Both ends of the inner tangent lie on their circles, and the line
        // is tangent there (radius ⟂ direction).
        for (q, c) in [(from, V2::new(0.0, 0.0)), (to, V2::new(1.0, -0.5))] {
            assert!(((q - c).norm() - 0.3).abs() < 1e-14);
            assert!((q - c).dot(&d).abs() < 1e-14);
        }
        let centres = V2::new(1.0, -0.5);
        let angle = (centres.normalize().dot(&d)).acos();
        assert!((angle - (0.6 / centres.norm()).asin()).abs() < 1e-13);
        assert!((p.wraps[0] - p.wraps[1]).abs() < 1e-13);
        assert!(p.wraps[0] > 0.0 && p.wraps[0] < PI);
    }

    #[test]
    fn impossible_paths_are_refused() {
        let inside = roller("r", [0.0, 0.0], Turn::Clockwise);
        let e = path([0.1, 0.0], [1.0, 0.0], &[inside], 0.0).unwrap_err();
        assert!(e.contains("the start point") && e.contains("inside"), "{e}");
        // A strip level with the roller's top only touches it.
        let touched = roller("r", [0.0, 0.0], Turn::Clockwise);
        let e = path([-1.0, 0.3], [1.0, 0.3], &[touched], 0.0).unwrap_err();
        assert!(e.contains("does not wrap roller `r`"), "{e}");
        // The straight piece from a to b runs through c.
        let a = roller("a", [0.0, 0.0], Turn::Clockwise);
        let b = roller("b", [2.0, 0.0], Turn::Clockwise);
        let c = roller("c", [1.0, 0.1], Turn::Clockwise);
        let e = path([-1.0, 0.0], [1.0, 2.0], &[a, b, c], 0.0).unwrap_err();
        assert!(e.contains("passes through roller `c`"), "{e}");
        // An S-line over three rollers (review 10) with the middle roller's
        // turn reversed: the spans into and out of it cross at (0.8096,
        // −0.2553) by the reviewer's own geometry.
        let line = |middle: Turn| {
            let mut r2 = roller("r2", [0.8, -0.5], middle);
            r2.radius = 0.15;
            let mut r1 = roller("r1", [0.0, 0.0], Turn::Clockwise);
            r1.radius = 0.2;
            let mut r3 = roller("r3", [1.6, 0.0], Turn::Clockwise);
            r3.radius = 0.2;
            path([-1.0, 0.0], [2.6, 0.0], &[r1, r2, r3], 0.0)
        };
        assert!(line(Turn::Counterclockwise).is_ok());
        let e = line(Turn::Clockwise).unwrap_err();
        assert!(
            e.contains("crosses itself") && e.contains("roller `r2`") && e.contains("`turn`"),
            "{e}"
        );
    }

    /// The mesh's rows follow the path: every arc node at r from the
    /// centre, the roller groups are rows, the exact normals are unit and
    /// normal to the path.
    #[test]
    fn the_mesh_follows_the_path() {
        let rollers = [roller("r1", [0.0, 0.0], Turn::Clockwise)];
        let p = path([-1.0, 0.3], [1.0, 0.3 - 0.5], &rollers, 1e-3).unwrap();
        let m = mesh(&p, [-0.5, 0.5], 4, 0.1, 0.02, &["r1".into()]);
        let g = m.grid.unwrap();
        let arc = &m.groups["r1_arc"];
        for &n in arc {
            let x = m.nodes[n];
            assert!(((x.y * x.y + x.z * x.z).sqrt() - 0.301).abs() < 1e-12);
        }
        assert!(g.row_of(&m.groups["r1_in"]).is_some());
        assert!(g.row_of(&m.groups["r1_out"]).is_some());
        let normals = m.exact_normals.as_ref().unwrap();
        for j in 0..g.ny {
            let a = m.nodes[g.node(0, j)];
            let b = m.nodes[g.node(0, j + 1)];
            assert!(normals[g.node(0, j)].dot(&(b - a)).abs() < 0.1 * (b - a).norm());
        }
        m.directors().expect("a consistent orientation");
    }
}
