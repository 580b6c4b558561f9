//! Is a region's (multi)polygon valid by the OGC simple-features rules GIS tools apply? Checked in
//! O(n log n) in its vertex count, because full-resolution boundaries bring 10⁵–10⁷ vertices and
//! geo's `Validation` compares every segment of a ring with every other (quadratic: minutes for
//! one region of 200,000 vertices).
//!
//! One segment index over all rings of the geometry finds every pair of segments that meet
//! other than at the vertex joining consecutive segments (or, where long segments' boxes crowd
//! the index, a sweep finds the first such pair); such a pair is a crossing, a collinear overlap
//! or a ring touching itself, all invalid, except that two different rings may touch at a
//! point. With no such pair, the rings are disjoint curves, so one point of each
//! ring decides how the rings nest: each hole inside its own shell and outside its polygon's
//! other holes, no part inside another part. A geometry of one ring that is star-shaped about
//! its centroid is simple without either, in O(n) ([`star_shaped`]).

use super::geometry::{crosses_ray, Segment};
use geo::kernels::{Kernel, Orientation, RobustKernel};
use geo::line_intersection::{line_intersection, LineIntersection};
use geo::{Centroid, Coord, Line, LineString, MultiPolygon, Polygon};
use rstar::{Envelope, RTree, RTreeObject, AABB};
use std::collections::BTreeSet;
use std::fmt;
use std::ops::Bound::{Excluded, Unbounded};

/// The first problem found, with a place in the layer's coordinates where there is one.
#[derive(Clone, Debug, PartialEq)]
pub enum Problem {
    /// A ring has fewer than three distinct vertices.
    TooFewPoints,
    /// A ring crosses, overlaps or touches itself.
    SelfIntersection(Coord<f64>),
    /// A ring doubles back along itself at a vertex (a zero-width spike).
    Spike(Coord<f64>),
    /// Two rings cross or share a stretch of boundary.
    RingsIntersect(Coord<f64>),
    /// A hole lies outside its polygon's shell, or inside another hole.
    HoleOutside,
    /// One part of a multipolygon lies inside another.
    PartsOverlap,
}

impl Problem {
    /// What is wrong, without where: the same words for every polygon with this kind of
    /// problem, so that many repairs can be counted by kind.
    pub fn kind(&self) -> &'static str {
        match self {
            Problem::TooFewPoints => "a ring has fewer than 3 distinct vertices",
            Problem::SelfIntersection(_) => "a ring intersects itself",
            Problem::Spike(_) => "a ring doubles back on itself (a spike)",
            Problem::RingsIntersect(_) => "two rings cross or overlap",
            Problem::HoleOutside => "a hole lies outside its polygon's shell",
            Problem::PartsOverlap => "one part of the multipolygon lies inside another",
        }
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Problem::SelfIntersection(c) | Problem::Spike(c) | Problem::RingsIntersect(c) => {
                write!(f, "{} at ({}, {})", self.kind(), c.x, c.y)
            }
            _ => f.write_str(self.kind()),
        }
    }
}

/// One ring of the geometry: its polygon and whether it is the shell.
struct RingRole {
    polygon: usize,
    shell: bool,
}

/// `None` for a valid geometry (finite coordinates assumed), else the first problem found.
pub fn problem(geometry: &MultiPolygon<f64>) -> Option<Problem> {
    examine(geometry).problem
}

/// What checking a geometry finds: its first problem (`None`: valid), and whether its segments
/// crowd its bounding box (see [`CROWDED`]): long segments whose boxes overlap, like a star's
/// spikes, which any sweep meets most of at once. A repair chooses its method by that; a ring
/// found valid without an index ([`star_shaped`]) reports `false`.
#[derive(Clone, Debug, PartialEq)]
pub struct Examined {
    pub problem: Option<Problem>,
    pub crowded: bool,
}

/// The geometry checked, the problem found by the sweep where its segments crowd, else by
/// comparing nearby pairs; a ring of fewer than three distinct vertices is not crowded.
pub fn examine(geometry: &MultiPolygon<f64>) -> Examined {
    examined(geometry, |index| index.crowded())
}

/// [`examine`], the problem found by the sweep where `sweep` says so.
fn examined(geometry: &MultiPolygon<f64>, sweep: impl Fn(&Runs) -> bool) -> Examined {
    let Some((rings, roles)) = rings_of(geometry) else {
        return Examined {
            problem: Some(Problem::TooFewPoints),
            crowded: false,
        };
    };
    if let [ring] = rings.as_slice() {
        if star_shaped(ring) {
            return Examined {
                problem: None,
                crowded: false,
            };
        }
    }
    let index = Runs::new(&rings);
    let problem =
        first_contact(&index, &rings, sweep(&index)).or_else(|| nesting(&index, &rings, &roles));
    Examined {
        problem,
        crowded: index.crowded(),
    }
}

/// Whether `ring` (open, without repeated vertices) is simple because it is star-shaped about
/// its area centroid: seen from there, every edge turns the same way, strictly, and the ring goes
/// round once. The vertices' directions then rise strictly through one turn, so each edge keeps
/// to its own sector and meets no other but at their shared vertices. O(n) with exact
/// orientation tests, where the segment index or the sweep is O(n log n); `false` decides
/// nothing. Compact regions pass (a star of 200,000 vertices: its sweep was a third of the run).
fn star_shaped(ring: &[Coord<f64>]) -> bool {
    let n = ring.len();
    let edge = |i: usize| (ring[i], ring[(i + 1) % n]);
    let Some(centre) = Polygon::new(LineString(ring.to_vec()), vec![]).centroid() else {
        return false;
    };
    let centre = centre.0;
    if !(centre.x.is_finite() && centre.y.is_finite()) {
        return false;
    }
    let turn = RobustKernel::orient2d(centre, ring[0], ring[1]);
    if turn == Orientation::Collinear {
        return false;
    }
    // Turns about the centre: the edges that cross the ray from it towards +x, each once,
    // counted with a half-open rule so that a vertex on the ray counts once.
    let mut turns = 0;
    for i in 0..n {
        let (a, b) = edge(i);
        if RobustKernel::orient2d(centre, a, b) != turn {
            return false;
        }
        let (from, to) = match turn {
            Orientation::CounterClockwise => (a, b),
            _ => (b, a),
        };
        if from.y < centre.y && centre.y <= to.y {
            turns += 1;
        }
    }
    turns == 1
}

/// Rings as the checks take them: open, without repeated vertices.
type Rings = Vec<Vec<Coord<f64>>>;

/// The geometry's rings with their roles; `None` if a ring has fewer than three distinct
/// vertices.
fn rings_of(geometry: &MultiPolygon<f64>) -> Option<(Rings, Vec<RingRole>)> {
    let mut rings: Rings = Vec::new();
    let mut roles: Vec<RingRole> = Vec::new();
    for (polygon, p) in geometry.0.iter().enumerate() {
        let shell = std::iter::once((p.exterior(), true));
        for (ring, is_shell) in shell.chain(p.interiors().iter().map(|h| (h, false))) {
            // Repeated vertices are harmless (zero-length segments): drop them, and the closing
            // vertex, so that consecutive segments are the only ones sharing a vertex.
            let mut coords: Vec<Coord<f64>> = ring.0.clone();
            coords.dedup();
            if coords.len() > 1 && coords.first() == coords.last() {
                coords.pop();
            }
            if coords.len() < 3 {
                return None;
            }
            rings.push(coords);
            roles.push(RingRole {
                polygon,
                shell: is_shell,
            });
        }
    }
    Some((rings, roles))
}

/// How many runs' boxes cover a point of the geometry's box, on average, above which the
/// segments are left to the sweep. A boundary of short segments covers a small part of its box
/// (each run meets two or three neighbouring runs), and comparing the pairs whose boxes meet is
/// then several times faster than the sweep; long segments whose boxes overlap, like a star's
/// spikes, cover it hundreds of times over, and those pairs grow with their square.
const CROWDED: f64 = 8.0;

/// The first problem between segments, found by the sweep or by comparing every pair of
/// segments whose bounding boxes meet.
fn first_contact(index: &Runs, rings: &[Vec<Coord<f64>>], by_sweep: bool) -> Option<Problem> {
    if by_sweep {
        return sweep(index, rings);
    }
    (index.tree.iter())
        .flat_map(|a| {
            (index.tree.locate_in_envelope_intersecting(&a.envelope))
                .filter(move |b| (b.ring, b.start) >= (a.ring, a.start))
                .map(move |b| (a, b))
        })
        .flat_map(|(a, b)| index.segment_pairs(a, b))
        .find_map(|(s, t)| contact(index, rings, &s, &t))
}

/// The first contact between segments that makes the rings invalid, found by a sweep from left
/// to right (a Shamos–Hoey sweep that lets rings touch): a vertical order of the segments the
/// sweep line crosses, in which a crossing shows as two neighbours meeting. Segments meet only at
/// vertices or at crossings; at each vertex every pair of segments through it is checked, and
/// after each change to the order, the new neighbours. Until the first crossing the segments'
/// order is that of where they start, so the leftmost problem is found before any order goes
/// wrong, and the sweep stops there. O(n log n) in the segments, however long and close they
/// are: an index of bounding boxes compares every pair of a star's spikes.
fn sweep(index: &Runs, rings: &[Vec<Coord<f64>>]) -> Option<Problem> {
    // The segments in ring order, and two events per segment: where it starts and where it
    // ends, with its number times two, plus one for the end.
    let mut segments: Vec<Swept> = Vec::new();
    let mut events: Vec<(Coord<f64>, usize)> = Vec::new();
    for (ring, coords) in rings.iter().enumerate() {
        for i in 0..coords.len() {
            let s = index.segment(ring, i);
            let (left, right) = if before(s.a, s.b) {
                (s.a, s.b)
            } else {
                (s.b, s.a)
            };
            events.push((left, 2 * segments.len()));
            events.push((right, 2 * segments.len() + 1));
            segments.push(Swept {
                left,
                right,
                ring,
                index: i,
            });
        }
    }
    // Where events share a point, in ring order, a start before an end: a total order, which
    // an unstable sort (faster) keeps.
    events.sort_unstable_by(|(p, e), (q, f)| {
        (p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y))).then(e.cmp(f))
    });
    let starts = |e: &(Coord<f64>, usize)| e.1.is_multiple_of(2);
    let segment = |e: &(Coord<f64>, usize)| segments[e.1 / 2];
    let mut order: BTreeSet<Key> = BTreeSet::new();
    let check = |u: &Swept, v: &Swept| {
        let (s, t) = (
            index.segment(u.ring, u.index),
            index.segment(v.ring, v.index),
        );
        let (s, t) = if (s.ring, s.index) < (t.ring, t.index) {
            (s, t)
        } else {
            (t, s)
        };
        contact(index, rings, &s, &t)
    };
    // Reused for every vertex: the segments through it.
    let mut through: Vec<Swept> = Vec::new();
    for group in events.chunk_by(|(p, _), (q, _)| p == q) {
        let p = group[0].0;
        let below = Key::Probe(p);
        // Every segment through `p`: those in the order that contain it (ending there or
        // passing through, next to each other) and those starting there. The segments just
        // below and just above them stay where they are while those through `p` change, so
        // one walk up from `p` and one step down find them all: four searches of the order
        // per vertex (with the removal and the insertion), where one per neighbour took seven.
        through.clear();
        let mut over = None;
        for key in order.range((Excluded(&below), Unbounded)) {
            match key.swept() {
                Some(s) if on_swept(p, s) => through.push(*s),
                s => {
                    over = s.copied();
                    break;
                }
            }
        }
        let under = (order.range((Unbounded, Excluded(&below))).next_back())
            .and_then(Key::swept)
            .copied();
        let ending = through.len();
        through.extend(group.iter().filter(|e| starts(e)).map(segment));
        for (k, u) in through.iter().enumerate() {
            if let Some(problem) = through[k + 1..].iter().find_map(|v| check(u, v)) {
                return Some(problem);
            }
        }
        for e in group {
            if !starts(e) {
                order.remove(&Key::Segment(segment(e)));
            }
        }
        for e in group {
            if starts(e) {
                order.insert(Key::Segment(segment(e)));
            }
        }
        // The new neighbours: below and above the segments through `p` now (those passing
        // through and those starting here), or each other.
        let mut now = (through[..ending].iter())
            .filter(|s| s.right != p)
            .chain(&through[ending..]);
        let pairs = match now.next() {
            Some(&first) => {
                let (lowest, highest) = now.fold((first, first), |(l, h), &s| {
                    let key = Key::Segment(s);
                    (
                        if key < Key::Segment(l) { s } else { l },
                        if key > Key::Segment(h) { s } else { h },
                    )
                });
                [(under, Some(lowest)), (Some(highest), over)]
            }
            None => [(under, over), (None, None)],
        };
        for (u, v) in pairs {
            if let Some(problem) = u.zip(v).and_then(|(u, v)| check(&u, &v)) {
                return Some(problem);
            }
        }
    }
    None
}

/// Sweep order: by x, then y (a vertical segment is swept bottom to top).
fn before(p: Coord<f64>, q: Coord<f64>) -> bool {
    (p.x, p.y) < (q.x, q.y)
}

/// A segment with its ends in sweep order.
#[derive(Clone, Copy, Debug)]
struct Swept {
    left: Coord<f64>,
    right: Coord<f64>,
    ring: usize,
    index: usize,
}

fn on_swept(p: Coord<f64>, s: &Swept) -> bool {
    RobustKernel::orient2d(s.left, s.right, p) == Orientation::Collinear
}

/// An entry of the sweep's vertical order, or a point placed just below every segment through
/// it, to find the segments around it.
#[derive(Debug)]
enum Key {
    Segment(Swept),
    Probe(Coord<f64>),
}

impl Key {
    fn swept(&self) -> Option<&Swept> {
        match self {
            Key::Segment(s) => Some(s),
            Key::Probe(..) => None,
        }
    }
}

impl Ord for Key {
    fn cmp(&self, other: &Key) -> std::cmp::Ordering {
        use std::cmp::Ordering;
        // Which side of `s` the point `p` lies on: above is counter-clockwise of left → right.
        let side = |s: &Swept, p: Coord<f64>| match RobustKernel::orient2d(s.left, s.right, p) {
            Orientation::CounterClockwise => Some(Ordering::Greater),
            Orientation::Clockwise => Some(Ordering::Less),
            Orientation::Collinear => None,
        };
        match (self, other) {
            (Key::Probe(_), Key::Probe(_)) => Ordering::Equal,
            (Key::Probe(p), Key::Segment(s)) => side(s, *p).unwrap_or(Ordering::Less),
            (Key::Segment(_), Key::Probe(..)) => other.cmp(self).reverse(),
            (Key::Segment(a), Key::Segment(b)) => {
                if (a.ring, a.index) == (b.ring, b.index) {
                    return Ordering::Equal;
                }
                // Compared where the later one starts (both are crossed by the sweep line
                // there), or by where it goes if it starts on the other.
                let (later, earlier, flip) = if before(a.left, b.left) {
                    (b, a, true)
                } else {
                    (a, b, false)
                };
                let order = side(earlier, later.left)
                    .or_else(|| side(earlier, later.right))
                    .unwrap_or_else(|| {
                        // Collinear: an overlap, reported when they meet; any fixed order.
                        (later.ring, later.index).cmp(&(earlier.ring, earlier.index))
                    });
                if flip {
                    order.reverse()
                } else {
                    order
                }
            }
        }
    }
}

impl PartialOrd for Key {
    fn partial_cmp(&self, other: &Key) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl PartialEq for Key {
    fn eq(&self, other: &Key) -> bool {
        self.cmp(other) == std::cmp::Ordering::Equal
    }
}

impl Eq for Key {}

/// Segments indexed by runs of [`RUN`] consecutive ones of a ring: a dense ring is spatially
/// coherent, so a run's bounding box is small, and the index holds a run's worth fewer
/// entries than one of single segments (building it was most of the check's time).
struct Runs<'r> {
    rings: &'r [Vec<Coord<f64>>],
    tree: RTree<Run>,
}

/// Segments `start..end` of ring `ring`.
struct Run {
    ring: usize,
    start: usize,
    end: usize,
    envelope: AABB<[f64; 2]>,
}

impl RTreeObject for Run {
    type Envelope = AABB<[f64; 2]>;
    fn envelope(&self) -> Self::Envelope {
        self.envelope
    }
}

const RUN: usize = 8;

impl<'r> Runs<'r> {
    fn new(rings: &'r [Vec<Coord<f64>>]) -> Runs<'r> {
        let mut runs = Vec::new();
        for (ring, coords) in rings.iter().enumerate() {
            for start in (0..coords.len()).step_by(RUN) {
                let end = (start + RUN).min(coords.len());
                let first = coords[start];
                let envelope = ((start + 1)..=end).map(|i| coords[i % coords.len()]).fold(
                    AABB::from_point([first.x, first.y]),
                    |mut b, c| {
                        b.merge(&AABB::from_point([c.x, c.y]));
                        b
                    },
                );
                runs.push(Run {
                    ring,
                    start,
                    end,
                    envelope,
                });
            }
        }
        Runs {
            rings,
            tree: RTree::bulk_load(runs),
        }
    }

    fn segment(&self, ring: usize, index: usize) -> Segment {
        let coords = &self.rings[ring];
        Segment {
            a: coords[index],
            b: coords[(index + 1) % coords.len()],
            ring,
            index,
        }
    }

    fn run_segments<'a>(&'a self, run: &'a Run) -> impl Iterator<Item = Segment> + 'a {
        (run.start..run.end).map(move |i| self.segment(run.ring, i))
    }

    /// Whether the runs' boxes cover the geometry's box more than [`CROWDED`] times over.
    fn crowded(&self) -> bool {
        let area = |b: &AABB<[f64; 2]>| {
            let (lower, upper) = (b.lower(), b.upper());
            (upper[0] - lower[0]) * (upper[1] - lower[1])
        };
        let covered: f64 = self.tree.iter().map(|run| area(&run.envelope)).sum();
        covered > CROWDED * area(&self.tree.root().envelope())
    }

    /// The pairs of segments of runs `a` and `b` whose bounding boxes meet, once each.
    fn segment_pairs<'a>(
        &'a self,
        a: &'a Run,
        b: &'a Run,
    ) -> impl Iterator<Item = (Segment, Segment)> + 'a {
        self.run_segments(a).flat_map(move |s| {
            let envelope = s.envelope();
            self.run_segments(b)
                .filter(move |t| {
                    (t.ring, t.index) > (s.ring, s.index) && t.envelope().intersects(&envelope)
                })
                .map(move |t| (s, t))
        })
    }

    /// The segments whose bounding boxes meet `envelope`.
    fn segments_near<'a>(
        &'a self,
        envelope: &'a AABB<[f64; 2]>,
    ) -> impl Iterator<Item = Segment> + 'a {
        self.tree
            .locate_in_envelope_intersecting(envelope)
            .flat_map(move |run| self.run_segments(run))
            .filter(move |s| s.envelope().intersects(envelope))
    }

    /// Whether `t` is the segment after `s` in their ring.
    fn follows(&self, s: &Segment, t: &Segment) -> bool {
        s.ring == t.ring && (s.index + 1) % self.rings[s.ring].len() == t.index
    }

    /// How many segments of the rings `include` accepts the ray from `p` towards +x crosses.
    fn crossings(&self, p: Coord<f64>, include: impl Fn(usize) -> bool) -> usize {
        let far = self.tree.root().envelope().upper()[0];
        let ray = AABB::from_corners([p.x, p.y], [far.max(p.x), p.y]);
        self.segments_near(&ray)
            .filter(|s| include(s.ring) && crosses_ray(s, p))
            .count()
    }
}

/// A problem between `s` and `t`, two segments whose bounding boxes meet.
#[inline(always)]
fn contact(index: &Runs, rings: &[Vec<Coord<f64>>], s: &Segment, t: &Segment) -> Option<Problem> {
    if index.follows(s, t) || index.follows(t, s) {
        return spike(index, s, t);
    }
    let meeting = line_intersection(Line::new(s.a, s.b), Line::new(t.a, t.b))?;
    let (at, invalid) = match meeting {
        LineIntersection::Collinear { intersection } => (intersection.start, true),
        // Two rings may touch at a point (a hole touching its shell, parts meeting at a
        // corner) but not cross there, which they can at a vertex too.
        LineIntersection::SinglePoint {
            intersection,
            is_proper,
        } => (
            intersection,
            s.ring == t.ring || is_proper || crosses_at_vertex(rings, s, t),
        ),
    };
    match invalid {
        false => None,
        true if s.ring == t.ring => Some(Problem::SelfIntersection(at)),
        true => Some(Problem::RingsIntersect(at)),
    }
}

/// Whether the rings of `s` and `t`, which meet at an end of one of them, cross there: one ring
/// passes from one side of the other to the other side. Exact (robust orientations).
fn crosses_at_vertex(rings: &[Vec<Coord<f64>>], s: &Segment, t: &Segment) -> bool {
    let Some(p) = [s.a, s.b, t.a, t.b]
        .into_iter()
        .find(|&p| on(p, s) && on(p, t))
    else {
        return false;
    };
    // The two points a ring goes to from `p`: its neighbours if `p` is its vertex, else the
    // ends of the segment through `p`.
    let arms = |u: &Segment| {
        let ring = &rings[u.ring];
        let n = ring.len();
        if p == u.a {
            (ring[(u.index + n - 1) % n], u.b)
        } else if p == u.b {
            (u.a, ring[(u.index + 2) % n])
        } else {
            (u.a, u.b)
        }
    };
    let (from, to) = arms(s);
    let (q1, q2) = arms(t);
    match (in_sweep(p, from, to, q1), in_sweep(p, from, to, q2)) {
        (Some(a), Some(b)) => a != b,
        // An arm along the other ring's is a shared stretch, which its own pair of segments
        // reports.
        _ => false,
    }
}

/// Whether `p` lies on the segment `u` (exact).
fn on(p: Coord<f64>, u: &Segment) -> bool {
    RobustKernel::orient2d(u.a, u.b, p) == Orientation::Collinear
        && p.x >= u.a.x.min(u.b.x)
        && p.x <= u.a.x.max(u.b.x)
        && p.y >= u.a.y.min(u.b.y)
        && p.y <= u.a.y.max(u.b.y)
}

/// Whether the direction from `p` to `q` lies strictly inside the counter-clockwise sweep from
/// the direction of `from` to that of `to` (`None`: along one of them).
fn in_sweep(p: Coord<f64>, from: Coord<f64>, to: Coord<f64>, q: Coord<f64>) -> Option<bool> {
    let orient = |a, b| RobustKernel::orient2d(p, a, b);
    let along = |d: Coord<f64>| {
        orient(d, q) == Orientation::Collinear
            && (d - p).x * (q - p).x + (d - p).y * (q - p).y > 0.0
    };
    if along(from) || along(to) {
        return None;
    }
    let left = |a, b| orient(a, b) == Orientation::CounterClockwise;
    Some(match orient(from, to) {
        Orientation::CounterClockwise => left(from, q) && left(q, to),
        Orientation::Clockwise => left(from, q) || left(q, to),
        // A straight pass (a fold back is a spike, found first).
        Orientation::Collinear => left(from, q),
    })
}

/// For consecutive segments of a ring: the ring turning back along itself where one ends and
/// the next begins (in a ring of three vertices each follows the other, so both joins count).
fn spike(index: &Runs, s: &Segment, t: &Segment) -> Option<Problem> {
    let folds = |first: &Segment, next: &Segment| {
        let (before, at, after) = (first.a, first.b, next.b);
        index.follows(first, next)
            && RobustKernel::orient2d(before, at, after) == Orientation::Collinear
            && (before - at).x * (after - at).x + (before - at).y * (after - at).y > 0.0
    };
    if folds(s, t) {
        Some(Problem::Spike(s.b))
    } else if folds(t, s) {
        Some(Problem::Spike(t.b))
    } else {
        None
    }
}

/// With no two rings meeting (other than touching at points), whether every hole lies in its
/// own shell and outside its polygon's other holes, and no part lies inside another part. The
/// rings being disjoint, any point of a ring that touches no other ring tells on which side of
/// every other ring the whole ring lies.
fn nesting(index: &Runs, rings: &[Vec<Coord<f64>>], roles: &[RingRole]) -> Option<Problem> {
    for (k, ring) in rings.iter().enumerate() {
        let role = &roles[k];
        let Some(probe) = probe(index, ring, k) else {
            continue;
        };
        if role.shell {
            // Inside an odd number of the other parts' rings: inside another part.
            let inside = index.crossings(probe, |r| roles[r].polygon != role.polygon) % 2 == 1;
            if inside {
                return Some(Problem::PartsOverlap);
            }
        } else {
            // Inside its shell and none of its polygon's other holes: inside an odd number of
            // its polygon's other rings.
            let held = index.crossings(probe, |r| r != k && roles[r].polygon == role.polygon);
            if held.is_multiple_of(2) {
                return Some(Problem::HoleOutside);
            }
        }
    }
    None
}

/// A point of ring `k` (a segment's midpoint) on no other ring; `None` if every midpoint is a
/// touching point, which needs another ring's vertex on each.
fn probe(index: &Runs, ring: &[Coord<f64>], k: usize) -> Option<Coord<f64>> {
    (0..ring.len()).find_map(|i| {
        let m = (ring[i] + ring[(i + 1) % ring.len()]) / 2.0;
        let near = AABB::from_point([m.x, m.y]);
        let touched = index.segments_near(&near).any(|u| u.ring != k && on(m, &u));
        (!touched).then_some(m)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use geo::{wkt, MultiPolygon, Polygon};

    fn check(p: Polygon<f64>) -> Option<Problem> {
        problem(&MultiPolygon(vec![p]))
    }

    #[test]
    fn valid_polygons_pass() {
        assert_eq!(check(wkt!(POLYGON((0. 0.,4. 0.,4. 4.,0. 4.,0. 0.)))), None);
        // Repeated vertices, an unclosed ring's worth of closing vertex, a triangle.
        assert_eq!(check(wkt!(POLYGON((0. 0.,4. 0.,4. 0.,4. 4.,0. 0.)))), None);
        // A hole touching its shell at a point, and parts meeting at a corner: valid (OGC).
        let touching = wkt!(POLYGON((0. 0.,4. 0.,4. 4.,0. 4.,0. 0.),(0. 2.,2. 1.,2. 3.,0. 2.)));
        assert_eq!(check(touching), None);
        let corner =
            wkt!(MULTIPOLYGON(((0. 0.,1. 0.,1. 1.,0. 1.,0. 0.)),((1. 1.,2. 1.,2. 2.,1. 2.,1. 1.))));
        assert_eq!(problem(&corner), None);
        // An island inside a lake of another part.
        let island = wkt!(MULTIPOLYGON(((0. 0.,9. 0.,9. 9.,0. 9.,0. 0.),(2. 2.,2. 7.,7. 7.,7. 2.,2. 2.)),((3. 3.,6. 3.,6. 6.,3. 6.,3. 3.))));
        assert_eq!(problem(&island), None);
    }

    #[test]
    fn each_kind_of_invalid_polygon_is_named() {
        let bowtie = wkt!(POLYGON((0. 0.,2. 2.,2. 0.,0. 2.,0. 0.)));
        assert_eq!(
            check(bowtie),
            Some(Problem::SelfIntersection(Coord { x: 1.0, y: 1.0 }))
        );
        // A spike also touches the ring where it leaves it, which may be found first.
        let spike = wkt!(POLYGON((0. 0.,4. 0.,4. 4.,6. 4.,4. 4.,0. 4.,0. 0.)));
        assert!(matches!(
            check(spike),
            Some(Problem::Spike(_) | Problem::SelfIntersection(_))
        ));
        let folded = wkt!(POLYGON((0. 0.,2. 0.,1. 0.,0. 0.)));
        assert!(matches!(check(folded), Some(Problem::Spike(_))));
        // A ring that touches itself at a vertex (a figure eight): invalid by OGC.
        let eight = wkt!(POLYGON((0. 0.,2. 0.,2. 2.,4. 2.,4. 4.,2. 4.,2. 2.,0. 2.,0. 0.)));
        assert!(matches!(check(eight), Some(Problem::SelfIntersection(_))));
        let crossing_hole =
            wkt!(POLYGON((0. 0.,4. 0.,4. 4.,0. 4.,0. 0.),(3. 1.,5. 1.,5. 2.,3. 2.,3. 1.)));
        assert!(matches!(
            check(crossing_hole),
            Some(Problem::RingsIntersect(_))
        ));
        let outside =
            wkt!(POLYGON((0. 0.,4. 0.,4. 4.,0. 4.,0. 0.),(5. 1.,6. 1.,6. 2.,5. 2.,5. 1.)));
        assert_eq!(check(outside), Some(Problem::HoleOutside));
        let nested = wkt!(POLYGON((0. 0.,9. 0.,9. 9.,0. 9.,0. 0.),(1. 1.,8. 1.,8. 8.,1. 8.,1. 1.),(2. 2.,7. 2.,7. 7.,2. 7.,2. 2.)));
        assert_eq!(check(nested), Some(Problem::HoleOutside));
        let inner =
            wkt!(MULTIPOLYGON(((0. 0.,9. 0.,9. 9.,0. 9.,0. 0.)),((3. 3.,6. 3.,6. 6.,3. 6.,3. 3.))));
        assert_eq!(problem(&inner), Some(Problem::PartsOverlap));
        let shared_edge =
            wkt!(MULTIPOLYGON(((0. 0.,1. 0.,1. 1.,0. 1.,0. 0.)),((1. 0.,2. 0.,2. 1.,1. 1.,1. 0.))));
        assert!(matches!(
            problem(&shared_edge),
            Some(Problem::RingsIntersect(_))
        ));
        let line = wkt!(POLYGON((0. 0.,1. 0.,0. 0.)));
        assert_eq!(check(line), Some(Problem::TooFewPoints));
    }

    #[test]
    fn a_ring_star_shaped_about_its_centroid_is_simple_and_one_winding_twice_is_not() {
        let around = |radii: &[f64], turns: f64| -> Vec<Coord<f64>> {
            let n = radii.len() as f64;
            (radii.iter().enumerate())
                .map(|(k, &r)| {
                    let t = turns * std::f64::consts::TAU * k as f64 / n;
                    Coord {
                        x: r * t.cos(),
                        y: r * t.sin(),
                    }
                })
                .collect()
        };
        // A star of 1,000 spikes, either way round: star-shaped, valid without an index.
        let spikes: Vec<f64> = (0..2000).map(|k| [0.9, 0.58][k % 2]).collect();
        let star = around(&spikes, 1.0);
        assert!(star_shaped(&star));
        let reversed: Vec<Coord<f64>> = star.iter().rev().copied().collect();
        assert!(star_shaped(&reversed));
        let polygon = |ring: Vec<Coord<f64>>| Polygon::new(ring.into(), vec![]);
        assert_eq!(check(polygon(star)), None);
        // A pentagram turns the same way at every edge but winds twice: it crosses itself.
        let pentagram = around(&[1.0; 5], 2.0);
        assert!(!star_shaped(&pentagram));
        assert!(matches!(
            check(polygon(pentagram)),
            Some(Problem::SelfIntersection(_))
        ));
        // A C, simple but not star-shaped about its centroid (outside it): left to the index.
        let c = wkt!(POLYGON((0. 0.,3. 0.,3. 1.,1. 1.,1. 2.,3. 2.,3. 3.,0. 3.,0. 0.)));
        let open = &c.exterior().0[..c.exterior().0.len() - 1];
        assert!(!star_shaped(open));
        assert_eq!(check(c), None);
    }

    #[test]
    fn agrees_with_geo_on_random_small_polygons() {
        use geo::{LineString, Validation};
        use rand::{Rng, SeedableRng};
        // Vertices on a 5×5 integer grid make collinear runs, touches and shared stretches
        // common, the cases a floating-point check gets wrong.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut ring = |n: usize, x0: i32, size: i32| {
            let coords: Vec<Coord<f64>> = (0..n)
                .map(|_| Coord {
                    x: f64::from(x0 + rng.random_range(0..size)),
                    y: f64::from(x0 + rng.random_range(0..size)),
                })
                .collect();
            LineString::from(coords)
        };
        let mut polygon = |case: usize| {
            let exterior = ring(3 + case % 5, 0, 5);
            let holes = if case.is_multiple_of(3) {
                vec![ring(3 + case % 2, 1, 3)]
            } else {
                vec![]
            };
            let mut polygon = Polygon::new(exterior, holes);
            polygon.exterior_mut(|r| r.close());
            polygon
        };
        let (mut valid, mut disagreements) = (0, Vec::new());
        for case in 0..6000 {
            // A third of the cases have two parts, which may overlap, touch or nest.
            let parts = if case % 3 == 1 { 2 } else { 1 };
            let geometry = MultiPolygon((0..parts).map(|k| polygon(case + k)).collect());
            let ours = problem(&geometry).is_none();
            valid += usize::from(ours);
            // geo passes some rings with no area (collinear vertices); OGC calls them
            // self-intersecting, as this check does.
            use geo::Area;
            let degenerate = (geometry.0.iter())
                .flat_map(|p| std::iter::once(p.exterior()).chain(p.interiors()))
                .any(|r| Polygon::new(r.clone(), vec![]).unsigned_area() == 0.0);
            if ours != geometry.is_valid() && !degenerate {
                disagreements.push(geometry);
            }
        }
        assert!(valid > 200, "too few valid cases to compare: {valid}");
        assert!(
            disagreements.is_empty(),
            "{:?}",
            &disagreements[..disagreements.len().min(3)]
        );
    }

    #[test]
    fn the_sweep_and_the_pairs_find_the_same_problems() {
        use geo::LineString;
        use rand::{Rng, SeedableRng};
        // Star-shaped rings snapped to an integer grid: mostly valid, with collinear runs,
        // vertical segments, holes and parts that touch, cross or nest.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let (mut valid, mut kinds) = (0, std::collections::BTreeSet::new());
        for case in 0..20_000 {
            let size = 4 + 2 * (case % 6) as i32;
            let mut ring = |n: usize, x0: i32, size: i32| {
                let c = f64::from(x0) + f64::from(size) / 2.0;
                let coords = (0..n).map(|i| {
                    let a =
                        std::f64::consts::TAU * (i as f64 + rng.random_range(0.0..0.9)) / n as f64;
                    let r = f64::from(size) / 2.0 * rng.random_range(0.3..1.0);
                    Coord {
                        x: (c + r * a.cos()).round(),
                        y: (c + r * a.sin()).round(),
                    }
                });
                let mut ring = LineString(coords.collect());
                ring.close();
                ring
            };
            let parts = 1 + case % 3;
            let geometry = MultiPolygon(
                (0..parts)
                    .map(|k| {
                        let holes = match (case + k) % 3 {
                            0 => vec![ring(3 + case % 3, 2, size - 4)],
                            _ => vec![],
                        };
                        let x0 = k as i32 * (size - 1 - case as i32 % 3);
                        Polygon::new(ring(3 + (case + k) % 9, x0, size), holes)
                    })
                    .collect(),
            );
            let by_sweep = super::examined(&geometry, |_| true).problem;
            let by_pairs = super::examined(&geometry, |_| false).problem;
            assert_eq!(
                by_sweep.is_none(),
                by_pairs.is_none(),
                "{geometry:?}: {by_sweep:?} / {by_pairs:?}"
            );
            valid += usize::from(by_sweep.is_none());
            // Either may meet another problem first where a geometry has several.
            if let Some(problem) = &by_sweep {
                kinds.insert(
                    format!("{problem:?}")
                        .split('(')
                        .next()
                        .unwrap()
                        .to_string(),
                );
            }
        }
        assert!(valid > 5_000, "too few valid cases: {valid}");
        assert!(kinds.len() >= 4, "too few kinds of problem: {kinds:?}");
    }

    /// `n` vertices (not closed) alternating between radius 1 and `inner`.
    fn star_ring(n: usize, inner: f64) -> Vec<Coord<f64>> {
        (0..n)
            .map(|k| {
                let t = k as f64 / n as f64 * std::f64::consts::TAU;
                let r = if k % 2 == 0 { 1.0 } else { inner };
                Coord {
                    x: r * t.cos(),
                    y: r * t.sin(),
                }
            })
            .collect()
    }

    #[test]
    fn a_star_is_left_to_the_sweep_and_a_square_is_not() {
        // 20,000 spikes whose boxes overlap: valid, then with one tip pulled across its
        // neighbour.
        let n = 40_000;
        let mut coords = star_ring(n, 0.6);
        let rings = vec![coords.clone()];
        assert!(Runs::new(&rings).crowded());
        let star = |c: &[Coord<f64>]| Polygon::new(geo::LineString(c.to_vec()), vec![]);
        // Valid, found so without the sweep (star-shaped), and by the sweep.
        assert_eq!(check(star(&coords)), None);
        assert_eq!(sweep(&Runs::new(&rings), &rings), None);
        let t = 3.0 / n as f64 * std::f64::consts::TAU;
        coords[0] = Coord {
            x: t.cos(),
            y: t.sin(),
        };
        let examined = examine(&MultiPolygon(vec![star(&coords)]));
        assert!(examined.crowded);
        assert!(matches!(
            examined.problem,
            Some(Problem::SelfIntersection(_))
        ));
        let square: Vec<Coord<f64>> = (0..n)
            .map(|k| {
                let s = (k % (n / 4)) as f64 / (n / 4) as f64;
                [(s, 0.0), (1.0, s), (1.0 - s, 1.0), (0.0, 1.0 - s)][k / (n / 4)].into()
            })
            .collect();
        assert!(!Runs::new(std::slice::from_ref(&square)).crowded());
        // Star-shaped too, so `examine` decides it without an index (and reports it uncrowded
        // whatever the index would say): the index's own verdict is the one above.
        assert_eq!(check(Polygon::new(geo::LineString(square), vec![])), None);
    }

    #[test]
    fn agrees_with_geo_on_a_dense_valid_ring() {
        // A 20,000-vertex star: every vertex near-collinear with its neighbours.
        let rings = vec![star_ring(20_000, 0.9999)];
        let star = Polygon::new(geo::LineString(rings[0].clone()), vec![]);
        assert_eq!(check(star), None);
        // Star-shaped, so decided without an index: the index and the sweep agree.
        let index = Runs::new(&rings);
        assert_eq!(first_contact(&index, &rings, false), None);
        assert_eq!(first_contact(&index, &rings, true), None);
    }
}
