//! Step 0 (method.md §1): from the regions, their centroids, which of them are adjacent, and the
//! outline of the whole map (every part with its holes), cleaned and simplified so it keeps about
//! two vertices per region.

use super::geometry::{
    ends_distance2, interior_point, interior_point_of_all, lowest, nearest_on_segment,
    segment_distance2, RingIndex,
};
use super::network::DisjointSets;
use super::overlay::{self, Given};
use super::watch;
use super::Params;
use geo::algorithm::buffer::{BufferStyle, LineJoin};
use geo::orient::{Direction, Orient};
use geo::{
    Area, BoundingRect, Buffer, Centroid, Contains, Coord, Intersects, LineString, MultiPolygon,
    Point, Polygon, Rect, SimplifyVwPreserve, Triangle,
};
use rayon::prelude::*;
use rstar::primitives::{GeomWithData, Line, Rectangle};
use rstar::{Envelope, RTree, RTreeObject, AABB};
use std::cmp::Ordering;
use std::collections::BTreeMap;
use std::collections::BinaryHeap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering as AtomicOrdering};
use std::sync::{Mutex, PoisonError};

/// When two regions' boundaries share a border: where, at one of its reaches at least, they run
/// within the reach of each other for a length above the reach's least.
#[derive(Clone, Copy)]
struct Touching {
    /// Up to [`MOST_REACHES`] of them.
    reaches: &'static [Reach],
}

/// A distance between two boundaries and the length they must run within it to share a border
/// (both in cells).
#[derive(Clone, Copy)]
struct Reach {
    reach: f64,
    least: f64,
}

impl Touching {
    /// The widest reach: how far apart the boundaries searched for each other may lie.
    fn widest(self) -> f64 {
        self.reaches.iter().map(|r| r.reach).fold(0.0, f64::max)
    }
}

/// The most reaches a [`Touching`] tries: down to a 128th of [`GAP_CLOSED`].
const MOST_REACHES: usize = 8;

/// Adjacency as the judge reads it (method.md §8): shared borders that were noded identically
/// meet exactly, but reprojection and rounding leave tiny gaps; and two regions share a border
/// rather than meet at a point above a ten-thousandth of a cell.
const SHARED: Touching = Touching {
    reaches: &[Reach {
        reach: 1e-6,
        least: 1e-4,
    }],
};
/// Neighbours for the layout where the outline's parts were joined across hairline gaps
/// ([`close_gaps`]) or the regions overlap ([`OVERLAP_SEARCHED`]): borders that run within the
/// gap (or the overlap) of each other for ten times its width (corners that come near across a
/// gap run so for a few widths at most, so they are not borders). The gap's width is not known,
/// so reaches from [`GAP_CLOSED`] down, halving, are tried: with the closing's gap alone, a
/// short border across a narrow gap was lost (Delaware and New Jersey, 0.04 cells long and 0.002
/// cells apart: the layout then had no reason to keep them together).
const ACROSS_GAPS: Touching = Touching {
    reaches: &halving_reaches(),
};

/// [`MOST_REACHES`] reaches from [`GAP_CLOSED`] down, each half the one before, each needing a
/// length of ten times itself.
const fn halving_reaches() -> [Reach; MOST_REACHES] {
    let mut reaches = [Reach {
        reach: GAP_CLOSED,
        least: 10.0 * GAP_CLOSED,
    }; MOST_REACHES];
    let mut k = 1;
    while k < MOST_REACHES {
        let reach = 0.5 * reaches[k - 1].reach;
        reaches[k] = Reach {
            reach,
            least: 10.0 * reach,
        };
        k += 1;
    }
    reaches
}

/// Boundary segments per parallel task of the adjacency search.
const ADJACENCY_CHUNK: usize = 4096;
/// Holes smaller than this many cells² are slivers between regions, not lakes (§1).
pub(crate) const SLIVER_AREA: f64 = 0.5;
/// Triangle area, in cells², below which the outline's detail is dropped before anything else
/// is done with it: a hundredth of a cell on both sides, the resolution the method needs
/// (§1; dense boundaries bring vertices a ten-thousandth of a cell apart).
const FINEST_DETAIL: f64 = 0.5e-4;
/// Share of the regions' total area covered twice or more above which neighbours are searched
/// across hairlines as across gaps ([`ACROSS_GAPS`]): regions drawn over each other's borders
/// (each widened by a ten-thousandth of a cell: 3.7e-4 on us_states and nc_counties) share no
/// border the exact reading finds, and us_states kept 3 of its 107 pairs. Far above the union's
/// rounding (at most 5e-9 on the shared layers and the US states and counties at 10⁶
/// vertices).
const OVERLAP_SEARCHED: f64 = 1e-6;
/// Share of the regions' total area covered twice or more above which the overlap is reported:
/// well above rounding, and below a region of a thousand overlapping a neighbour.
const OVERLAP_NOTED: f64 = 1e-3;
/// Gap between parts of the outline, in cells, under which they are one part ([`close_gaps`]):
/// the outline's resolution, as for [`FINEST_DETAIL`].
const GAP_CLOSED: f64 = 1e-2;
/// Corners sharper than this (radians) are bevelled by the closing's widening: a spike's miter
/// would reach out of all proportion.
const MITER_ANGLE: f64 = 0.1;
/// A centroid outside the simplified outline is moved this far inside it, in cells (§1).
const INSIDE_MARGIN: f64 = 0.05;

/// The outline of the map: closed rings (open coordinate chains) in the unit-cell frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Ring {
    pub coords: Vec<Coord<f64>>,
    /// The connected part (mainland, island) the ring belongs to.
    pub part: usize,
    pub hole: bool,
}

/// What the later steps need to know of the regions, in the unit-cell frame.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// One centroid per region (§1), inside the simplified outline: the Snake's node.
    pub centroids: Vec<Coord<f64>>,
    /// The area centroid of each region's whole (multi)polygon: what the metrics measure from
    /// (§8).
    pub area_centroids: Vec<Coord<f64>>,
    /// The union of the regions as it is, every part and hole kept: what the metrics compare
    /// the layout with.
    pub regions_union: MultiPolygon<f64>,
    /// Per region, the part of `regions_union` (its landmass) holding most of its area.
    pub landmass_of: Vec<usize>,
    /// Adjacent pairs (i < j), sorted, as the judge reads them (method.md §8): what the metrics
    /// measure.
    pub adjacency: Vec<(usize, usize)>,
    /// The pairs the layout keeps together (i < j), sorted: the adjacent pairs, and where the
    /// outline's parts were joined across hairline gaps or the regions overlap, the regions
    /// whose borders run along each other across them.
    pub neighbours: Vec<(usize, usize)>,
    /// The simplified outline.
    pub rings: Vec<Ring>,
    /// Per region, the part of the simplified outline (its landmass in the layout) that holds
    /// its centroid.
    pub part_of: Vec<usize>,
    /// The share of the regions' total area covered twice or more ([`overlap_share`]).
    pub overlap: f64,
}

/// Prepares `regions` (unit-cell frame, validated: non-empty, finite, positive area; `valid_here`
/// says, per region, whether its validity was checked in these coordinates and held). `drawn`
/// is each region as drawn, before any repair, whose boundary gives its neighbours: the judge
/// (method.md §8) and the user read adjacency off the boundaries as drawn, and a repair can drop
/// a sliver of no area that runs along a neighbour (an out-and-back stretch of border whose two
/// sides cross), and with it the shared border;
/// `reached` hears the share of the work done as the costly stages (the adjacency, union and
/// simplification, side by side, most of it on dense boundaries) go, from any thread; `None`
/// once it has returned false (cancelled). The adjacency stops within a chunk of its search
/// and the other side between its stages; the two calls that cannot stop (the union's overlay,
/// the sort of the borders) are left to end in the background ([`watch::watched`]).
pub fn prepare(
    regions: &[&MultiPolygon<f64>],
    drawn: &[&MultiPolygon<f64>],
    valid_here: &[bool],
    params: &Params,
    reached: &(dyn Fn(f64, &str) -> bool + Sync),
) -> Option<Prepared> {
    let centroids: Vec<Coord<f64>> = regions.iter().map(|r| centroid(r)).collect();
    let area_centroids = regions
        .iter()
        .zip(&centroids)
        .map(|(r, &fallback)| r.centroid().map_or(fallback, |p| p.0))
        .collect();
    // A repair stays within the box of the region as drawn: the drawn boxes group both.
    let clusters = clusters(drawn, SHARED.widest());
    if !reached(0.05, "outline: adjacency and union") {
        return None;
    }
    // The borders as drawn give the adjacency, and the union of the regions gives the outline:
    // the two do not meet, and on a dense boundary each is a few tenths of a second that one
    // core spends mostly alone (BENCHMARKS.md "Dense boundaries"), so they run side by side.
    let stages = SideBySide::new(reached, expected_costs(drawn, &clusters));
    let (adjacency, other_side) = rayon::join(
        || {
            let adjacency =
                adjacency(drawn, &clusters, params.point_adjacency, SHARED, &|share| {
                    stages.advanced(Stage::Adjacency, share)
                })?;
            stages.ended(Stage::Adjacency).then_some(adjacency)
        },
        || {
            // One overlay call per cluster, which cannot stop itself: watched, and heard by
            // the host as time passes against the time expected for it.
            let expected = stages.expected_seconds(Stage::Union);
            let regions_union = merge(regions, valid_here, &clusters, |seconds| {
                stages.advanced(Stage::Union, watch::expected_share(seconds, expected))
            })?;
            // Each of the next two is a tenth of a second on a union of 3.5 million vertices
            // (the US states at 10⁷): the host is asked between them, the share held.
            let landmass_of = landmasses(regions, &regions_union, &centroids);
            if !stages.advanced(Stage::Union, 0.0) {
                return None;
            }
            let union = clean(regions_union.clone(), &centroids);
            if !stages.ended(Stage::Union) {
                return None;
            }
            // Small layers still keep a quadrilateral per ring on average.
            let target = ((params.vertices_per_region * regions.len() as f64).ceil() as usize)
                .max(4 * rings_of(&union).len());
            let (simplified, joined) =
                simplify(&union, target, params.simplify_tolerance, &|share| {
                    stages.advanced(Stage::Simplification, share)
                })?;
            let simplified = stages.ended(Stage::Simplification).then_some(simplified)?;
            Some((regions_union, landmass_of, simplified, joined))
        },
    );
    let (adjacency, (regions_union, landmass_of, simplified, joined)) = (adjacency?, other_side?);
    // Parts joined across hairline gaps, or regions overlapping along their borders: their
    // borders run within a hairline of each other without meeting.
    let overlap = overlap_share(regions, &regions_union);
    let search_near = joined || overlap > OVERLAP_SEARCHED;
    let neighbours = if search_near {
        let near = self::adjacency(
            drawn,
            &self::clusters(drawn, ACROSS_GAPS.widest()),
            params.point_adjacency,
            ACROSS_GAPS,
            // A second search of every border, heard by the host at the outline's end.
            &|_| reached(0.95, "outline"),
        )?;
        let mut all: Vec<(usize, usize)> = adjacency.iter().chain(&near).copied().collect();
        all.sort_unstable();
        all.dedup();
        all
    } else {
        adjacency.clone()
    };
    let rings = rings_of(&simplified);
    let index = RingIndex::new(&coords_of(&rings));
    let centroids: Vec<Coord<f64>> = centroids
        .into_iter()
        .map(|c| move_inside(c, &index))
        .collect();
    let part_of = parts_holding(&rings, &centroids);
    Some(Prepared {
        centroids,
        area_centroids,
        regions_union,
        landmass_of,
        adjacency,
        neighbours,
        rings,
        part_of,
        overlap,
    })
}

/// The outline's costly stages, which run side by side.
#[derive(Clone, Copy)]
enum Stage {
    Adjacency,
    Union,
    Simplification,
}

impl Stage {
    const ALL: [Stage; 3] = [Stage::Adjacency, Stage::Union, Stage::Simplification];

    fn name(self) -> &'static str {
        match self {
            Stage::Adjacency => "adjacency",
            Stage::Union => "union",
            Stage::Simplification => "simplification",
        }
    }
}

/// The time each [`Stage`] is expected to take, in µs, on `overlaid` vertices of regions with
/// neighbours and `lone` vertices of regions without. Measured on the shared layers densified to
/// 10⁶ vertices, the world among them, and on a star of 10⁶ (2026-12-07, BENCHMARKS.md
/// "Progress"): the adjacency takes 0.16–0.25 µs an edge of a region with neighbours (a lone
/// region has none to find); the union 0.11–0.29 µs a vertex where regions are overlaid, 0.05 µs
/// where a lone region's polygons are its union; the simplification 0.03–0.13 µs an overlaid
/// vertex (the inner borders are gone from the union: it keeps a tenth to a third of them) and
/// about 1 µs a lone region's vertex (all kept: 1.1 µs on the star).
fn costs(overlaid: f64, lone: f64) -> [f64; 3] {
    [
        0.2 * overlaid,
        0.2 * overlaid + 0.05 * lone,
        0.07 * overlaid + 1.0 * lone,
    ]
}

/// [`costs`] on `regions`, grouped in `clusters` (a cluster of one is a lone region).
fn expected_costs(regions: &[&MultiPolygon<f64>], clusters: &[Vec<usize>]) -> [f64; 3] {
    let (mut overlaid, mut lone) = (0.0, 0.0);
    for cluster in clusters {
        let vertices: usize = cluster.iter().map(|&k| vertex_count(regions[k])).sum();
        match cluster.len() {
            1 => lone += vertices as f64,
            _ => overlaid += vertices as f64,
        }
    }
    costs(overlaid, lone)
}

/// The time [`prepare`]'s costly stages are expected to take, in seconds, on `vertices` vertices
/// of `regions` regions, before the regions are grouped: the regions of a layer of more than one
/// taken as having neighbours. The adjacency runs beside the union and the simplification.
pub fn expected_seconds(vertices: usize, regions: usize) -> f64 {
    let v = vertices as f64;
    let [adjacency, union, simplification] = match regions {
        0 | 1 => costs(0.0, v),
        _ => costs(v, 0.0),
    };
    1e-6 * adjacency.max(union + simplification)
}

/// Reports the outline's share done as the [`Stage`]s go, in whichever order they end, and
/// names those still running.
struct SideBySide<'r> {
    reached: &'r (dyn Fn(f64, &str) -> bool + Sync),
    /// Per stage, the time it is expected to take ([`expected_costs`]).
    costs: [f64; 3],
    /// Per stage, the share of it done.
    done: Mutex<[f64; 3]>,
    /// Whether `reached` has returned false.
    stopped: AtomicBool,
}

impl<'r> SideBySide<'r> {
    fn new(reached: &'r (dyn Fn(f64, &str) -> bool + Sync), costs: [f64; 3]) -> Self {
        SideBySide {
            reached,
            costs,
            done: Mutex::new([0.0; 3]),
            stopped: AtomicBool::new(false),
        }
    }

    /// The time `stage` is expected to take, in seconds.
    fn expected_seconds(&self, stage: Stage) -> f64 {
        1e-6 * self.costs[stage as usize]
    }

    /// Whether the work is to stop.
    fn stopped(&self) -> bool {
        self.stopped.load(AtomicOrdering::Relaxed)
    }

    /// `stage` has ended; false if the work is to stop.
    fn ended(&self, stage: Stage) -> bool {
        self.advanced(stage, 1.0)
    }

    /// `stage` has done `share` of its work; false if the work is to stop.
    fn advanced(&self, stage: Stage, share: f64) -> bool {
        if self.stopped() {
            return false;
        }
        // Reported under the lock, so that the shares heard only grow.
        let mut done = self.done.lock().unwrap_or_else(PoisonError::into_inner);
        let own = &mut done[stage as usize];
        *own = own.max(share.clamp(0.0, 1.0));
        // The adjacency runs beside the union and then the simplification, and the outline
        // takes as long as the longer side: the time a side has run, as its share done of the
        // time expected for it says, over that longer time. When the expectations hold, the
        // share heard follows the time; when a side is faster than expected, it jumps ahead at
        // that side's end.
        let side = |stages: &[Stage]| -> (f64, f64) {
            let done = (stages.iter())
                .map(|&s| self.costs[s as usize] * done[s as usize])
                .sum();
            (done, stages.iter().map(|&s| self.costs[s as usize]).sum())
        };
        let (beside, beside_whole) = side(&[Stage::Adjacency]);
        let (then, then_whole) = side(&[Stage::Union, Stage::Simplification]);
        let whole = (beside.max(then) / beside_whole.max(then_whole)).min(1.0);
        let whole = if whole.is_finite() { whole } else { 0.0 };
        // The simplification begins as the union ends.
        let begun =
            |s: &Stage| !matches!(s, Stage::Simplification) || done[Stage::Union as usize] == 1.0;
        let running: Vec<&str> = (Stage::ALL.iter().zip(done.iter()))
            .filter(|(s, &d)| begun(s) && d < 1.0)
            .map(|(s, _)| s.name())
            .collect();
        let message = if running.is_empty() {
            "outline".to_owned()
        } else {
            format!("outline: {}", running.join(" and "))
        };
        if !(self.reached)(0.05 + 0.9 * whole, &message) {
            self.stopped.store(true, AtomicOrdering::Relaxed);
            return false;
        }
        true
    }
}

/// How much the `regions` overlap, when `share`, the share of their total area that their
/// union does not cover (area counted twice or more, [`overlap_share`]), is above
/// [`OVERLAP_NOTED`]: that share, and one pair `(i, j)` to name, region `j`'s interior point
/// lying on region `i`, if some region's does (a duplicated feature, a region drawn over
/// another; overlaps that hold no interior point leave it `None`).
pub fn overlaps(
    regions: &[&MultiPolygon<f64>],
    share: f64,
) -> Option<(f64, Option<(usize, usize)>)> {
    if share.is_nan() || share <= OVERLAP_NOTED {
        return None;
    }
    let boxes = box_tree(regions.iter().map(|r| r.bounding_rect()));
    let pair = (0..regions.len()).find_map(|j| {
        let p = interior_point_of_all(regions[j])?;
        (boxes.locate_all_at_point(&[p.x, p.y]))
            .map(|b| b.data)
            .filter(|&i| i != j && regions[i].contains(&Point(p)))
            .min()
            .map(|i| (i, j))
    });
    Some((share, pair))
}

/// The share of the `regions`' total area that their `union` does not cover: the area counted
/// twice or more (within the union's rounding, either side of 0, when none overlap).
fn overlap_share(regions: &[&MultiPolygon<f64>], union: &MultiPolygon<f64>) -> f64 {
    let total: f64 = regions.iter().map(|r| r.unsigned_area()).sum();
    1.0 - union.unsigned_area() / total
}

/// The bounding boxes `boxes` (none for an empty geometry), each with its index, in an R-tree.
pub(crate) fn box_tree(
    boxes: impl Iterator<Item = Option<Rect<f64>>>,
) -> RTree<GeomWithData<Rectangle<[f64; 2]>, usize>> {
    RTree::bulk_load(
        boxes
            .enumerate()
            .filter_map(|(k, b)| {
                let b = b?;
                let corners = ([b.min().x, b.min().y], [b.max().x, b.max().y]);
                Some(GeomWithData::new(
                    Rectangle::from_corners(corners.0, corners.1),
                    k,
                ))
            })
            .collect(),
    )
}

/// For each point, the part of the outline `rings` whose inside holds it (the nearest part for
/// a point in none, which only rounding can make).
fn parts_holding(rings: &[Ring], points: &[Coord<f64>]) -> Vec<usize> {
    let parts = rings.iter().map(|r| r.part + 1).max().unwrap_or(0);
    let indexes: Vec<RingIndex> = (0..parts)
        .map(|part| {
            let own: Vec<Ring> = rings.iter().filter(|r| r.part == part).cloned().collect();
            RingIndex::new(&coords_of(&own))
        })
        .collect();
    points
        .iter()
        .map(|&p| {
            (0..parts)
                .find(|&k| indexes[k].contains(p))
                .unwrap_or_else(|| {
                    (0..parts)
                        .min_by(|&a, &b| {
                            let d = |k: usize| indexes[k].distance(p);
                            d(a).total_cmp(&d(b)).then(a.cmp(&b))
                        })
                        .unwrap_or(0)
                })
        })
        .collect()
}

/// For each region, the part of `union` that holds most of its area: each of a region's polygons
/// lies in one part (a connected polygon lies in one connected part of the union), found from a
/// point inside it (a region whose polygons all fall outside every part's bounding box, by
/// rounding, belongs to the part nearest its centroid). A part's segment index is built only
/// when needed.
fn landmasses(
    regions: &[&MultiPolygon<f64>],
    union: &MultiPolygon<f64>,
    centroids: &[Coord<f64>],
) -> Vec<usize> {
    let parts: Vec<std::sync::OnceLock<RingIndex>> =
        union.0.iter().map(|_| Default::default()).collect();
    let index = |k: usize| {
        parts[k].get_or_init(|| {
            RingIndex::new(&coords_of(&rings_of(&MultiPolygon(vec![
                union.0[k].clone()
            ]))))
        })
    };
    let boxes = box_tree(union.0.iter().map(|p| p.bounding_rect()));
    // A point of a region lies in the union: when no smaller candidate holds it, the largest
    // does, so that the mainland of a dense layer never needs its index.
    let sizes: Vec<usize> = union.0.iter().map(|p| p.exterior().0.len()).collect();
    let part_of = |p: Coord<f64>| {
        let mut holding: Vec<usize> = (boxes.locate_all_at_point(&[p.x, p.y]))
            .map(|b| b.data)
            .collect();
        holding.sort_unstable_by_key(|&k| (sizes[k], k));
        let largest = holding.pop()?;
        Some(
            holding
                .into_iter()
                .find(|&k| index(k).contains(p))
                .unwrap_or(largest),
        )
    };
    (regions.par_iter().zip(centroids))
        .map(|(region, &centroid)| {
            let mut area = vec![0.0; union.0.len()];
            for polygon in &region.0 {
                if let Some(k) = interior_point(polygon).and_then(part_of) {
                    area[k] += polygon.unsigned_area();
                }
            }
            let held = (0..area.len())
                .filter(|&k| area[k] > 0.0)
                .max_by(|&a, &b| area[a].total_cmp(&area[b]).then(b.cmp(&a)));
            held.unwrap_or_else(|| {
                (0..area.len())
                    .min_by(|&a, &b| {
                        let d = |k: usize| index(k).distance(centroid);
                        d(a).total_cmp(&d(b)).then(a.cmp(&b))
                    })
                    .unwrap_or(0)
            })
        })
        .collect()
}

/// The area centroid, or a point on the surface of the largest part when the centroid falls
/// outside the region (crescents, multipart regions).
fn centroid(region: &MultiPolygon<f64>) -> Coord<f64> {
    if let Some(c) = region.centroid() {
        if region.contains(&c) {
            return c.0;
        }
    }
    let largest = region
        .0
        .iter()
        .max_by(|a, b| a.unsigned_area().total_cmp(&b.unsigned_area()));
    largest
        .and_then(interior_point)
        .or_else(|| interior_point_of_all(region))
        .unwrap_or(Coord { x: 0.0, y: 0.0 })
}

/// A boundary segment of a region, for the adjacency search.
#[derive(Clone, Copy, Debug)]
struct Edge {
    a: Coord<f64>,
    b: Coord<f64>,
    region: usize,
}

impl RTreeObject for Edge {
    type Envelope = AABB<[f64; 2]>;
    fn envelope(&self) -> Self::Envelope {
        AABB::from_corners([self.a.x, self.a.y], [self.b.x, self.b.y])
    }
}

/// Pairs of regions whose boundaries share a line of positive length (or, with
/// `point_adjacency`, any point). Works on the boundaries' segments so that it needs no exact
/// noding: a segment counts as shared where another region's segment runs along it within
/// `reach` (in cells), for a length above `least` (ditto). `reached` hears the share of the work
/// done as it goes, from any thread; `None` once it has returned false.
fn adjacency(
    regions: &[&MultiPolygon<f64>],
    clusters: &[Vec<usize>],
    point_adjacency: bool,
    touching: Touching,
    reached: &(dyn Fn(f64) -> bool + Sync),
) -> Option<Vec<(usize, usize)>> {
    // A region alone in its cluster touches no other.
    let members: Vec<usize> = (clusters.iter().filter(|c| c.len() > 1))
        .flatten()
        .copied()
        .collect();
    let all = (members.iter())
        .map(|&region| vertex_count(regions[region]))
        .sum::<usize>() as f64;
    // The work, per edge, as measured on the US states at 10⁶ vertices (0.03 s a million
    // edges): collecting, keying, sorting and matching every edge (1 + 1 + 2 + 1), then taking
    // out those left to search and indexing them (1.5) and searching them (4). Until
    // the matching says how many are left, all are counted; with `point_adjacency` all are
    // searched, unmatched.
    let matching = if point_adjacency { 1.0 } else { 5.0 };
    let share = |done: f64, left: f64| {
        let whole = matching * all + 5.5 * left;
        if whole > 0.0 {
            done / whole
        } else {
            1.0
        }
    };
    let edges = boundary_edges(regions, &members, &|collected| {
        reached(share(collected * all, all))
    })?;
    // With `point_adjacency` every edge is searched, since regions that meet at a corner share
    // no edge.
    let (shared, searched) = if point_adjacency {
        (Default::default(), edges)
    } else {
        // A sort of 10⁷ edges takes a second and cannot stop itself: watched, and heard by the
        // host as time passes against the time expected for it.
        let expected = 4.0 * all * SECONDS_PER_EDGE;
        let (shared, searched) = watch::watched(
            rayon::current_num_threads(),
            move || shared_vertex_for_vertex(edges),
            |seconds| {
                let done = watch::expected_share(seconds, expected);
                reached(share((1.0 + 4.0 * done) * all, all))
            },
        )?;
        if !reached(share(matching * all, searched.len() as f64)) {
            return None;
        }
        (shared, searched)
    };
    let (left, matched) = (searched.len() as f64, matching * all);
    let runs = edge_runs(&searched);
    let tree = RTree::bulk_load(
        (runs.iter())
            .map(|run| GeomWithData::new(Rectangle::from_aabb(run.envelope), run.edges.clone()))
            .collect(),
    );
    if !reached(share(matched + 1.5 * left, left)) {
        return None;
    }
    let chunks_done = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let chunks = runs.len().div_ceil(ADJACENCY_CHUNK / RUN_EDGES).max(1) as f64;
    // In parallel over fixed chunks of runs, summed chunk by chunk in order: the same sums
    // (to the last bit) with any number of threads.
    let (reaches, reach) = (touching.reaches, touching.widest());
    debug_assert!(reaches.len() <= MOST_REACHES);
    let widened = |b: AABB<[f64; 2]>| {
        AABB::from_corners(
            [b.lower()[0] - reach, b.lower()[1] - reach],
            [b.upper()[0] + reach, b.upper()[1] + reach],
        )
    };
    // Per pair, the length shared within each reach.
    type Lengths = [f64; MOST_REACHES];
    let per_chunk: Vec<BTreeMap<(usize, usize), Lengths>> = runs
        .par_chunks(ADJACENCY_CHUNK / RUN_EDGES)
        .map(|chunk| {
            let mut shared: BTreeMap<(usize, usize), Lengths> = Default::default();
            if stop.load(AtomicOrdering::Relaxed) {
                return shared;
            }
            // The runs near a run, asked of the tree once for all its edges rather than once
            // per edge: boundaries a hairline apart leave every edge to search.
            let mut near_runs: Vec<std::ops::Range<usize>> = Vec::new();
            for run in chunk {
                let region = searched[run.edges.start].region;
                near_runs.clear();
                // Each pair once, from its first region; a run holds one region's edges.
                near_runs.extend(
                    (tree.locate_in_envelope_intersecting(&widened(run.envelope)))
                        .filter(|near| searched[near.data.start].region > region)
                        .map(|near| near.data.clone()),
                );
                for e in &searched[run.edges.clone()] {
                    let search = widened(e.envelope());
                    let near = (near_runs.iter())
                        .flat_map(|edges| &searched[edges.clone()])
                        .filter(|f| f.envelope().intersects(&search));
                    for f in near {
                        let Some(beside) = Beside::of(e, f, reach, point_adjacency) else {
                            continue;
                        };
                        let lengths = shared.entry((e.region, f.region)).or_default();
                        for (length, r) in lengths.iter_mut().zip(reaches) {
                            *length += beside.along_within(r.reach);
                        }
                    }
                }
            }
            let done = chunks_done.fetch_add(1, AtomicOrdering::Relaxed) + 1;
            if !reached(share(
                matched + left * (1.5 + 4.0 * done as f64 / chunks),
                left,
            )) {
                stop.store(true, AtomicOrdering::Relaxed);
            }
            shared
        })
        .collect();
    if stop.into_inner() {
        return None;
    }
    // A border shared vertex for vertex is shared within every reach.
    let mut lengths: BTreeMap<(usize, usize), Lengths> = (shared.into_iter())
        .map(|(pair, length)| (pair, [length; MOST_REACHES]))
        .collect();
    for chunk in per_chunk {
        for (pair, found) in chunk {
            let sums = lengths.entry(pair).or_default();
            for (sum, length) in sums.iter_mut().zip(found) {
                *sum += length;
            }
        }
    }
    let pairs = (lengths.into_iter())
        .filter(|(_, lengths)| {
            point_adjacency || lengths.iter().zip(reaches).any(|(&l, r)| l > r.least)
        })
        .map(|(pair, _)| pair)
        .collect();
    Some(pairs)
}

/// The time, in seconds, one unit of the adjacency's work takes per boundary edge (see
/// [`adjacency`]): 0.03 s a million edges, on the US states at 10⁶ vertices.
const SECONDS_PER_EDGE: f64 = 0.03e-6;

/// Regions whose boundary edges are collected per parallel task of [`boundary_edges`].
const REGIONS_PER_CHUNK: usize = 64;

/// The rings of `region`, each shell before its holes.
fn rings_of_region(region: &MultiPolygon<f64>) -> impl Iterator<Item = &LineString<f64>> {
    (region.0.iter()).flat_map(|p| std::iter::once(p.exterior()).chain(p.interiors()))
}

/// The boundary edges of the `members`, region by region in that order and each ring's in its
/// order. Collected in parallel into their places, since at 10⁷ vertices this alone took a third
/// of a second; `go_on` hears the share collected; `None` once it has returned false.
fn boundary_edges(
    regions: &[&MultiPolygon<f64>],
    members: &[usize],
    go_on: &(dyn Fn(f64) -> bool + Sync),
) -> Option<Vec<Edge>> {
    let counts: Vec<usize> = members.iter().map(|&r| vertex_count(regions[r])).collect();
    let total: usize = counts.iter().sum();
    let blank = Edge {
        a: Coord::zero(),
        b: Coord::zero(),
        region: 0,
    };
    let mut edges = vec![blank; total];
    let mut places: Vec<(usize, &mut [Edge])> = Vec::with_capacity(members.len());
    let mut rest = edges.as_mut_slice();
    for (&region, &count) in members.iter().zip(&counts) {
        let (place, tail) = std::mem::take(&mut rest).split_at_mut(count);
        places.push((region, place));
        rest = tail;
    }
    let (done, stop) = (AtomicUsize::new(0), AtomicBool::new(false));
    places.par_chunks_mut(REGIONS_PER_CHUNK).for_each(|chunk| {
        if stop.load(AtomicOrdering::Relaxed) {
            return;
        }
        let mut count = 0;
        for (region, place) in chunk.iter_mut() {
            let lines = rings_of_region(regions[*region]).flat_map(|ring| ring.lines());
            for (edge, line) in place.iter_mut().zip(lines) {
                *edge = Edge {
                    a: line.start,
                    b: line.end,
                    region: *region,
                };
            }
            count += place.len();
        }
        let before = done.fetch_add(count, AtomicOrdering::Relaxed);
        if !go_on((before + count) as f64 / total.max(1) as f64) {
            stop.store(true, AtomicOrdering::Relaxed);
        }
    });
    (!stop.into_inner()).then_some(edges)
}

/// Borders two regions have vertex for vertex (a topologically built layer shares every inner
/// border so) are shared along their whole length: found by sorting, not searching, which is
/// what keeps millions of vertices fast. Returns the length each pair of regions shares so, and
/// the edges no other region has, left to search for borders that run along each other within
/// the tolerance, in the boundaries' order.
fn shared_vertex_for_vertex(edges: Vec<Edge>) -> (BTreeMap<(usize, usize), f64>, Vec<Edge>) {
    let key = |e: &Edge| {
        let (p, q) = if (e.a.x, e.a.y) <= (e.b.x, e.b.y) {
            (e.a, e.b)
        } else {
            (e.b, e.a)
        };
        // + 0.0 turns −0 into 0, which must match.
        [p.x, p.y, q.x, q.y].map(|v| (v + 0.0).to_bits())
    };
    let mut keyed: Vec<([u64; 4], usize, usize)> = (edges.par_iter().enumerate())
        .map(|(k, e)| (key(e), e.region, k))
        .collect();
    keyed.par_sort_unstable();
    let mut shared: BTreeMap<(usize, usize), f64> = Default::default();
    // Per edge, whether it is left to search.
    let mut rest = vec![false; edges.len()];
    for group in keyed.chunk_by(|a, b| a.0 == b.0) {
        let mut owners: Vec<usize> = group.iter().map(|g| g.1).collect();
        owners.dedup();
        if owners.len() == 1 {
            for g in group {
                rest[g.2] = true;
            }
            continue;
        }
        let e = &edges[group[0].2];
        let length = (e.b - e.a).x.hypot((e.b - e.a).y);
        for (k, &i) in owners.iter().enumerate() {
            for &j in &owners[k + 1..] {
                *shared.entry((i, j)).or_default() += length;
            }
        }
    }
    let searched = (edges.into_iter().zip(rest))
        .filter_map(|(e, r)| r.then_some(e))
        .collect();
    (shared, searched)
}

/// How a boundary edge `f` lies beside another, `e`: worked out once for every reach tried.
struct Beside {
    /// The squared distance between the two edges: 0 where they cross (when crossings are
    /// tested), otherwise the least from an end of one to the other.
    distance2: f64,
    /// How far the farther end of `f` lies from `e`'s line.
    off_line: f64,
    /// The length along `e` that `f` runs on.
    along: f64,
}

impl Beside {
    /// How `f` lies beside `e`, if they come within `reach` of each other. With `crossings`
    /// (point adjacency: a touch at a point makes neighbours), edges that cross or touch are
    /// within every reach, by the exact crossing test. Without, only the lengths along matter,
    /// and those the ends' distances give alike: an edge that crosses `e` with both ends
    /// within a reach of `e`'s line has an end within that reach of `e`, or `e` one within it
    /// of the edge (a unit test holds this on random edges). So neither the crossing test (a
    /// tenth of the run of us_states at 10⁶ vertices drawn apart) nor the distances of an edge
    /// that runs along no length of `e` within `reach` are worked out: most edges a search
    /// meets lie beyond `e`'s ends.
    fn of(e: &Edge, f: &Edge, reach: f64, crossings: bool) -> Option<Beside> {
        let d = e.b - e.a;
        let len = (d.x * d.x + d.y * d.y).sqrt();
        let (off_line, along) = if len == 0.0 {
            (0.0, 0.0)
        } else {
            let u = d / len;
            let off_line = |p: Coord<f64>| ((p - e.a).x * u.y - (p - e.a).y * u.x).abs();
            let along = |p: Coord<f64>| (p - e.a).x * u.x + (p - e.a).y * u.y;
            let (s, t) = (along(f.a), along(f.b));
            (
                off_line(f.a).max(off_line(f.b)),
                (s.max(t).min(len) - s.min(t).max(0.0)).max(0.0),
            )
        };
        if !crossings && (off_line > reach || along == 0.0) {
            return None;
        }
        let distance2 = if crossings {
            segment_distance2(e.a, e.b, f.a, f.b)
        } else {
            ends_distance2(e.a, e.b, f.a, f.b)
        };
        let beside = Beside {
            distance2,
            off_line,
            along,
        };
        beside.within(reach).then_some(beside)
    }

    /// Whether the edges come within `reach` of each other.
    fn within(&self, reach: f64) -> bool {
        self.distance2 <= reach * reach
    }

    /// The length along `e` that `f` runs on within `reach` (both of `f`'s ends within `reach`
    /// of `e`'s line); 0 if the edges do not come that near.
    fn along_within(&self, reach: f64) -> f64 {
        if self.within(reach) && self.off_line <= reach {
            self.along
        } else {
            0.0
        }
    }
}

/// Boundary edges in a row, under one box.
struct EdgeRun {
    /// The edges, as a range of the list they come from.
    edges: std::ops::Range<usize>,
    envelope: AABB<[f64; 2]>,
}

/// The most edges in an [`EdgeRun`]: the adjacency's tree holds runs, not edges, and is built
/// that many times faster (the US states at 10⁶ vertices: 0.15 s for a tree of 419,352 edges),
/// while a search meets a few more edges, each tested by its box first.
const RUN_EDGES: usize = 8;

/// `edges` (in the boundaries' order) cut into runs of up to [`RUN_EDGES`] edges of one region
/// that follow on from each other, so that each run's box stays about as small as its edges.
fn edge_runs(edges: &[Edge]) -> Vec<EdgeRun> {
    let mut runs: Vec<EdgeRun> = Vec::new();
    for (k, e) in edges.iter().enumerate() {
        match runs.last_mut() {
            Some(run)
                if run.edges.len() < RUN_EDGES
                    && edges[k - 1].region == e.region
                    && edges[k - 1].b == e.a =>
            {
                run.edges.end = k + 1;
                run.envelope.merge(&e.envelope());
            }
            _ => runs.push(EdgeRun {
                edges: k..k + 1,
                envelope: e.envelope(),
            }),
        }
    }
    runs
}

/// Groups of regions whose bounding boxes (widened by `reach`) overlap, directly or through
/// others: only regions of one group can touch within `reach`. Each group lists its regions in
/// order, and the groups come in the order of their first regions.
fn clusters(regions: &[&MultiPolygon<f64>], reach: f64) -> Vec<Vec<usize>> {
    let boxes: Vec<Option<AABB<[f64; 2]>>> = regions
        .iter()
        .map(|r| {
            let b = r.bounding_rect()?;
            let t = reach;
            Some(AABB::from_corners(
                [b.min().x - t, b.min().y - t],
                [b.max().x + t, b.max().y + t],
            ))
        })
        .collect();
    let tree: RTree<GeomWithData<Rectangle<[f64; 2]>, usize>> = RTree::bulk_load(
        (boxes.iter().enumerate())
            .filter_map(|(k, b)| Some(GeomWithData::new(Rectangle::from_aabb((*b)?), k)))
            .collect(),
    );
    // Union–find over the overlapping pairs, each group rooted at its smallest region.
    let mut sets = DisjointSets::new(regions.len());
    for (k, b) in boxes.iter().enumerate() {
        let Some(b) = b else { continue };
        for other in tree.locate_in_envelope_intersecting(b) {
            sets.union(k, other.data);
        }
    }
    let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for k in 0..regions.len() {
        groups.entry(sets.find(k)).or_default().push(k);
    }
    groups.into_values().collect()
}

/// The union of all regions, cluster by cluster, since only regions of one cluster can meet;
/// `None` once `go_on`, asked as the overlay runs ([`watch::watched`]), has returned false.
/// Parts come as the polygon overlay writes them, ordered by their lowest vertex (the overlay's
/// order): the simplification keeps each ring's first vertex and later steps number the parts,
/// so both follow from the geometry alone. geo's union reads the winding of the first
/// ring as the rule for all, and layers in the wild mix windings (Shapefile rings run
/// clockwise), so every polygon is oriented first.
fn merge(
    regions: &[&MultiPolygon<f64>],
    valid_here: &[bool],
    clusters: &[Vec<usize>],
    go_on: impl FnMut(f64) -> bool,
) -> Option<MultiPolygon<f64>> {
    let overlays: Vec<(Vec<Polygon<f64>>, Given)> = clusters
        .par_iter()
        .map(|group| {
            let oriented: Vec<Polygon<f64>> = (group.iter())
                .flat_map(|&k| regions[k].0.iter())
                .map(|p| p.orient(Direction::Default))
                .collect();
            let given = match group[..] {
                [k] if valid_here[k] => Given::ValidRegion,
                [_] => Given::Region,
                _ => Given::Regions,
            };
            (oriented, given)
        })
        .collect();
    let union = move || {
        let parts: Vec<Vec<Polygon<f64>>> = (overlays.par_iter())
            .map(|(polygons, given)| overlay::union(polygons, *given))
            .collect();
        by_lowest_vertex(parts.into_iter().flatten())
    };
    watch::watched(rayon::current_num_threads(), union, go_on)
}

/// `parts` ordered by their lowest (x, then y) vertex, as the overlay writes them.
fn by_lowest_vertex(parts: impl Iterator<Item = Polygon<f64>>) -> MultiPolygon<f64> {
    let lowest_vertex = |p: &Polygon<f64>| {
        let ring = &p.exterior().0;
        lowest(ring).map_or(
            Coord {
                x: f64::INFINITY,
                y: f64::INFINITY,
            },
            |k| ring[k],
        )
    };
    let mut parts: Vec<(Coord<f64>, Polygon<f64>)> =
        parts.map(|p| (lowest_vertex(&p), p)).collect();
    parts.sort_by(|(p, _), (q, _)| p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y)));
    MultiPolygon(parts.into_iter().map(|(_, p)| p).collect())
}

/// The parts of `union` that come nearer each other than [`GAP_CLOSED`] joined into one, by a
/// closing (widened by half the gap, then narrowed by as much), the other parts as they are.
/// Regions drawn or simplified apart, one by one, leave hairline gaps between neighbours (North
/// Carolina's counties shrunk by 3.5 m, a ten-thousandth of a cell, gave 108 landmasses: each
/// county an island with a budget of its own, and simplified rings crossing their neighbours');
/// and a strait that narrow is below the outline's resolution. The judge's landmasses
/// (method.md §8) stay those of the exact union: only the layout's outline is closed. Also
/// says whether any parts were joined.
fn close_gaps(union: MultiPolygon<f64>) -> (MultiPolygon<f64>, bool) {
    if union.0.len() < 2 {
        return (union, false);
    }
    let gap = GAP_CLOSED;
    let widened = |b: Rect<f64>| {
        let d = Coord { x: gap, y: gap };
        Rect::new(b.min() - d, b.max() + d)
    };
    let boxes = box_tree(union.0.iter().map(|p| p.bounding_rect().map(widened)));
    // Only segments within another part's widened box can be near it.
    let segments: Vec<GeomWithData<Line<[f64; 2]>, usize>> = (union.0.iter().enumerate())
        .flat_map(|(k, p)| {
            std::iter::once(p.exterior())
                .chain(p.interiors())
                .flat_map(|r| r.lines())
                .map(move |l| (k, l))
        })
        .filter(|(k, l)| {
            let b = l.bounding_rect();
            let envelope = AABB::from_corners([b.min().x, b.min().y], [b.max().x, b.max().y]);
            (boxes.locate_in_envelope_intersecting(&envelope)).any(|o| o.data != *k)
        })
        .map(|(k, l)| GeomWithData::new(Line::new([l.start.x, l.start.y], [l.end.x, l.end.y]), k))
        .collect();
    let tree = RTree::bulk_load(segments);
    let mut sets = DisjointSets::new(union.0.len());
    let coord = |p: [f64; 2]| Coord { x: p[0], y: p[1] };
    for s in tree.iter() {
        let (a, b) = (coord(s.geom().from), coord(s.geom().to));
        let near = widened(Rect::new(a, b));
        let envelope =
            AABB::from_corners([near.min().x, near.min().y], [near.max().x, near.max().y]);
        for t in tree.locate_in_envelope_intersecting(&envelope) {
            if t.data <= s.data || sets.find(t.data) == sets.find(s.data) {
                continue;
            }
            let (c, d) = (coord(t.geom().from), coord(t.geom().to));
            if segment_distance2(a, b, c, d) < gap * gap {
                sets.union(s.data, t.data);
            }
        }
    }
    let mut groups: std::collections::BTreeMap<usize, Vec<Polygon<f64>>> = Default::default();
    for (k, p) in union.0.into_iter().enumerate() {
        groups.entry(sets.find(k)).or_default().push(p);
    }
    let joined = groups.values().any(|parts| parts.len() > 1);
    let style = |d: f64| BufferStyle::new(d).line_join(LineJoin::Miter(MITER_ANGLE));
    // The widening and narrowing leave specks where rings met at a point (a triangle of no
    // size on a joined ring made the outline cross itself): dropped.
    let closed = by_lowest_vertex(groups.into_values().flat_map(|parts| {
        match parts.len() {
            1 => parts,
            _ => MultiPolygon(parts)
                .buffer_with_style(style(0.5 * gap))
                .buffer_with_style(style(-0.5 * gap))
                .0
                .into_iter()
                .filter(|p| p.unsigned_area() >= gap * gap)
                .map(without_slivers)
                .collect(),
        }
    }));
    (closed, joined)
}

/// Drops parts that hold no centroid (stray islands of multipart regions) and fills holes that
/// are slivers between regions rather than lakes or missing regions.
fn clean(union: MultiPolygon<f64>, centroids: &[Coord<f64>]) -> MultiPolygon<f64> {
    let parts = union
        .0
        .into_iter()
        .filter(|part| {
            let Some(bounds) = part.bounding_rect() else {
                return false;
            };
            let shell = Polygon::new(part.exterior().clone(), vec![]);
            (centroids.iter())
                .filter(|c| bounds.intersects(&Point(**c)))
                .any(|&c| shell.contains(&Point(c)))
        })
        .map(without_slivers);
    MultiPolygon(parts.collect())
}

/// `part` with its holes smaller than [`SLIVER_AREA`] filled.
fn without_slivers(part: Polygon<f64>) -> Polygon<f64> {
    let (exterior, holes) = part.into_inner();
    let holes = holes
        .into_iter()
        .filter(|h| Polygon::new(h.clone(), vec![]).unsigned_area() >= SLIVER_AREA)
        .collect();
    Polygon::new(exterior, holes)
}

/// The vertices of `p`'s rings, each counted once: also the number of its boundary edges.
fn vertex_count(p: &MultiPolygon<f64>) -> usize {
    rings_of_region(p)
        .map(|ring| ring.0.len().saturating_sub(1))
        .sum()
}

/// Topology-preserving Visvalingam simplification to about `target` vertices (§1), or with the
/// tolerance the user gave. Detail finer than [`FINEST_DETAIL`] goes first, in one pass, so that
/// dense boundaries cost one pass over their vertices. The tolerance is then the least that
/// leaves plain Visvalingam (ten times faster than the topology-preserving variant, and close
/// enough for "about") with `target` vertices ([`tolerance_for`]); the topology-preserving
/// variant then runs once. geo preserves topology within each part only, so a result whose
/// rings cross each other is refused and the tolerance halved ([`halved`]). Parts nearer each
/// other than the outline's resolution are joined ([`close_gaps`]) once the finest detail is
/// gone (a hairline apart, simplified rings cross); also says whether any were. `heard` hears
/// the share done as the finest detail goes (most of the time on a long, detailed boundary: a
/// second on a star of 10⁶ vertices); `None` once it has returned false.
fn simplify(
    union: &MultiPolygon<f64>,
    target: usize,
    tolerance: Option<f64>,
    heard: &dyn Fn(f64) -> bool,
) -> Option<(MultiPolygon<f64>, bool)> {
    if tolerance.is_none() && vertex_count(union) <= target {
        return Some(close_gaps(union.clone()));
    }
    let finest = FINEST_DETAIL.min(tolerance.unwrap_or(f64::INFINITY));
    // Vertices within a tenth of the finest detail of the last one kept go first, in linear
    // time, then plain Visvalingam, which needs no segment index. The shares are of the time
    // measured on the shared layers densified to 10⁶ vertices and on a star of 10⁶: the first
    // pass is 0.6–0.9 of it where the simplification takes long (the world's coasts, the star),
    // less where it does not (0.2 on the US counties: 0.07 s; BENCHMARKS.md "Progress").
    let thinned = thin(union, 0.1 * finest.sqrt());
    if !heard(0.05) {
        return None;
    }
    let fine = visvalingam(&thinned, finest, &|share| heard(0.05 + 0.8 * share))?;
    let fine = close_gaps(fine);
    if !heard(0.9) {
        return None;
    }
    Some(simplified_from(union, fine, target, tolerance, finest))
}

/// The rest of [`simplify`], from the `fine` outline of `union`.
fn simplified_from(
    union: &MultiPolygon<f64>,
    fine: (MultiPolygon<f64>, bool),
    target: usize,
    tolerance: Option<f64>,
    finest: f64,
) -> (MultiPolygon<f64>, bool) {
    // The fine outline is checked for crossings only once it or a simplification of it has to
    // be: when the simplification passes, its own check suffices (checking the fine outline
    // first was a tenth of the run on a star of long spikes, whose boxes all overlap in the
    // index).
    match tolerance_to_try(&fine.0, target, tolerance) {
        None if !crosses(&fine.0) => return fine,
        None => {}
        Some(eps) => {
            let simplified = fine.0.simplify_vw_preserve(eps);
            if !crosses(&simplified) {
                return (simplified, fine.1);
            }
            if !crosses(&fine.0) {
                return halved(fine, 0.5 * eps);
            }
        }
    }
    // Plain Visvalingam made the fine outline cross itself: the topology-preserving variant
    // makes it instead, or, if its parts still cross each other, the union as it is.
    let fine = Some(close_gaps(union.simplify_vw_preserve(finest)))
        .filter(|(p, _)| !crosses(p))
        .unwrap_or_else(|| close_gaps(union.clone()));
    match tolerance_to_try(&fine.0, target, tolerance) {
        None => fine,
        Some(eps) => halved(fine, eps),
    }
}

/// Whether two rings of `outline` cross, or one crosses itself.
fn crosses(outline: &MultiPolygon<f64>) -> bool {
    RingIndex::new(&coords_of(&rings_of(outline))).self_intersects()
}

/// Tolerances at or below this are not tried: they would simplify nothing.
const SMALLEST_TRIED: f64 = 1e-12;

/// The tolerance to simplify `fine` with: the one given, or the one that leaves about `target`
/// vertices ([`tolerance_for`]); `None` when there is nothing to simplify.
fn tolerance_to_try(
    fine: &MultiPolygon<f64>,
    target: usize,
    tolerance: Option<f64>,
) -> Option<f64> {
    let eps = match tolerance {
        Some(eps) => eps,
        None if vertex_count(fine) <= target => return None,
        None => tolerance_for(fine, target),
    };
    (eps > SMALLEST_TRIED).then_some(eps)
}

/// `fine` (whose rings do not cross, or which is the last resort) simplified by geo's
/// topology-preserving Visvalingam with the first of `eps`, `eps / 2`, `eps / 4`, … whose
/// rings do not cross each other; `fine` itself if none.
fn halved(fine: (MultiPolygon<f64>, bool), mut eps: f64) -> (MultiPolygon<f64>, bool) {
    while eps > SMALLEST_TRIED {
        let simplified = fine.0.simplify_vw_preserve(eps);
        if !crosses(&simplified) {
            return (simplified, fine.1);
        }
        eps *= 0.5;
    }
    fine
}

/// Tolerances below this simplify nothing that matters (cells² in the unit-cell frame), and a
/// tolerance of 0 would make geo's Visvalingam return its input unchanged.
const LEAST_TOLERANCE: f64 = 1e-9;

/// The least Visvalingam tolerance (at least [`LEAST_TOLERANCE`]) with which geo's plain
/// `simplify_vw` leaves `polygons` at most `target` vertices, or, if none does, the one that
/// removes all it can. geo's Visvalingam removes the smallest triangle first and stops at the
/// first larger than the tolerance, and the order it removes them in does not depend on the
/// tolerance: one run to the end per ring ([`Removals`]) gives the count for every
/// tolerance at once, where a bisection ran the simplification some 35 times (most of the
/// outline's time on a boundary of long, detailed spikes).
fn tolerance_for(polygons: &MultiPolygon<f64>, target: usize) -> f64 {
    let mut levels: Vec<f64> = rings_of_region(polygons)
        .flat_map(|r| Removals::until(r, f64::INFINITY, &mut |_| true))
        .flat_map(|removals| removals.levels)
        .collect();
    levels.sort_unstable_by(f64::total_cmp);
    // With tolerance `eps`, each ring loses its levels ≤ `eps` (a ring's levels only grow).
    let to_remove = vertex_count(polygons).saturating_sub(target);
    let level = match to_remove {
        0 => LEAST_TOLERANCE,
        k => levels.get(k - 1).or(levels.last()).copied().unwrap_or(0.0),
    };
    level.max(LEAST_TOLERANCE)
}

/// geo's plain Visvalingam (`simplify_vw`) of every ring of `polygons` with tolerance `eps`, the
/// same vertices kept ([`Removals`]) in a heap of 16-byte entries where geo's are 40: on a
/// boundary of 200,000 vertices the fine pass of [`simplify`] was a quarter of the run, most of
/// it moving heap entries. `heard` hears the share of the heap's work done as the rings go
/// (time follows the entries taken from the heap, about three per vertex when most of them go:
/// each removal scores both neighbours anew); `None` once it has returned false.
fn visvalingam(
    polygons: &MultiPolygon<f64>,
    eps: f64,
    heard: &dyn Fn(f64) -> bool,
) -> Option<MultiPolygon<f64>> {
    let total = 3.0 * vertex_count(polygons).max(1) as f64;
    let mut before = 0;
    let mut ring = |ring: &LineString<f64>| -> Option<LineString<f64>> {
        if eps <= 0.0 {
            return Some(ring.clone());
        }
        let mut kept = vec![true; ring.0.len()];
        let removals = Removals::until(ring, eps, &mut |taken| {
            heard((before + taken) as f64 / total)
        })?;
        before += 3 * ring.0.len();
        for &k in &removals.order {
            kept[k as usize] = false;
        }
        Some(LineString(
            (ring.0.iter().zip(&kept))
                .filter(|(_, &k)| k)
                .map(|(&c, _)| c)
                .collect(),
        ))
    };
    let mut parts = Vec::with_capacity(polygons.0.len());
    for p in &polygons.0 {
        let exterior = ring(p.exterior())?;
        let holes = p.interiors().iter().map(&mut ring).collect::<Option<_>>()?;
        parts.push(Polygon::new(exterior, holes));
    }
    Some(MultiPolygon(parts))
}

/// How many heap entries [`Removals::until`] takes between reports: a few milliseconds' worth.
const REMOVALS_HEARD: usize = 1 << 14;

/// What geo's plain Visvalingam removes from a ring with tolerance `eps`: the vertices in the
/// order it removes them, and for each the largest triangle area removed up to and including it.
/// Run to the end (`eps` infinite), it gives the removals for every tolerance at once: with
/// tolerance `eps` geo removes exactly the vertices whose level is ≤ `eps`, a prefix of the
/// order. Mirrors geo's loop (`visvalingam_indices` in geo's simplify_vw.rs): a min-heap by
/// area alone, filled and updated in the same order, so that equal areas come out in geo's
/// order too. geo finds a stale entry by its vertex's neighbours; a vertex's neighbours change
/// only where the vertex is scored anew (or removed), so a stamp per vertex does the same.
struct Removals {
    order: Vec<u32>,
    levels: Vec<f64>,
}

impl Removals {
    /// The removals from `ring` with tolerance `eps`. `heard` hears, every [`REMOVALS_HEARD`]
    /// entries taken from the heap, how many were; `None` once it has returned false.
    fn until(
        ring: &LineString<f64>,
        eps: f64,
        heard: &mut dyn FnMut(usize) -> bool,
    ) -> Option<Removals> {
        /// A vertex scored with the neighbours it had, as its stamp then says.
        struct Scored {
            area: f64,
            current: u32,
            stamp: u32,
        }
        impl Ord for Scored {
            fn cmp(&self, other: &Scored) -> Ordering {
                other
                    .area
                    .partial_cmp(&self.area)
                    .unwrap_or(Ordering::Equal)
            }
        }
        impl PartialOrd for Scored {
            fn partial_cmp(&self, other: &Scored) -> Option<Ordering> {
                Some(self.cmp(other))
            }
        }
        impl PartialEq for Scored {
            fn eq(&self, other: &Scored) -> bool {
                self.area == other.area
            }
        }
        impl Eq for Scored {}

        let coords = &ring.0;
        let n = coords.len();
        let area = |a: usize, c: usize, b: usize| {
            Triangle::new(coords[a], coords[c], coords[b]).unsigned_area()
        };
        // The neighbours still kept: -1 or n for none (the ends are never removed).
        let mut adjacent: Vec<(i64, i64)> = (0..n as i64).map(|i| (i - 1, i + 1)).collect();
        let mut stamps: Vec<u32> = vec![0; n];
        let mut heap: BinaryHeap<Scored> = (1..n.saturating_sub(1))
            .map(|i| Scored {
                area: area(i - 1, i, i + 1),
                current: i as u32,
                stamp: 0,
            })
            .collect();
        let mut order = Vec::with_capacity(n.saturating_sub(2));
        let mut levels = Vec::with_capacity(n.saturating_sub(2));
        let mut level = 0.0_f64;
        let mut taken = 0;
        while let Some(smallest) = heap.pop() {
            taken += 1;
            if taken % REMOVALS_HEARD == 0 && !heard(taken) {
                return None;
            }
            // geo stops at the first triangle above the tolerance, stale or not.
            if smallest.area > eps {
                break;
            }
            let current = smallest.current as usize;
            // Scored before a neighbour went, or removed: stale.
            if smallest.stamp != stamps[current] {
                continue;
            }
            level = level.max(smallest.area);
            order.push(smallest.current);
            levels.push(level);
            let (left, right) = adjacent[current];
            let (ll, _) = adjacent[left as usize];
            let (_, rr) = adjacent[right as usize];
            adjacent[left as usize] = (ll, right);
            adjacent[right as usize] = (left, rr);
            stamps[current] += 1;
            for (a, c, b) in [(ll, left, right), (left, right, rr)] {
                let c = c as usize;
                // A neighbour changed: whatever was scored for `c` is stale.
                stamps[c] += 1;
                if (0..n as i64).contains(&a) && (0..n as i64).contains(&b) {
                    heap.push(Scored {
                        area: area(a as usize, c, b as usize),
                        current: c as u32,
                        stamp: stamps[c],
                    });
                }
            }
        }
        Some(Removals { order, levels })
    }
}

/// `union` without the vertices nearer than `spacing` to the last vertex kept before them (the
/// radial-distance filter: linear time, and no point of a ring moves by more than `spacing`).
/// A ring that would keep fewer than four vertices keeps all.
fn thin(union: &MultiPolygon<f64>, spacing: f64) -> MultiPolygon<f64> {
    let thin_ring = |ring: &LineString<f64>| {
        let mut kept: Vec<Coord<f64>> = Vec::with_capacity(ring.0.len());
        for &c in &ring.0 {
            match kept.last() {
                Some(&last) if (c - last).x.hypot((c - last).y) < spacing => {}
                _ => kept.push(c),
            }
        }
        // The ring stays closed on its own first vertex.
        match (kept.first(), ring.0.last()) {
            (Some(&first), Some(_)) if kept.len() >= 4 => {
                if kept.last() != Some(&first) {
                    kept.push(first);
                }
                LineString(kept)
            }
            _ => ring.clone(),
        }
    };
    MultiPolygon(
        (union.0.iter())
            .map(|p| {
                Polygon::new(
                    thin_ring(p.exterior()),
                    p.interiors().iter().map(thin_ring).collect(),
                )
            })
            .collect(),
    )
}

/// The rings of a multipolygon, open, with part numbers; exteriors counter-clockwise, holes
/// clockwise, so every ring keeps the interior on its left.
pub fn rings_of(p: &MultiPolygon<f64>) -> Vec<Ring> {
    let open = |ring: &LineString<f64>, ccw: bool| {
        let mut coords: Vec<Coord<f64>> = ring.0.clone();
        if coords.len() > 1 && coords.first() == coords.last() {
            coords.pop();
        }
        let area = Polygon::new(LineString(coords.clone()), vec![]).signed_area();
        if (area > 0.0) != ccw {
            coords.reverse();
        }
        coords
    };
    p.0.iter()
        .enumerate()
        .flat_map(|(part, poly)| {
            std::iter::once(Ring {
                coords: open(poly.exterior(), true),
                part,
                hole: false,
            })
            .chain(poly.interiors().iter().map(move |h| Ring {
                coords: open(h, false),
                part,
                hole: true,
            }))
        })
        .collect()
}

pub fn coords_of(rings: &[Ring]) -> Vec<Vec<Coord<f64>>> {
    rings.iter().map(|r| r.coords.clone()).collect()
}

/// A multipolygon from rings: the inverse of [`rings_of`], used to rebuild the outline at the
/// Snake's moved positions.
pub fn polygons_of(rings: &[Ring]) -> MultiPolygon<f64> {
    let parts = rings.iter().map(|r| r.part).max().map_or(0, |m| m + 1);
    let closed = |r: &Ring| {
        let mut line = r.coords.clone();
        if let Some(&first) = line.first() {
            line.push(first);
        }
        LineString(line)
    };
    let polygons = (0..parts).filter_map(|part| {
        let exterior = rings.iter().find(|r| r.part == part && !r.hole)?;
        let holes = rings
            .iter()
            .filter(|r| r.part == part && r.hole)
            .map(closed)
            .collect();
        Some(Polygon::new(closed(exterior), holes))
    });
    MultiPolygon(polygons.collect())
}

/// `outline` without the rings too small to draw: a part whose ring the network holds as one or
/// two nodes (an islet far below a cell, simplified to a point) and the holes so shrunk. The
/// method keeps such a part, so that the parts keep their indices; an output polygon whose ring
/// encloses no area is one GEOS and shapely refuse to read.
pub fn drawable(outline: &MultiPolygon<f64>) -> MultiPolygon<f64> {
    let encloses = |ring: &LineString<f64>| {
        ring.0.len() >= 4 && Polygon::new(ring.clone(), Vec::new()).unsigned_area() > 0.0
    };
    let polygons = (outline.0.iter())
        .filter(|p| encloses(p.exterior()))
        .map(|p| {
            let holes = p.interiors().iter().filter(|h| encloses(h)).cloned();
            Polygon::new(p.exterior().clone(), holes.collect())
        });
    MultiPolygon(polygons.collect())
}

/// Moves a centroid that is outside the simplified outline to `INSIDE_MARGIN` inside it, past
/// the nearest point of the outline (§1).
fn move_inside(c: Coord<f64>, index: &RingIndex) -> Coord<f64> {
    if index.contains(c) {
        return c;
    }
    let Some((segment, _)) = index.nearest(c) else {
        return c;
    };
    let q = nearest_on_segment(c, segment.a, segment.b);
    let away = q - c;
    let len = (away.x * away.x + away.y * away.y).sqrt();
    // The inward direction: across the nearest point, or the segment's left normal when the
    // centroid lies on the outline (rings keep the interior on their left).
    let dir = if len > 1e-12 {
        away / len
    } else {
        let t = segment.b - segment.a;
        let n = (t.x * t.x + t.y * t.y).sqrt().max(1e-300);
        Coord {
            x: -t.y / n,
            y: t.x / n,
        }
    };
    let mut margin = INSIDE_MARGIN;
    while margin > 1e-9 {
        let candidate = q + dir * margin;
        if index.contains(candidate) {
            return candidate;
        }
        margin *= 0.5;
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::geometry::segments_intersect;
    use geo::{polygon, SimplifyVw};

    fn square(x: f64, y: f64) -> MultiPolygon<f64> {
        MultiPolygon(vec![
            polygon![(x: x, y: y), (x: x + 1.0, y: y), (x: x + 1.0, y: y + 1.0), (x: x, y: y + 1.0)],
        ])
    }

    /// A ring of `n` vertices round a circle, its radius wiggled by a fixed pattern; `staircase`
    /// snaps the coordinates to a coarse grid, so that many triangles have equal areas (ties in
    /// geo's heap).
    fn wiggly(n: usize, staircase: bool) -> LineString<f64> {
        let mut coords: Vec<Coord<f64>> = (0..n)
            .map(|i| {
                let t = i as f64 / n as f64 * std::f64::consts::TAU;
                let r = 10.0 + ((i * 7919) % 13) as f64 * 0.05 + (3.0 * t).sin();
                let c = Coord {
                    x: r * t.cos(),
                    y: r * t.sin(),
                };
                if staircase {
                    Coord {
                        x: (c.x * 4.0).round() / 4.0,
                        y: (c.y * 4.0).round() / 4.0,
                    }
                } else {
                    c
                }
            })
            .collect();
        coords.dedup();
        coords.push(coords[0]);
        LineString(coords)
    }

    /// A band along a spiral of `turns` turns, `width` wide, its arms `gap` apart (in cells),
    /// with `n` vertices along each side: simplified coarsely, a chord across a turn of the band
    /// cuts through the arm beside it.
    fn spiral(turns: f64, width: f64, gap: f64, n: usize) -> MultiPolygon<f64> {
        let pitch = (width + gap) / std::f64::consts::TAU;
        let side = |offset: f64| -> Vec<Coord<f64>> {
            (0..n)
                .map(|i| {
                    let t = 2.0 * std::f64::consts::TAU
                        + turns * std::f64::consts::TAU * i as f64 / (n - 1) as f64;
                    let r = pitch * t + offset;
                    Coord {
                        x: r * t.cos(),
                        y: r * t.sin(),
                    }
                })
                .collect()
        };
        let mut ring = side(-width / 2.0);
        ring.extend(side(width / 2.0).into_iter().rev());
        ring.push(ring[0]);
        MultiPolygon(vec![Polygon::new(LineString(ring), vec![])])
    }

    #[test]
    fn a_long_simplification_reports_as_it_goes_and_stops_when_told() {
        // A band of 60,000 vertices, each a quarter of a hundredth of a cell from the next (the
        // thinning keeps them all): the finest detail's pass takes some 180,000 entries from its
        // heap, about eleven reports' worth.
        let band = spiral(3.0, 1.0, 0.2, 30_000);
        let heard = Mutex::new(Vec::new());
        let listen = |share: f64| {
            heard.lock().unwrap().push(share);
            true
        };
        assert!(simplify(&band, 60, None, &listen).is_some());
        let shares = heard.into_inner().unwrap();
        assert!(shares.windows(2).all(|w| w[0] < w[1]), "{shares:?}");
        let during = shares.iter().filter(|&&s| s > 0.05 && s < 0.85).count();
        assert!(during >= 5, "{shares:?}");
        // Told to stop at its first report, it stops there.
        let asked = AtomicUsize::new(0);
        let stop = |_: f64| {
            asked.fetch_add(1, AtomicOrdering::Relaxed);
            false
        };
        assert!(simplify(&band, 60, None, &stop).is_none());
        assert_eq!(asked.load(AtomicOrdering::Relaxed), 1);
    }

    #[test]
    fn a_simplification_that_would_cross_itself_keeps_more_vertices_instead() {
        // Three turns of a band a cell wide with gaps of a fifth of a cell (79 cells², 4,000
        // vertices), to be simplified to 60: plain Visvalingam to that count cuts across the
        // arms (checked here, so that the test takes the fallback: the tolerance is halved until
        // nothing crosses), and the outline must not.
        let band = spiral(3.0, 1.0, 0.2, 2_000);
        let plain = band.simplify_vw(tolerance_for(&band, 60));
        assert!(crosses(&plain));
        let (outline, _) = simplify(&band, 60, None, &|_| true).unwrap();
        assert!(!crosses(&outline));
        let kept = vertex_count(&outline);
        assert!(kept > 60 && kept < 4_000, "{kept} vertices");
        // The band itself is kept: its area within 2 % (chords across a band a cell wide, bent
        // no tighter than a radius of 2.4 cells, cut off little of it).
        let (before, after) = (band.unsigned_area(), outline.unsigned_area());
        assert!(
            (after - before).abs() < 0.02 * before,
            "{before} -> {after}"
        );
    }

    #[test]
    fn removals_give_geos_simplification_for_every_tolerance() {
        for (n, staircase) in [(400, false), (400, true), (3, false), (5, true)] {
            let ring = wiggly(n, staircase);
            let levels = (Removals::until(&ring, f64::INFINITY, &mut |_| true).unwrap()).levels;
            let holed = MultiPolygon(vec![Polygon::new(
                ring.clone(),
                vec![LineString(ring.0.iter().rev().map(|&c| c * 0.5).collect())],
            )]);
            for eps in [1e-9, 1e-4, 1e-3, 0.01, 0.03, 0.1, 0.3, 1.0, 10.0, 1e6] {
                let removed = levels.iter().filter(|&&l| l <= eps).count();
                let by_geo = ring.simplify_vw(eps);
                assert_eq!(
                    ring.0.len() - removed,
                    by_geo.0.len(),
                    "{n} vertices, staircase {staircase}, tolerance {eps}"
                );
                // The same vertices, ties and all, ring by ring.
                assert_eq!(
                    visvalingam(&holed, eps, &|_| true).unwrap(),
                    holed.simplify_vw(eps)
                );
            }
        }
    }

    #[test]
    fn the_tolerance_is_the_least_that_reaches_the_target() {
        let polygons = MultiPolygon(vec![
            Polygon::new(wiggly(500, false), vec![]),
            Polygon::new(wiggly(300, true), vec![]),
        ]);
        let all = vertex_count(&polygons);
        for target in [all, all - 1, 600, 200, 40] {
            let eps = tolerance_for(&polygons, target);
            assert!(
                vertex_count(&polygons.simplify_vw(eps)) <= target,
                "target {target}"
            );
            if eps > LEAST_TOLERANCE {
                // A hair less keeps too many: the tolerance is the least.
                let less = eps * (1.0 - 1e-9);
                assert!(
                    vertex_count(&polygons.simplify_vw(less)) > target,
                    "target {target}"
                );
            }
        }
    }

    #[test]
    fn overlaps_are_measured_and_one_pair_named() {
        let side_by_side = [square(0.0, 0.0), square(1.0, 0.0)];
        let refs: Vec<&MultiPolygon<f64>> = side_by_side.iter().collect();
        let union = merge(&refs, &[true, true], &[vec![0, 1]], |_| true).unwrap();
        assert_eq!(overlaps(&refs, overlap_share(&refs, &union)), None);
        // A 0.6 × 0.6 square drawn over the first: 0.36 of 2.36 counted twice (hand count).
        let small = MultiPolygon(vec![
            polygon![(x: 0.2, y: 0.2), (x: 0.8, y: 0.2), (x: 0.8, y: 0.8), (x: 0.2, y: 0.8)],
        ]);
        let stacked = [square(0.0, 0.0), square(1.0, 0.0), small];
        let refs: Vec<&MultiPolygon<f64>> = stacked.iter().collect();
        let union = merge(&refs, &[true, true, true], &[vec![0, 1, 2]], |_| true).unwrap();
        let (share, pair) = overlaps(&refs, overlap_share(&refs, &union)).expect("an overlap");
        assert!((share - 0.36 / 2.36).abs() < 1e-9, "{share}");
        let (i, j) = pair.expect("a pair");
        assert_eq!((i.min(j), i.max(j)), (0, 2));
    }

    #[test]
    fn a_block_of_squares_has_rook_adjacency_and_one_outline() {
        let regions: Vec<MultiPolygon<f64>> = (0..3)
            .flat_map(|r| (0..3).map(move |c| square(c as f64, r as f64)))
            .collect();
        let refs: Vec<&MultiPolygon<f64>> = regions.iter().collect();
        let prepared = prepare(
            &refs,
            &refs,
            &vec![false; refs.len()],
            &Params::default(),
            &|_, _| true,
        )
        .expect("not cancelled");
        // 3×3 rook adjacency: 12 pairs; diagonal neighbours touch at a point only.
        assert_eq!(prepared.adjacency.len(), 12);
        assert!(prepared.adjacency.contains(&(0, 1)));
        assert!(!prepared.adjacency.contains(&(0, 4)));
        assert_eq!(prepared.rings.len(), 1);
        assert!((prepared.regions_union.unsigned_area() - 9.0).abs() < 1e-9);
        assert!((prepared.centroids[4].x - 1.5).abs() < 1e-12);
        let with_points = Params {
            point_adjacency: true,
            ..Params::default()
        };
        assert_eq!(
            prepare(
                &refs,
                &refs,
                &vec![false; refs.len()],
                &with_points,
                &|_, _| true
            )
            .expect("not cancelled")
            .adjacency
            .len(),
            20
        );
    }

    #[test]
    fn parts_a_hairline_apart_are_joined_and_parts_further_apart_kept() {
        let prepared = |gap: f64| {
            let regions = [square(0.0, 0.0), square(1.0 + gap, 0.2)];
            let refs: Vec<&MultiPolygon<f64>> = regions.iter().collect();
            prepare(&refs, &refs, &[true, true], &Params::default(), &|_, _| {
                true
            })
            .expect("not cancelled")
        };
        // Half the closed gap: one part, about the two squares' area (the closing fills the
        // gap's 0.8 × 0.005 strip, and no more than a few gap-wide corners besides).
        let joined = prepared(0.5 * GAP_CLOSED);
        assert_eq!(joined.rings.len(), 1, "{:?}", joined.rings);
        let area = polygons_of(&joined.rings).unsigned_area();
        assert!((area - 2.0).abs() < 0.01, "{area}");
        // The exact union, the judge's landmasses, keeps both parts, and the judge's adjacency
        // no pair; the layout keeps the two squares, facing each other for 0.8, together.
        assert_eq!(joined.regions_union.0.len(), 2);
        assert!(joined.adjacency.is_empty());
        assert_eq!(joined.neighbours, vec![(0, 1)]);
        // Twice the closed gap: two parts, each its own square, untouched.
        let apart = prepared(2.0 * GAP_CLOSED);
        assert_eq!(apart.rings.len(), 2);
        assert!(apart.neighbours.is_empty());
        assert_eq!(polygons_of(&apart.rings).unsigned_area(), 2.0);
    }

    #[test]
    fn a_short_border_across_a_narrow_gap_is_kept_and_a_corner_is_not() {
        // Delaware and New Jersey drawn a hairline apart: a border of 0.04 cells across a gap
        // of 0.002 (a fifth of the closing's gap) was lost when only a facing of ten times the
        // closing's gap (0.1 cells) counted.
        let gap = 0.2 * GAP_CLOSED;
        let regions = [
            square(0.0, 0.0),
            // Beside the first square's upper right corner, facing it for 0.04.
            square(1.0 + gap, 0.96),
            // Diagonally below the first, meeting it only corner to corner across the gap.
            square(-1.0 - gap, -1.0 - gap),
        ];
        let refs: Vec<&MultiPolygon<f64>> = regions.iter().collect();
        let prepared = prepare(&refs, &refs, &[true; 3], &Params::default(), &|_, _| true)
            .expect("not cancelled");
        assert!(prepared.adjacency.is_empty());
        assert_eq!(prepared.neighbours, vec![(0, 1)]);
    }

    #[test]
    fn small_holes_are_filled_and_empty_parts_dropped() {
        let holed = MultiPolygon(vec![Polygon::new(
            LineString::from(vec![
                (0.0, 0.0),
                (4.0, 0.0),
                (4.0, 4.0),
                (0.0, 4.0),
                (0.0, 0.0),
            ]),
            vec![
                LineString::from(vec![
                    (0.5, 0.5),
                    (0.7, 0.5),
                    (0.7, 0.7),
                    (0.5, 0.7),
                    (0.5, 0.5),
                ]),
                LineString::from(vec![
                    (2.0, 2.0),
                    (3.0, 2.0),
                    (3.0, 3.0),
                    (2.0, 3.0),
                    (2.0, 2.0),
                ]),
            ],
        )]);
        let mut island = square(10.0, 10.0);
        island.0.extend(square(20.0, 20.0).0.iter().map(|p| {
            use geo::Scale;
            p.scale(0.01)
        }));
        let prepared = prepare(
            &[&holed, &island],
            &[&holed, &island],
            &[false, false],
            &Params::default(),
            &|_, _| true,
        )
        .expect("not cancelled");
        let holes: Vec<&Ring> = prepared.rings.iter().filter(|r| r.hole).collect();
        assert_eq!(holes.len(), 1, "the 1-cell² lake stays, the sliver goes");
        // The island region's centroid lies in its big square; the tiny part holds no centroid.
        assert_eq!(prepared.rings.iter().filter(|r| !r.hole).count(), 2);
    }

    #[test]
    fn without_crossings_the_lengths_along_are_those_of_the_exact_test() {
        // Random edges beside a unit edge at the scale of each reach, long or short, many
        // crossing it or ending near its ends: every length along within every reach is the
        // same whether or not crossings are tested exactly (Beside::of).
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let e = Edge {
            a: Coord { x: 0.0, y: 0.0 },
            b: Coord { x: 1.0, y: 0.0 },
            region: 0,
        };
        let mut crossing = 0;
        for touching in [SHARED, ACROSS_GAPS] {
            let reach = touching.widest();
            for _ in 0..50_000 {
                let scale = touching.reaches[rng.random_range(0..touching.reaches.len())].reach;
                let end = [0.0, 1.0][rng.random_range(0..2)];
                let near_end = rng.random_bool(0.5);
                let mut point = || Coord {
                    x: if near_end {
                        end + rng.random_range(-3.0 * scale..3.0 * scale)
                    } else {
                        rng.random_range(-0.1..1.1)
                    },
                    y: rng.random_range(-2.0 * scale..2.0 * scale),
                };
                let f = Edge {
                    a: point(),
                    b: point(),
                    region: 1,
                };
                crossing += usize::from(segments_intersect(e.a, e.b, f.a, f.b));
                let exact = Beside::of(&e, &f, reach, true);
                let ends = Beside::of(&e, &f, reach, false);
                for r in touching.reaches {
                    let along =
                        |b: &Option<Beside>| b.as_ref().map_or(0.0, |b| b.along_within(r.reach));
                    assert_eq!(along(&ends), along(&exact), "{f:?} within {}", r.reach);
                }
            }
        }
        assert!(crossing > 10_000, "{crossing} crossings");
    }

    #[test]
    fn edge_runs_keep_to_one_region_and_to_edges_that_follow_on() {
        let edge = |a: (f64, f64), b: (f64, f64), region: usize| Edge {
            a: Coord { x: a.0, y: a.1 },
            b: Coord { x: b.0, y: b.1 },
            region,
        };
        // Ten edges of region 0 in a row, then one that starts elsewhere, then two of region 1
        // that go on from region 0's last.
        let mut edges: Vec<Edge> = (0..10)
            .map(|k| edge((k as f64, 0.0), (k as f64 + 1.0, 0.0), 0))
            .collect();
        edges.push(edge((20.0, 0.0), (21.0, 0.0), 0));
        edges.push(edge((21.0, 0.0), (22.0, 0.0), 1));
        edges.push(edge((22.0, 0.0), (22.0, 1.0), 1));
        let runs = edge_runs(&edges);
        let ranges: Vec<std::ops::Range<usize>> = runs.iter().map(|r| r.edges.clone()).collect();
        assert_eq!(ranges, [0..RUN_EDGES, RUN_EDGES..10, 10..11, 11..13]);
        let last = &runs[3].envelope;
        assert_eq!((last.lower(), last.upper()), ([21.0, 0.0], [22.0, 1.0]));
    }

    #[test]
    fn the_outline_reports_the_time_its_sides_have_run_against_the_longer_and_only_forward() {
        let heard = Mutex::new(Vec::new());
        let reached = |share: f64, message: &str| {
            heard.lock().unwrap().push((share, message.to_owned()));
            true
        };
        // Each stage expected to take as long: the union and the simplification after it are
        // the longer side, twice the adjacency.
        let stages = SideBySide::new(&reached, [1.0, 1.0, 1.0]);
        stages.advanced(Stage::Adjacency, 0.5);
        stages.advanced(Stage::Adjacency, 0.25);
        stages.ended(Stage::Union);
        stages.ended(Stage::Adjacency);
        stages.advanced(Stage::Simplification, 0.5);
        stages.ended(Stage::Simplification);
        let heard = heard.into_inner().unwrap();
        let shares: Vec<f64> = heard.iter().map(|(s, _)| *s).collect();
        // Half the adjacency is a quarter of the outline's time, and a report of less changes
        // nothing; the union's end is half of it, as is the adjacency's end, which the longer
        // side has reached; half the simplification is three quarters, and its end all: from
        // 0.05 to 0.95 of the bar.
        let expected = [0.25, 0.25, 0.5, 0.5, 0.75, 1.0].map(|d| 0.05 + 0.9 * d);
        assert_eq!(shares.len(), expected.len());
        for (got, want) in shares.iter().zip(expected) {
            assert!((got - want).abs() < 1e-12, "{shares:?}");
        }
        let messages: Vec<&str> = heard.iter().map(|(_, m)| m.as_str()).collect();
        assert_eq!(
            messages,
            [
                "outline: adjacency and union",
                "outline: adjacency and union",
                "outline: adjacency and simplification",
                "outline: simplification",
                "outline: simplification",
                "outline",
            ]
        );
    }

    #[test]
    fn boundary_edges_come_in_the_boundaries_order_and_stop_when_told() {
        // Three chunks of regions, one with a hole: the edges as a plain walk gives them.
        let regions: Vec<MultiPolygon<f64>> = (0..150)
            .map(|k| {
                let mut region = square((k % 15) as f64, (k / 15) as f64);
                if k == 70 {
                    let hole = geo::LineString::from(vec![
                        (7.4, 4.4),
                        (7.4, 4.6),
                        (7.6, 4.6),
                        (7.6, 4.4),
                        (7.4, 4.4),
                    ]);
                    region.0[0].interiors_push(hole);
                }
                region
            })
            .collect();
        let refs: Vec<&MultiPolygon<f64>> = regions.iter().collect();
        let members: Vec<usize> = (0..150).rev().collect();
        let walked: Vec<(Coord<f64>, Coord<f64>, usize)> = (members.iter())
            .flat_map(|&k| {
                rings_of_region(refs[k])
                    .flat_map(move |r| r.lines().map(move |l| (l.start, l.end, k)))
            })
            .collect();
        let shares = Mutex::new(Vec::new());
        let edges = boundary_edges(&refs, &members, &|share| {
            shares.lock().unwrap().push(share);
            true
        })
        .expect("not stopped");
        let collected: Vec<_> = edges.iter().map(|e| (e.a, e.b, e.region)).collect();
        assert_eq!(collected, walked);
        assert_eq!(walked.len(), 150 * 4 + 4);
        // One report per chunk of 64 regions, the last at the whole.
        let mut shares = shares.into_inner().unwrap();
        shares.sort_by(f64::total_cmp);
        assert_eq!(shares.len(), 3);
        assert_eq!(shares.last(), Some(&1.0));
        assert!(boundary_edges(&refs, &members, &|_| false).is_none());
    }

    #[test]
    fn a_cancel_stops_both_sides_of_the_outline() {
        let asked = AtomicUsize::new(0);
        let cancel = |_: f64, _: &str| {
            asked.fetch_add(1, AtomicOrdering::Relaxed);
            false
        };
        let stages = SideBySide::new(&cancel, [1.0, 1.0, 1.0]);
        assert!(!stages.stopped());
        assert!(!stages.advanced(Stage::Adjacency, 0.1));
        assert!(stages.stopped());
        // Neither side asks again.
        assert!(!stages.ended(Stage::Union));
        assert_eq!(asked.load(AtomicOrdering::Relaxed), 1);
        // The whole preparation, cancelled as it begins and as the adjacency reports.
        let regions: Vec<MultiPolygon<f64>> = (0..3).map(|c| square(c as f64, 0.0)).collect();
        let refs: Vec<&MultiPolygon<f64>> = regions.iter().collect();
        let params = Params::default();
        assert!(prepare(&refs, &refs, &[true; 3], &params, &|_, _| false).is_none());
        let at_adjacency = |_: f64, m: &str| !m.contains("adjacency");
        assert!(prepare(&refs, &refs, &[true; 3], &params, &at_adjacency).is_none());
        // The first report without the union in it is the union's end, whichever side ends
        // first.
        let after_the_union = |_: f64, m: &str| m.contains("union");
        assert!(prepare(&refs, &refs, &[true; 3], &params, &after_the_union).is_none());
    }
}
