//! The quality metrics of method.md §8, as the shared judge (`shared/eval/gridmap_eval.py`, the
//! reference implementation of §8) computes them: location after the scale-and-translation fit
//! in fitted cells, adjacency in the 8- and 4-neighbourhood, false neighbours, orientation,
//! Fourier shape similarity with Euclidean norms, and the shape of the layout itself (pieces,
//! holes, notches, regions on the wrong landmass).
//!
//! Each adjacent pair is scored once ([`PairScore`]); the layout numbers are means over all
//! pairs and the per-region numbers means over the pairs incident to the region, so both come
//! from the same helpers. Likewise the location fit is computed once and gives both the layout's
//! C_location and each region's displacement.

use super::frame::Frame;
use super::geometry::RingIndex;
use super::outline::{coords_of, Prepared, SLIVER_AREA};
use super::tiling::{Corner, Position, Tiling};
use super::{LayoutMetrics, RegionMetrics};
use geo::{Area, BoundingRect, Coord, LineString, MultiPolygon, Winding};
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{PointDistance, RTree, AABB};
// Fx hashing: the layout's shape is computed for every shift the landmass settling tries, and
// SipHash was a fifth of a layout before refinement on the US counties.
use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};

/// What every layout of one layer is scored against, in map units: made once per run.
pub struct Reference {
    /// Area centroids c_i of the regions' whole (multi)polygons.
    pub centroids: Vec<Coord<f64>>,
    /// Adjacent region pairs (i < j).
    pub adjacency: Vec<(usize, usize)>,
    /// The union of the regions, for the source's pieces and holes.
    pub outline: MultiPolygon<f64>,
    /// The Fourier descriptor of the largest part's outer ring, for the shape similarity (once
    /// per run: a dense outline has millions of vertices).
    pub shape: Option<Vec<f64>>,
    /// The regions' landmasses, for the wrong-landmass share.
    pub landmasses: Landmasses,
    /// S of the original map (sqrt(total area / M)), the unit of the paper's location variant.
    pub unit: f64,
    /// The share of the union's holes' area (`source_holes`) in holes of at least
    /// [`SLIVER_AREA`] S²: lakes and missing regions, which a layout may keep (§8). Smaller holes
    /// are slivers between regions (§1): a layer simplified feature by feature (`ogr2ogr
    /// -simplify` to a sixteenth of a cell on us_counties) has hundreds, 27 cells in all, and
    /// counting them as lakes let its layouts keep 25 holes.
    pub lake_share: f64,
}

impl Reference {
    /// The reference of the regions `prepared` describes, whose frame is `frame`.
    pub fn new(prepared: &Prepared, frame: Frame) -> Reference {
        Reference::of(
            (prepared.area_centroids.iter())
                .map(|&c| frame.to_map(c))
                .collect(),
            prepared.neighbours.clone(),
            frame.polygons_to_map(&prepared.regions_union),
            prepared.landmass_of.clone(),
            frame.scale,
        )
    }

    /// The reference of regions with these centroids, adjacent pairs, union, landmass (part of
    /// `outline`) per region and S.
    fn of(
        centroids: Vec<Coord<f64>>,
        adjacency: Vec<(usize, usize)>,
        outline: MultiPolygon<f64>,
        landmass_of: Vec<usize>,
        unit: f64,
    ) -> Reference {
        let holes = (outline.0.iter())
            .flat_map(|p| p.interiors())
            .map(|ring| geo::Polygon::new(ring.clone(), vec![]).unsigned_area());
        let (all, lakes) = holes.fold((0.0, 0.0), |(all, lakes), area| {
            let lake = area >= SLIVER_AREA * unit * unit;
            (all + area, lakes + if lake { area } else { 0.0 })
        });
        Reference {
            centroids,
            adjacency,
            lake_share: if all > 0.0 { lakes / all } else { 1.0 },
            landmasses: Landmasses::new(&outline, landmass_of),
            shape: (outline.0.iter())
                .max_by(|a, b| a.unsigned_area().total_cmp(&b.unsigned_area()))
                .and_then(|p| descriptor(p.exterior())),
            outline,
            unit,
        }
    }
}

/// A layout to score, in the reference's frame (map units).
pub struct Scored<'a> {
    pub reference: &'a Reference,
    /// Moved centroids q_i (for the paper's location variant).
    pub moved: &'a [Coord<f64>],
    /// How the cells tile the plane.
    pub tiling: Tiling,
    /// Cell position of each region (see [`Tiling`]).
    pub cells: &'a [Position],
    /// Cell centres g_i.
    pub centres: &'a [Coord<f64>],
    /// Side of a cell.
    pub cell_size: f64,
}

/// The connected parts of the regions' union and which part each region belongs to (the one
/// holding most of its area), indexed for distance queries: what the wrong-landmass share
/// measures, and what the refinement avoids.
pub struct Landmasses {
    /// Per part, its index if it counts ([`Landmasses::part_counts`]): only those are measured
    /// from.
    parts: Vec<Option<RingIndex>>,
    /// The counted parts' boxes, indexed: a place asks only the parts whose box comes nearer
    /// than its own landmass (a layer of 2,000 islands of three regions each asked every one
    /// of them, most of its run).
    boxes: RTree<GeomWithData<Rectangle<[f64; 2]>, usize>>,
    /// Per region, its part.
    of: Vec<usize>,
    /// Per part, whether it holds 3 regions or more.
    large: Vec<bool>,
    /// Whether two parts or more are large: only then do the large ones count.
    several: bool,
}

impl Landmasses {
    /// `parts`: the parts of the union; `of[i]`: the part of region `i`.
    pub fn new(parts: &MultiPolygon<f64>, of: Vec<usize>) -> Landmasses {
        let mut sizes = vec![0usize; parts.0.len()];
        for &k in &of {
            sizes[k] += 1;
        }
        let large: Vec<bool> = sizes.iter().map(|&n| n >= LANDMASS_REGIONS).collect();
        let several = large.iter().filter(|&&large| large).count() >= 2;
        let counted: Vec<bool> = large.iter().map(|&large| several && large).collect();
        let boxes = super::outline::box_tree(
            (parts.0.iter().zip(&counted)).map(|(p, &counts)| p.bounding_rect().filter(|_| counts)),
        );
        let parts = (parts.0.iter().zip(&counted))
            .map(|(p, &counts)| {
                counts.then(|| {
                    let rings = super::outline::rings_of(&MultiPolygon(vec![p.clone()]));
                    RingIndex::new(&coords_of(&rings))
                })
            })
            .collect();
        Landmasses {
            parts,
            boxes,
            of,
            large,
            several,
        }
    }

    /// Whether part `k` counts: it holds 3 regions or more, and another part does too.
    fn part_counts(&self, k: usize) -> bool {
        self.several && self.large.get(k) == Some(&true)
    }

    /// Whether region `region`'s landmass holds 3 regions or more (whether or not another one
    /// does).
    pub fn large(&self, region: usize) -> bool {
        (self.of.get(region)).is_some_and(|&k| self.large.get(k) == Some(&true))
    }

    /// Whether any region counts for the wrong-landmass share (two landmasses of 3+ regions).
    pub fn any_counted(&self) -> bool {
        self.several
    }

    /// Whether region `region` counts for the wrong-landmass share (its landmass holds 3+
    /// regions, and another one does too).
    pub fn counts(&self, region: usize) -> bool {
        (self.of.get(region)).is_some_and(|&k| self.part_counts(k))
    }

    /// Per region, its landmass (a part of the union): [`Landmasses::misplaced`] gives the
    /// regions of one landmass the same answer at the same point.
    pub fn of(&self) -> &[usize] {
        &self.of
    }

    /// Whether region `region`, placed at `p`, lies nearer another counted landmass than its
    /// own (and outside its own).
    pub fn misplaced(&self, region: usize, p: Coord<f64>) -> bool {
        (self.of.get(region)).is_some_and(|&home| self.nearer_another(home, p))
    }

    /// Whether `p` lies outside landmass `home` and nearer another counted landmass; false when
    /// `home` does not count.
    pub fn nearer_another(&self, home: usize, p: Coord<f64>) -> bool {
        if !self.part_counts(home) {
            return false;
        }
        let distance = self.distance(home, p);
        // Inside its own landmass (or nowhere, for a point that is not finite).
        if distance <= 0.0 || distance.is_nan() {
            return false;
        }
        // With a margin for rounding: only a part that cannot be nearer is passed.
        let reach = distance * (1.0 + 1e-9);
        let around = AABB::from_corners([p.x - reach, p.y - reach], [p.x + reach, p.y + reach]);
        // No point of what a box holds is nearer than the box itself.
        (self.boxes.locate_in_envelope_intersecting(&around)).any(|part| {
            part.data != home
                && part.geom().distance_2(&[p.x, p.y]) < reach * reach
                && self.distance(part.data, p) < distance
        })
    }

    /// Distance from `p` to part `k` (0 inside it), a counted one.
    fn distance(&self, k: usize, p: Coord<f64>) -> f64 {
        match &self.parts[k] {
            Some(part) if part.contains(p) => 0.0,
            Some(part) => part.distance(p),
            None => f64::INFINITY,
        }
    }
}

/// Points sampled along each outline for the Fourier descriptors.
const SAMPLES: usize = 256;
/// Harmonics kept on each side of 0 (1..=K and −K..=−1).
const HARMONICS: usize = 32;
/// A pair whose direction is off by more than this is misdirected (degrees).
const MISDIRECTED_DEG: f64 = 45.0;
/// Landmasses with at least this many regions take part in the wrong-landmass share.
const LANDMASS_REGIONS: usize = 3;

/// Computes the layout metrics and the per-region metrics (in the order of `layout.reference.centroids`)
/// of method.md §8.
///
/// Definitions where the spec leaves room (the judge's, where it has one):
/// - the fit maps cell centres onto centroids, g ↦ s·g + t, least squares in closed form (see
///   [`fit`]); distances are in fitted cells, s·w; a fit with s = 0 exactly (a mirror image of a
///   symmetric layer) keeps s = 1 and only shifts. The 90th percentile interpolates linearly.
/// - With no adjacent pairs, `adjacent` = `adjacent_rook` = 1 (nothing was lost) and
///   `orientation` = `misdirected` = 0; with no touching cells `false_neighbours` = 0.
/// - Angles are directed (0..=180°); a pair whose two centroids (or cells) coincide has no
///   direction and is left out of the mean, as the judge does.
/// - C_shape: see [`shape_similarity`]; the layout's shape: see [`LayoutShape`].
pub fn evaluate(layout: &Scored) -> (LayoutMetrics, Vec<RegionMetrics>) {
    let m = layout.reference.centroids.len();
    debug_assert!(
        layout.moved.len() == m && layout.cells.len() == m && layout.centres.len() == m,
        "every region needs a moved centroid, a cell and a cell centre"
    );
    let (scale, shift) = fit(layout.centres, &layout.reference.centroids);
    let fitted_cell = layout.cell_size * scale.abs();
    let fitted: Vec<Coord<f64>> = layout.centres.iter().map(|&g| g * scale + shift).collect();
    let displacement: Vec<f64> = (0..m)
        .map(|i| distance(layout.reference.centroids[i], fitted[i]) / fitted_cell)
        .collect();
    let pairs: Vec<PairScore> = layout
        .reference
        .adjacency
        .iter()
        .map(|&(i, j)| PairScore::of(layout, i, j))
        .collect();
    // The pairs each region belongs to, for its own share and mean angle.
    let mut incident: Vec<Vec<&PairScore>> = vec![Vec::new(); m];
    for (&(i, j), pair) in layout.reference.adjacency.iter().zip(&pairs) {
        incident[i].push(pair);
        incident[j].push(pair);
    }
    let shape = LayoutShape::of(layout.cells, layout.tiling);
    let (source_pieces, source_holes) = source_shape(&layout.reference.outline);

    let metrics = LayoutMetrics {
        location: mean_or(displacement.iter().copied(), 0.0),
        location_p90: percentile(&displacement, 0.9),
        location_max: displacement.iter().copied().fold(0.0, f64::max),
        location_raw: mean_or(
            (0..m).map(|i| distance(layout.reference.centroids[i], layout.centres[i])),
            0.0,
        ),
        location_moved: mean_or(
            (0..m).map(|i| distance(layout.moved[i], layout.centres[i]) / layout.reference.unit),
            0.0,
        ),
        adjacent: kept_share(&pairs),
        adjacent_rook: mean_or(pairs.iter().map(|p| indicator(p.rook)), 1.0),
        false_neighbours: false_neighbours(layout),
        orientation: mean_angle(&pairs),
        misdirected: mean_or(
            pairs
                .iter()
                .filter_map(|p| p.angle)
                .map(|a| indicator(a > MISDIRECTED_DEG)),
            0.0,
        ),
        shape: shape_similarity(layout, &shape),
        pieces: shape.pieces.len() as u32,
        source_pieces,
        holes: shape.holes,
        source_holes: source_holes / (fitted_cell * fitted_cell),
        notches: shape.notches,
        wrong_landmass: wrong_landmass(layout, &fitted),
    };
    let regions = displacement
        .iter()
        .zip(&incident)
        .map(|(&displacement, own)| RegionMetrics {
            displacement,
            neighbours_kept: kept_share(own.iter().copied()),
            orientation_error: mean_angle(own.iter().copied()),
        })
        .collect();
    (metrics, regions)
}

/// How one adjacent pair fared in the layout.
#[derive(Debug)]
struct PairScore {
    /// The two cells are 8-neighbours (touch at an edge or a corner).
    queen: bool,
    /// The two cells share an edge.
    rook: bool,
    /// Directed angle between c_j − c_i and g_j − g_i, degrees in 0..=180; `None` when either
    /// has no direction.
    angle: Option<f64>,
}

impl PairScore {
    fn of(layout: &Scored, i: usize, j: usize) -> PairScore {
        let (a, b) = (layout.cells[i], layout.cells[j]);
        PairScore {
            queen: layout.tiling.touching(a, b),
            rook: layout.tiling.sharing_an_edge(a, b),
            angle: angle_deg(
                layout.reference.centroids[j] - layout.reference.centroids[i],
                layout.centres[j] - layout.centres[i],
            ),
        }
    }
}

/// Share of `pairs` whose cells stayed 8-neighbours; 1 with no pairs (nothing was lost).
fn kept_share<'p>(pairs: impl IntoIterator<Item = &'p PairScore>) -> f64 {
    mean_or(pairs.into_iter().map(|p| indicator(p.queen)), 1.0)
}

/// Mean direction error of `pairs` in degrees; 0 with none that has a direction.
fn mean_angle<'p>(pairs: impl IntoIterator<Item = &'p PairScore>) -> f64 {
    mean_or(pairs.into_iter().filter_map(|p| p.angle), 0.0)
}

fn indicator(condition: bool) -> f64 {
    if condition {
        1.0
    } else {
        0.0
    }
}

/// The mean of `values`, or `empty` when there are none (so metrics never become NaN).
fn mean_or(values: impl Iterator<Item = f64>, empty: f64) -> f64 {
    let (sum, count) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if count == 0 {
        empty
    } else {
        sum / count as f64
    }
}

/// The `q`-quantile of `values` with linear interpolation between order statistics (numpy's
/// default); 0 with no values.
fn percentile(values: &[f64], q: f64) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let Some(last) = sorted.len().checked_sub(1) else {
        return 0.0;
    };
    let at = q * last as f64;
    let (low, high) = (at.floor() as usize, at.ceil() as usize);
    sorted[low] + (sorted[high] - sorted[low]) * (at - low as f64)
}

fn distance(a: Coord<f64>, b: Coord<f64>) -> f64 {
    (a.x - b.x).hypot(a.y - b.y)
}

/// Unsigned angle from `u` to `v` in degrees (0..=180): atan2 of the cross and dot products,
/// which stays accurate near 0° and 180° where acos of the normalised dot product does not.
/// `None` when either has no length.
fn angle_deg(u: Coord<f64>, v: Coord<f64>) -> Option<f64> {
    if (u.x == 0.0 && u.y == 0.0) || (v.x == 0.0 && v.y == 0.0) {
        return None;
    }
    let cross = u.x * v.y - u.y * v.x;
    let dot = u.x * v.x + u.y * v.y;
    Some(cross.atan2(dot).abs().to_degrees())
}

/// A correlation this near 0 is rounding noise (see [`fit`]).
const ROUNDING: f64 = 1e-9;

/// The least-squares scale s and translation t minimising Σ|s·from_i + t − onto_i|².
///
/// Closed form: with the means f̄, ō, s = Σ(f_i − f̄)·(o_i − ō) / Σ|f_i − f̄|² and t = ō − s·f̄.
/// The scale is left free in sign. When `from` has no spread (one region) or the best scale is
/// 0, the scale is taken as 1 and only the shift fitted (as the judge does). The scale counts as
/// 0 when the correlation of the two point sets is within [`ROUNDING`] of it: a row of cells
/// fitted to a column of regions has an exact covariance of 0, which rounding in the frames'
/// transforms turns into 1e-16 and a location of 1e15 cells.
pub(crate) fn fit(from: &[Coord<f64>], onto: &[Coord<f64>]) -> (f64, Coord<f64>) {
    let n = from.len().max(1) as f64;
    let mean = |points: &[Coord<f64>]| {
        points
            .iter()
            .fold(Coord { x: 0.0, y: 0.0 }, |acc, &p| acc + p)
            / n
    };
    let (fm, om) = (mean(from), mean(onto));
    let (mut covariance, mut variance, mut spread) = (0.0, 0.0, 0.0);
    for (&f, &o) in from.iter().zip(onto) {
        let (df, d_o) = (f - fm, o - om);
        covariance += df.x * d_o.x + df.y * d_o.y;
        variance += df.x * df.x + df.y * df.y;
        spread += d_o.x * d_o.x + d_o.y * d_o.y;
    }
    let correlated = covariance.abs() > ROUNDING * (variance * spread).sqrt();
    let scale = if variance > 0.0 && correlated && from.len() > 1 {
        covariance / variance
    } else {
        1.0
    };
    (scale, om - fm * scale)
}

/// False-neighbour share: of the pairs of touching cells (8-neighbourhood; for hexagons the 6
/// edge neighbours), the share whose
/// regions are not adjacent; 0 when no cells touch.
fn false_neighbours(layout: &Scored) -> f64 {
    let at: HashMap<Position, usize> = (layout.cells.iter().enumerate())
        .map(|(i, &p)| (p, i))
        .collect();
    let adjacent: HashSet<(usize, usize)> = layout.reference.adjacency.iter().copied().collect();
    let (mut touching, mut false_ones) = (0usize, 0usize);
    for (i, &(c, r)) in layout.cells.iter().enumerate() {
        for &(dc, dr) in layout.tiling.half_neighbourhood() {
            if let Some(&j) = at.get(&(c + dc, r + dr)) {
                touching += 1;
                false_ones += usize::from(!adjacent.contains(&(i.min(j), i.max(j))));
            }
        }
    }
    if touching == 0 {
        0.0
    } else {
        false_ones as f64 / touching as f64
    }
}

/// Wrong-landmass share: among the regions of landmasses holding 3+ regions (when there are two
/// such landmasses or more), the share whose fitted cell centre lies nearer another of them than
/// its own (and outside its own).
fn wrong_landmass(layout: &Scored, fitted: &[Coord<f64>]) -> f64 {
    let lands = &layout.reference.landmasses;
    let counted: Vec<usize> = (0..fitted.len()).filter(|&i| lands.counts(i)).collect();
    let wrong = counted
        .iter()
        .filter(|&&i| lands.misplaced(i, fitted[i]))
        .count();
    wrong as f64 / counted.len().max(1) as f64
}

/// The number of parts of the regions' union and the area of its holes (map units²).
fn source_shape(outline: &MultiPolygon<f64>) -> (u32, f64) {
    let holes = outline
        .0
        .iter()
        .flat_map(|p| p.interiors())
        .map(|ring| geo::Polygon::new(ring.clone(), vec![]).unsigned_area())
        .sum();
    (outline.0.len() as u32, holes)
}

/// The shape of a layout as a set of cells (method.md §8): its pieces, holes and notches, and
/// the boundary of each piece.
pub(crate) struct LayoutShape {
    /// The edge-connected components of the cells, largest first (ties: first found).
    pieces: Vec<HashSet<Position>>,
    /// Cells' worth of area enclosed by pieces and not theirs: the area of their inner rings.
    holes: u32,
    /// Empty positions next to a cell with at most one free side (holes included).
    notches: u32,
}

impl LayoutShape {
    /// The number of pieces.
    pub(crate) fn pieces(&self) -> usize {
        self.pieces.len()
    }

    /// Cells enclosed in holes.
    pub(crate) fn holes(&self) -> u32 {
        self.holes
    }

    pub(crate) fn of(cells: &[Position], tiling: Tiling) -> LayoutShape {
        let occupied: HashSet<Position> = cells.iter().copied().collect();
        let pieces = pieces(cells, &occupied, tiling);
        LayoutShape {
            holes: hole_area(&pieces, tiling),
            pieces,
            notches: notches(cells, &occupied, tiling),
        }
    }

    /// [`LayoutShape::holes`] of `cells` alone, for a caller that asks it often (the landmass
    /// blocks' settling): neither the notches nor the pieces' sets are made.
    pub(crate) fn holes_of(cells: &[Position], tiling: Tiling) -> u32 {
        let mut holes = 0;
        each_piece(cells, cells.iter().copied().collect(), tiling, |piece| {
            holes += enclosed_by(piece, tiling);
        });
        holes
    }
}

/// The area of the pieces' inner rings, in cells.
fn hole_area(pieces: &[HashSet<Position>], tiling: Tiling) -> u32 {
    pieces.iter().map(|piece| enclosed_by(piece, tiling)).sum()
}

/// The positions `piece` encloses: those of its box, widened by a position all round, that no
/// path of edge neighbours outside the piece joins to the box's rim. A piece's boundary loops
/// bound the edge-connected regions of the positions outside it ([`boundary_loops`]), so these
/// are what its inner loops enclose, counted on a grid of the box where tracing the loops took
/// a hash map of corners per piece (a landmass block's settling asks this for the whole layout
/// at every shift it weighs: a thousand islands, a quarter of the run in the loops). A piece
/// whose box is mostly empty (a thin country laid out on the diagonal: 10,000 regions in a box
/// of 17 million positions) has its loops traced instead ([`enclosed_by_loops`]), so that the
/// cost follows the piece and not its box.
fn enclosed_by<'a>(piece: impl IntoIterator<Item = &'a Position> + Copy, tiling: Tiling) -> u32 {
    let Some((low, high)) = widened_box(piece) else {
        // No cell.
        return 0;
    };
    let positions = (high.0 - low.0 + 1) as usize * (high.1 - low.1 + 1) as usize;
    if positions > SMALL_BOX.max(MOSTLY_EMPTY * piece.into_iter().count()) {
        enclosed_by_loops(&piece.into_iter().copied().collect(), tiling)
    } else {
        enclosed_in_box(piece, (low, high), tiling)
    }
}

/// The box of `piece` widened by a position all round, as its lowest and highest positions;
/// `None` for no cell.
fn widened_box<'a>(piece: impl IntoIterator<Item = &'a Position>) -> Option<(Position, Position)> {
    let (mut low, mut high) = ((i32::MAX, i32::MAX), (i32::MIN, i32::MIN));
    for &(c, r) in piece {
        low = (low.0.min(c - 1), low.1.min(r - 1));
        high = (high.0.max(c + 1), high.1.max(r + 1));
    }
    (low.0 <= high.0).then_some((low, high))
}

/// [`enclosed_by`] by a flood of `piece`'s widened box `(low, high)` from its rim.
fn enclosed_in_box<'a>(
    piece: impl IntoIterator<Item = &'a Position> + Copy,
    (low, high): (Position, Position),
    tiling: Tiling,
) -> u32 {
    let width = (high.0 - low.0 + 1) as usize;
    let index = |(c, r): Position| (r - low.1) as usize * width + (c - low.0) as usize;
    let inside = |(c, r): Position| (low.0..=high.0).contains(&c) && (low.1..=high.1).contains(&r);
    // Per position of the box: in the piece, reached from the rim, or neither (enclosed).
    const OPEN: u8 = 0;
    const PIECE: u8 = 1;
    const REACHED: u8 = 2;
    let mut state = vec![OPEN; width * (high.1 - low.1 + 1) as usize];
    for &p in piece {
        state[index(p)] = PIECE;
    }
    // The rim is outside the piece and joined all round (every tiling steps along rows and
    // columns), so one corner of it reaches all of it.
    state[index(low)] = REACHED;
    let mut stack = vec![low];
    while let Some(p) = stack.pop() {
        for &n in tiling.edge_neighbours(p).iter() {
            if inside(n) && state[index(n)] == OPEN {
                state[index(n)] = REACHED;
                stack.push(n);
            }
        }
    }
    state.iter().filter(|&&s| s == OPEN).count() as u32
}

/// Positions of a piece's box per cell of the piece above which [`enclosed_by`] traces the
/// piece's loops rather than flooding its box. A compact layout's widened box holds one to
/// five positions per cell (Voronoi 3,000: 1.2; us_counties 2.2; world_countries 4.4).
const MOSTLY_EMPTY: usize = 64;

/// A box of at most this many positions is flooded whatever its piece: 4 KB of states, less
/// than the hash map of corners the loops need (a lone island's box holds 9 positions).
const SMALL_BOX: usize = 4096;

/// [`enclosed_by`] from `piece`'s boundary loops: the area of its inner (clockwise) loops, in
/// cells.
fn enclosed_by_loops(piece: &HashSet<Position>, tiling: Tiling) -> u32 {
    let inner: i64 = (boundary_loops(piece, tiling).iter())
        .map(|ring| twice_area(ring))
        .filter(|&area| area < 0)
        .sum();
    (-inner / twice_area(&unit_cell_ring(tiling))) as u32
}

/// The corners of the cell at (0, 0), closed: a cell's area in the loops' units.
fn unit_cell_ring(tiling: Tiling) -> Vec<Corner> {
    let corners = tiling.corners((0, 0));
    (0..=corners.len())
        .map(|k| corners[k % corners.len()])
        .collect()
}

/// Twice the signed area of a closed ring of corners (first corner repeated at the end), in
/// corner units, counter-clockwise positive: exact, in integers.
fn twice_area(ring: &[Corner]) -> i64 {
    (ring.windows(2))
        .map(|w| w[0].0 * w[1].1 - w[1].0 * w[0].1)
        .sum()
}

/// How many times the landmasses' blocks break: over the landmasses (`part[i]` is cell `i`'s),
/// the edge-connected pieces of each one's cells, less one. A world layout has a piece per
/// island and continent, which is no defect; a continent in two pieces is one.
pub(crate) fn landmass_breaks(cells: &[Position], part: &[usize], tiling: Tiling) -> usize {
    let parts = part.iter().map(|&p| p + 1).max().unwrap_or(0);
    let mut of_part: Vec<Vec<Position>> = vec![Vec::new(); parts];
    for (&cell, &p) in cells.iter().zip(part) {
        of_part[p].push(cell);
    }
    (of_part.iter())
        .map(|own| {
            let occupied: HashSet<Position> = own.iter().copied().collect();
            pieces(own, &occupied, tiling).len().saturating_sub(1)
        })
        .sum()
}

/// The edge-connected components of the cells (duplicates count once), largest first; a tie
/// keeps the order in which their first cells come.
fn pieces(
    cells: &[Position],
    occupied: &HashSet<Position>,
    tiling: Tiling,
) -> Vec<HashSet<Position>> {
    let mut found = Vec::new();
    each_piece(cells, occupied.clone(), tiling, |piece| {
        found.push(piece.iter().copied().collect::<HashSet<Position>>());
    });
    // Stable: equal sizes keep their order.
    found.sort_by_key(|piece| std::cmp::Reverse(piece.len()));
    found
}

/// Calls `visit` with each edge-connected component of the cells, in the order their first
/// cells come; `unvisited` holds the cells (duplicates count once).
fn each_piece(
    cells: &[Position],
    mut unvisited: HashSet<Position>,
    tiling: Tiling,
    mut visit: impl FnMut(&[Position]),
) {
    let mut piece = Vec::new();
    for &start in cells {
        if !unvisited.remove(&start) {
            continue;
        }
        piece.clear();
        piece.push(start);
        let mut next = 0;
        while let Some(&p) = piece.get(next) {
            next += 1;
            for &near in tiling.edge_neighbours(p).iter() {
                if unvisited.remove(&near) {
                    piece.push(near);
                }
            }
        }
        visit(&piece);
    }
}

/// Empty positions next to a cell whose sides are all taken but at most one.
fn notches(cells: &[Position], occupied: &HashSet<Position>, tiling: Tiling) -> u32 {
    let mut seen = HashSet::default();
    let mut count = 0;
    for &p in cells {
        for &q in tiling.edge_neighbours(p).iter() {
            if occupied.contains(&q) || !seen.insert(q) {
                continue;
            }
            let sides = tiling.edge_neighbours(q);
            let taken = sides.iter().filter(|s| occupied.contains(s)).count();
            count += u32::from(taken + 1 >= sides.len());
        }
    }
    count
}

/// Every boundary loop of a piece, as rings of corners (first corner repeated at the end):
/// counter-clockwise for the outer boundary, clockwise for each hole.
///
/// Every cell side facing a position outside the piece is a boundary edge, directed with the
/// cell on its left. Where two cells of the piece meet only at a corner, that corner has two
/// outgoing edges; the walk turns right, so it keeps following the same empty region: each loop
/// bounds one edge-connected region of empty space, as the rings of a polygon union do (a hole
/// may touch the outer ring at such a corner, and stays a hole).
fn boundary_loops(piece: &HashSet<Position>, tiling: Tiling) -> Vec<Vec<Corner>> {
    let mut outgoing: HashMap<Corner, Vec<Corner>> = HashMap::default();
    // In a fixed order, so that loops and their starts do not depend on the hash set's order.
    let mut cells: Vec<Position> = piece.iter().copied().collect();
    cells.sort_unstable_by_key(|&p| {
        let (x, y) = tiling.centre_key(p);
        (y, x)
    });
    for &p in cells.iter().rev() {
        let corners = tiling.corners(p);
        for (k, n) in tiling.edge_neighbours(p).iter().enumerate() {
            if !piece.contains(n) {
                outgoing
                    .entry(corners[k])
                    .or_default()
                    .push(corners[(k + 1) % corners.len()]);
            }
        }
    }
    // The first loop starts at the lowest, then leftmost cell's bottom-left corner, which
    // nothing of the piece lies below: the outer loop. The others start where only one edge
    // leaves (a corner where the piece pinches could be passed twice by one loop), in a fixed
    // order.
    let mut corners: Vec<Corner> = outgoing.keys().copied().collect();
    corners.sort_unstable();
    let outer = cells.first().map(|&p| lowest_corner(tiling, p));
    let mut loops = Vec::new();
    loop {
        let single = |c: &&Corner| outgoing.get(c).is_some_and(|ends| ends.len() == 1);
        let start = if loops.is_empty() { outer } else { None }
            .or_else(|| corners.iter().find(single).copied())
            .or_else(|| corners.iter().find(|c| outgoing.contains_key(c)).copied());
        let Some(start) = start else {
            return loops;
        };
        loops.push(trace_loop(&mut outgoing, start));
    }
}

/// The corner of `p` from which the outer loop is walked when `p` is the lowest, then leftmost
/// cell of its piece: its lowest corner (the leftmost of the lowest), where nothing of the piece
/// lies below, with exactly one boundary edge leaving it.
fn lowest_corner(tiling: Tiling, p: Position) -> Corner {
    let corners = tiling.corners(p);
    let offset = |c: &Corner| tiling.corner_offset(*c);
    *(corners.iter())
        .min_by(|a, b| {
            let (a, b) = (offset(a), offset(b));
            a.y.total_cmp(&b.y).then(a.x.total_cmp(&b.x))
        })
        .expect("a cell has corners")
}

/// Follows boundary edges from `start` until the walk is back there, turning right wherever
/// there is a choice, and removes the edges it used.
fn trace_loop(outgoing: &mut HashMap<Corner, Vec<Corner>>, start: Corner) -> Vec<Corner> {
    let take = |outgoing: &mut HashMap<Corner, Vec<Corner>>, at: Corner, k: usize| {
        let ends = outgoing.get_mut(&at).expect("a boundary corner");
        let next = ends.swap_remove(k);
        if ends.is_empty() {
            outgoing.remove(&at);
        }
        next
    };
    let first = take(outgoing, start, 0);
    let mut ring = vec![start];
    let (mut from, mut at) = (start, first);
    while at != start {
        ring.push(at);
        let heading = (at.0 - from.0, at.1 - from.1);
        // The rightmost turn: the smallest cross product of heading and next step.
        let k = (outgoing[&at].iter().enumerate())
            .min_by_key(|(_, &(x, y))| heading.0 * (y - at.1) - heading.1 * (x - at.0))
            .map(|(k, _)| k)
            .expect("every boundary corner has an outgoing edge");
        (from, at) = (at, take(outgoing, at, k));
    }
    ring.push(start);
    ring
}

/// C_shape: similarity of the outer ring of the largest piece of the cells and that of the
/// largest part of the regions' union, each by [`descriptor`]:
/// similarity = 1 − ‖d₁ − d₂‖₂ / (‖d₁‖₂ + ‖d₂‖₂) (method.md §8), in 0..=1, 1 for equal
/// descriptors; 0 when either outline is degenerate.
fn shape_similarity(layout: &Scored, shape: &LayoutShape) -> f64 {
    let (Some(cells), Some(regions)) = (
        cell_ring(layout, shape).and_then(|r| descriptor(&r)),
        layout.reference.shape.as_ref(),
    ) else {
        return 0.0;
    };
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let difference: Vec<f64> = cells.iter().zip(regions).map(|(a, b)| a - b).collect();
    let total = norm(&cells) + norm(regions);
    if total > 0.0 {
        1.0 - norm(&difference) / total
    } else {
        0.0
    }
}

/// Fourier descriptor of a closed ring, invariant to translation, scale, rotation and start
/// point: orient counter-clockwise, sample [`SAMPLES`] points evenly by arc length as complex
/// numbers z_k = x_k + i·y_k, take Z(n) = Σ_k z_k·e^(−2πi·n·k/N) and return
/// |Z(1)|, …, |Z(K)|, |Z(−K)|, …, |Z(−1)| divided by the larger of |Z(1)| and |Z(−1)|,
/// K = [`HARMONICS`] (the judge's order and normalisation). `None` for a ring without length or
/// extent.
fn descriptor(ring: &LineString<f64>) -> Option<Vec<f64>> {
    let mut ring = ring.clone();
    ring.close();
    ring.make_ccw_winding();
    let samples = resample(&ring.0, SAMPLES)?;
    // e^(−2πi·m/N) for m = 0..N: every n·k product reduces to one of these modulo N.
    let twiddles: Vec<(f64, f64)> = (0..SAMPLES)
        .map(|m| {
            let phase = -2.0 * std::f64::consts::PI * m as f64 / SAMPLES as f64;
            (phase.cos(), phase.sin())
        })
        .collect();
    let magnitude = |n: i64| {
        let (mut re, mut im) = (0.0, 0.0);
        for (k, z) in samples.iter().enumerate() {
            let (c, s) = twiddles[(n * k as i64).rem_euclid(SAMPLES as i64) as usize];
            re += z.x * c - z.y * s;
            im += z.x * s + z.y * c;
        }
        re.hypot(im)
    };
    let harmonics = HARMONICS as i64;
    let first = magnitude(1).max(magnitude(-1));
    (first > 0.0).then(|| {
        (1..=harmonics)
            .chain(-harmonics..=-1)
            .map(|n| magnitude(n) / first)
            .collect()
    })
}

/// `count` points evenly spaced by arc length along the closed ring `points` (first point
/// repeated at the end), starting at its first point. `None` when the ring has no length.
fn resample(points: &[Coord<f64>], count: usize) -> Option<Vec<Coord<f64>>> {
    let mut cumulative = Vec::with_capacity(points.len());
    let mut total = 0.0;
    cumulative.push(0.0);
    for w in points.windows(2) {
        total += distance(w[0], w[1]);
        cumulative.push(total);
    }
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let mut segment = 0;
    let samples = (0..count)
        .map(|k| {
            let at = total * k as f64 / count as f64;
            // `at` < total, so a segment ending beyond it always exists.
            while cumulative[segment + 1] <= at {
                segment += 1;
            }
            let (a, b) = (points[segment], points[segment + 1]);
            let along =
                (at - cumulative[segment]) / (cumulative[segment + 1] - cumulative[segment]);
            a + (b - a) * along
        })
        .collect();
    Some(samples)
}

/// The outer ring of the largest piece of the cells, in map units: cells of side `cell_size`
/// placed as their (column, row) say, anchored at the first region's centre. `None` with no
/// cells.
fn cell_ring(layout: &Scored, shape: &LayoutShape) -> Option<LineString<f64>> {
    let (&(col0, row0), &centre0) = layout.cells.first().zip(layout.centres.first())?;
    let piece = shape.pieces.first()?;
    let outer = boundary_loops(piece, layout.tiling).into_iter().next()?;
    let size = layout.cell_size;
    // Corner offsets are from the centre of position (0, 0); the first cell's centre is
    // centre_offset of its position from it.
    let first = layout.tiling.centre_offset((col0, row0));
    let to_map = |corner: Corner| {
        let offset = layout.tiling.corner_offset(corner) - first;
        centre0 + offset * size
    };
    Some(outer.into_iter().map(to_map).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use geo::{polygon, Polygon};

    #[test]
    fn enclosed_positions_are_the_inner_loops_area() {
        // Random cell sets, dense enough for holes and for pinches where cells meet at a
        // corner: the grid count against the traced loops' areas.
        use rand::{Rng, SeedableRng};
        let tilings = [
            Tiling::Square,
            Tiling::Hex(crate::core::params::HexOrientation::Pointy),
            Tiling::Hex(crate::core::params::HexOrientation::Flat),
        ];
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut with_holes = 0;
        for round in 0..600 {
            let tiling = tilings[round % 3];
            let side = rng.random_range(3..12);
            let density = rng.random_range(0.45..0.8);
            let cells: Vec<Position> = (0..side * side)
                .map(|k| (k % side, k / side))
                .filter(|_| rng.random::<f64>() < density)
                .collect();
            let occupied: HashSet<Position> = cells.iter().copied().collect();
            for piece in pieces(&cells, &occupied, tiling) {
                let flooded = enclosed_in_box(&piece, widened_box(&piece).unwrap(), tiling);
                assert_eq!(
                    flooded,
                    enclosed_by_loops(&piece, tiling),
                    "{tiling:?} {piece:?}"
                );
                with_holes += usize::from(flooded > 0);
            }
        }
        // The sets exercise holes, not only solid pieces.
        assert!(with_holes > 50, "{with_holes}");
        // A cell's area in corner units, which the loops' areas are divided by: 1 for squares;
        // 6 for hexagons, whose corner units are a quarter of the width by half the side.
        for (tiling, twice) in [(tilings[0], 2), (tilings[1], 12), (tilings[2], 12)] {
            assert_eq!(twice_area(&unit_cell_ring(tiling)), twice, "{tiling:?}");
        }
    }

    #[test]
    fn a_long_diagonal_piece_has_its_holes_counted_from_its_loops() {
        // A staircase of 3,000 cells from (0, 0) to (1500, 1499), in a box of 2.3 million
        // positions, and at its start a ring of 8 cells round one empty position, joined to the
        // staircase by (0, −1): one hole, by hand.
        let mut cells: Vec<Position> = (0..1500).flat_map(|k| [(k, k), (k + 1, k)]).collect();
        cells.push((0, -1));
        cells.extend(
            (-3..=-1)
                .flat_map(|c| (-3..=-1).map(move |r| (c, r)))
                .filter(|&p| p != (-2, -2)),
        );
        let piece: HashSet<Position> = cells.iter().copied().collect();
        let (low, high) = widened_box(&piece).unwrap();
        let positions = (high.0 - low.0 + 1) as usize * (high.1 - low.1 + 1) as usize;
        assert!(
            positions > MOSTLY_EMPTY * piece.len() + 4096,
            "the loops are traced"
        );
        assert_eq!(enclosed_by(&piece, Tiling::Square), 1);
        assert_eq!(enclosed_in_box(&piece, (low, high), Tiling::Square), 1);
        assert_eq!(LayoutShape::of(&cells, Tiling::Square).holes(), 1);
    }

    /// A 3×3 block of unit-square regions, region `3·row + col` at column `col`, row `row` (row 0
    /// on top), with rook adjacency and the block's outline.
    fn block() -> Reference {
        let centroids = (0..9)
            .map(|i| Coord {
                x: f64::from(i % 3) + 0.5,
                y: 2.5 - f64::from(i / 3),
            })
            .collect();
        let mut adjacency = Vec::new();
        for i in 0..9 {
            if i % 3 < 2 {
                adjacency.push((i, i + 1));
            }
            if i < 6 {
                adjacency.push((i, i + 3));
            }
        }
        let square: Polygon<f64> =
            polygon![(x: 0.0, y: 0.0), (x: 3.0, y: 0.0), (x: 3.0, y: 3.0), (x: 0.0, y: 3.0)];
        let outline = MultiPolygon(vec![square]);
        Reference::of(centroids, adjacency, outline, vec![0; 9], 1.0)
    }

    /// Unit cells for (column, row) positions, centres in the block's frame.
    fn centres_of(cells: &[Position]) -> Vec<Coord<f64>> {
        cells
            .iter()
            .map(|&(c, r)| Coord {
                x: f64::from(c) + 0.5,
                y: 2.5 - f64::from(r),
            })
            .collect()
    }

    fn scored<'a>(
        b: &'a Reference,
        cells: &'a [Position],
        centres: &'a [Coord<f64>],
        cell_size: f64,
    ) -> Scored<'a> {
        Scored {
            tiling: Tiling::Square,
            reference: b,
            moved: &b.centroids,
            cells,
            centres,
            cell_size,
        }
    }

    fn identity_cells() -> Vec<Position> {
        (0..9).map(|i| (i % 3, i / 3)).collect()
    }

    #[test]
    fn regions_on_their_own_cells_score_perfectly() {
        let b = block();
        let cells = identity_cells();
        let centres = centres_of(&cells);
        let (m, regions) = evaluate(&scored(&b, &cells, &centres, 1.0));
        assert_eq!(b.adjacency.len(), 12);
        assert_eq!((m.adjacent, m.adjacent_rook), (1.0, 1.0));
        assert_eq!((m.orientation, m.misdirected), (0.0, 0.0));
        assert!(m.location < 1e-12 && m.location_raw < 1e-12 && m.location_moved < 1e-12);
        assert!(m.location_p90 < 1e-12 && m.location_max < 1e-12);
        assert!(m.shape > 0.999_999, "{}", m.shape);
        // Touching pairs of a 3×3 block: 12 edge pairs and 8 diagonal ones, none of the diagonal
        // ones adjacent (rook adjacency).
        assert!((m.false_neighbours - 8.0 / 20.0).abs() < 1e-12);
        assert_eq!(
            (m.pieces, m.holes, m.notches, m.source_pieces),
            (1, 0, 0, 1)
        );
        assert_eq!((m.source_holes, m.wrong_landmass), (0.0, 0.0));
        for r in &regions {
            assert_eq!((r.neighbours_kept, r.orientation_error), (1.0, 0.0));
            assert!(r.displacement < 1e-12);
        }
    }

    #[test]
    fn the_fit_removes_scale_and_shift_but_the_raw_variants_do_not() {
        let b = block();
        let cells = identity_cells();
        let centres: Vec<Coord<f64>> = b
            .centroids
            .iter()
            .map(|&c| c * 0.5 + Coord { x: 10.0, y: -4.0 })
            .collect();
        let (m, _) = evaluate(&scored(&b, &cells, &centres, 0.5));
        assert!(m.location < 1e-12, "{}", m.location);
        let raw = b
            .centroids
            .iter()
            .zip(&centres)
            .map(|(&c, &g)| distance(c, g))
            .sum::<f64>()
            / 9.0;
        assert!((m.location_raw - raw).abs() < 1e-12 && raw > 10.0);
        assert!(
            (m.location_moved - raw).abs() < 1e-12,
            "moved = centroids, unit = 1"
        );
        assert!(
            m.shape > 0.999_999,
            "the same square at another scale: {}",
            m.shape
        );
    }

    #[test]
    fn location_is_in_fitted_cells() {
        // Cells at half the centroids' spacing, one region one cell out of place: the fit scales
        // by about 2, so the displacement counts in fitted cells (of side 2 × 0.5 = 1 map unit).
        let b = block();
        let mut cells = identity_cells();
        cells[8] = (3, 2);
        let centres: Vec<Coord<f64>> = centres_of(&cells).iter().map(|&c| c * 0.5).collect();
        let (m, regions) = evaluate(&scored(&b, &cells, &centres, 0.5));
        let (s, t) = fit(&centres, &b.centroids);
        for (i, r) in regions.iter().enumerate() {
            let expected = distance(b.centroids[i], centres[i] * s + t) / (0.5 * s);
            assert!((r.displacement - expected).abs() < 1e-12);
        }
        assert!((m.location_max - regions[8].displacement).abs() < 1e-12);
        // Nine values: the 90th percentile is 80 % of the way from the 8th to the 9th.
        let mut sorted: Vec<f64> = regions.iter().map(|r| r.displacement).collect();
        sorted.sort_by(f64::total_cmp);
        assert!((m.location_p90 - (sorted[7] + 0.2 * (sorted[8] - sorted[7]))).abs() < 1e-12);
    }

    #[test]
    fn a_row_fitted_to_a_column_keeps_its_scale() {
        // Five strips stacked up, laid out in a row: the exact covariance is 0 (the judge then
        // fits the shift alone), and rounding in a transform must not make it a tiny scale.
        let column: Vec<Coord<f64>> = (0..5)
            .map(|k| Coord {
                x: 50.0,
                y: k as f64,
            })
            .collect();
        let row: Vec<Coord<f64>> = (0..5)
            .map(|k| Coord {
                x: 10.0 * k as f64,
                y: 1e-15 * k as f64,
            })
            .collect();
        assert_eq!(fit(&row, &column).0, 1.0);
        // A weak but real correlation keeps its fitted scale.
        let tilted: Vec<Coord<f64>> = row
            .iter()
            .map(|&c| {
                c + Coord {
                    x: 0.0,
                    y: 1e-3 * c.x,
                }
            })
            .collect();
        let (scale, _) = fit(&tilted, &column);
        assert!(scale > 0.0 && scale < 1e-3, "{scale}");
    }

    #[test]
    fn a_mirrored_layout_keeps_neighbours_but_flips_directions() {
        let b = block();
        let cells: Vec<Position> = (0..9).map(|i| (2 - i % 3, i / 3)).collect();
        let centres = centres_of(&cells);
        let layout = scored(&b, &cells, &centres, 1.0);
        let (m, regions) = evaluate(&layout);
        assert_eq!(m.adjacent, 1.0);
        // The 6 left-right pairs point the opposite way, the 6 up-down pairs are unchanged.
        let pair = |i: usize, j: usize| PairScore::of(&layout, i, j).angle.unwrap();
        assert_eq!(pair(0, 1), 180.0);
        assert_eq!(pair(4, 5), 180.0);
        assert_eq!(pair(0, 3), 0.0);
        assert!((m.orientation - 90.0).abs() < 1e-9, "{}", m.orientation);
        assert_eq!(m.misdirected, 0.5);
        // Region 1 (top middle) has two left-right neighbours and one below it.
        assert!((regions[1].orientation_error - 120.0).abs() < 1e-9);
        assert!((regions[4].orientation_error - 90.0).abs() < 1e-9);
        // The best scale for a mirror image of a symmetric block is exactly 0: the fit keeps
        // s = 1 and shifts, so the cells stay where they are, mirrored.
        let moved: f64 = (0..9)
            .map(|i| distance(b.centroids[i], centres[i]))
            .sum::<f64>()
            / 9.0;
        assert!(
            (m.location - moved).abs() < 1e-12,
            "{} vs {moved}",
            m.location
        );
    }

    /// Hand-counted layouts: `#` is a cell, `.` an empty position, rows from the top.
    fn cells_of(picture: &[&str]) -> Vec<Position> {
        let mut cells = Vec::new();
        for (row, line) in picture.iter().enumerate() {
            for (col, ch) in line.chars().enumerate() {
                if ch == '#' {
                    cells.push((col as i32, row as i32));
                }
            }
        }
        cells
    }

    #[test]
    fn a_landmass_in_two_pieces_is_one_break_and_islands_are_none() {
        // Landmass 0: a row of three cells and, apart, one more (two pieces: one break).
        // Landmasses 1 and 2: one cell each, apart from everything (no break), and landmass 1
        // touching landmass 0 does not join them.
        let cells = [(0, 0), (1, 0), (2, 0), (5, 0), (3, 0), (8, 8)];
        let part = [0, 0, 0, 0, 1, 2];
        assert_eq!(landmass_breaks(&cells, &part, Tiling::Square), 1);
        assert_eq!(LayoutShape::of(&cells, Tiling::Square).pieces(), 3);
        assert_eq!(landmass_breaks(&cells[..3], &part[..3], Tiling::Square), 0);
    }

    #[test]
    fn only_holes_of_half_a_cell_or_more_are_lakes() {
        // A 10 × 10 map of 100 regions (S = 1) with a lake of 2 × 2 and a sliver of 1 × 0.1
        // between regions: the sliver's area, a fortieth of the holes', is no lake (§1).
        let rect = |x0: f64, y0: f64, x1: f64, y1: f64| {
            LineString::from(vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)])
        };
        let holed = |holes: Vec<LineString<f64>>| {
            let outline = MultiPolygon(vec![Polygon::new(rect(0.0, 0.0, 10.0, 10.0), holes)]);
            Reference::of(vec![Coord::zero()], vec![], outline, vec![0], 1.0)
        };
        let both = holed(vec![rect(2.0, 2.0, 4.0, 4.0), rect(6.0, 6.0, 7.0, 6.1)]);
        assert!(
            (both.lake_share - 4.0 / 4.1).abs() < 1e-12,
            "{}",
            both.lake_share
        );
        assert_eq!(holed(vec![rect(6.0, 6.0, 7.0, 6.1)]).lake_share, 0.0);
        assert_eq!(holed(vec![]).lake_share, 1.0);
    }

    #[test]
    fn pieces_holes_and_notches_are_counted_as_by_hand() {
        // A ring around one hole, a notch in its right side, and a separate cell that touches
        // the ring only at a corner (a piece of its own: corners do not join pieces).
        let ring = cells_of(&["####.", "#.#..", "####.", "....#"]);
        let shape = LayoutShape::of(&ring, Tiling::Square);
        assert_eq!(shape.pieces.len(), 2);
        assert_eq!(shape.pieces[0].len(), 10);
        // The hole (1, 1); the notch (3, 1) has three sides taken (left, top, bottom) and one
        // free. (4, 0) and (4, 2) have two sides free each: not notches.
        assert_eq!(shape.holes, 1);
        assert_eq!(shape.notches, 2);

        // A pocket that meets the outside only at a corner stays a hole, as in a polygon union.
        let pinched = cells_of(&["###", "#.#", "##."]);
        let shape = LayoutShape::of(&pinched, Tiling::Square);
        assert_eq!((shape.pieces.len(), shape.holes), (1, 1));
        // A bay two cells deep is no hole; its inner end is a notch, its mouth is not.
        let bay = cells_of(&["###", "#.#", "#.#", "#.#"]);
        let shape = LayoutShape::of(&bay, Tiling::Square);
        assert_eq!((shape.holes, shape.notches), (0, 1));
    }

    #[test]
    fn the_cell_ring_is_in_map_units() {
        let cells: Vec<Position> = (0..10_000).map(|i| (i % 100, i / 100)).collect();
        let centres: Vec<Coord<f64>> = cells
            .iter()
            .map(|&(c, r)| Coord {
                x: 1000.0 + 2.0 * f64::from(c) + 1.0,
                y: 500.0 - 2.0 * f64::from(r) - 1.0,
            })
            .collect();
        let outline = MultiPolygon(vec![]);
        let reference = Reference::of(centres.clone(), vec![], outline, vec![], 2.0);
        let layout = Scored {
            tiling: Tiling::Square,
            reference: &reference,
            moved: &centres,
            cells: &cells,
            centres: &centres,
            cell_size: 2.0,
        };
        let shape = LayoutShape::of(&cells, Tiling::Square);
        let ring = cell_ring(&layout, &shape).unwrap();
        let polygon = Polygon::new(ring, vec![]);
        assert_eq!(polygon.signed_area(), 40_000.0);
        let bounds = geo::BoundingRect::bounding_rect(&polygon).unwrap();
        assert_eq!((bounds.min().x, bounds.max().y), (1000.0, 500.0));
        assert_eq!((bounds.max().x, bounds.min().y), (1200.0, 300.0));
        // No outline to compare with: the shape metric is 0, not NaN.
        assert_eq!(evaluate(&layout).0.shape, 0.0);
    }

    #[test]
    fn regions_nearer_another_landmass_are_counted() {
        // Two landmasses of three regions each, far apart; one region of the left one is given a
        // cell among the right one's.
        let left: Polygon<f64> =
            polygon![(x: 0.0, y: 0.0), (x: 3.0, y: 0.0), (x: 3.0, y: 1.0), (x: 0.0, y: 1.0)];
        let right: Polygon<f64> =
            polygon![(x: 10.0, y: 0.0), (x: 13.0, y: 0.0), (x: 13.0, y: 1.0), (x: 10.0, y: 1.0)];
        let outline = MultiPolygon(vec![left, right]);
        let centroids: Vec<Coord<f64>> = [0.5, 1.5, 2.5, 10.5, 11.5, 12.5]
            .iter()
            .map(|&x| Coord { x, y: 0.5 })
            .collect();
        let reference = Reference::of(
            centroids.clone(),
            vec![],
            outline,
            vec![0, 0, 0, 1, 1, 1],
            1.0,
        );
        let mut cells: Vec<Position> = vec![(0, 0), (1, 0), (2, 0), (10, 0), (11, 0), (12, 0)];
        let centres = |cells: &[Position]| -> Vec<Coord<f64>> {
            cells
                .iter()
                .map(|&(c, _)| Coord {
                    x: f64::from(c) + 0.5,
                    y: 0.5,
                })
                .collect()
        };
        let at_home = centres(&cells);
        let layout = Scored {
            tiling: Tiling::Square,
            reference: &reference,
            moved: &centroids,
            cells: &cells,
            centres: &at_home,
            cell_size: 1.0,
        };
        assert_eq!(evaluate(&layout).0.wrong_landmass, 0.0);
        cells[2] = (13, 0);
        let moved = centres(&cells);
        let layout = Scored {
            tiling: Tiling::Square,
            reference: &reference,
            moved: &centroids,
            cells: &cells,
            centres: &moved,
            cell_size: 1.0,
        };
        let m = evaluate(&layout).0;
        assert!(
            (m.wrong_landmass - 1.0 / 6.0).abs() < 1e-12,
            "{}",
            m.wrong_landmass
        );
    }

    #[test]
    fn a_landmass_whose_box_is_near_but_whose_land_is_far_is_not_nearer() {
        // A square island (0, 0)-(2, 2) and an L-shaped landmass: its foot x ≥ 3, y ≤ 1 and its
        // stem x ≥ 8, in the box (3, 0)-(9, 6), which holds points far from its land.
        let island: Polygon<f64> =
            polygon![(x: 0.0, y: 0.0), (x: 2.0, y: 0.0), (x: 2.0, y: 2.0), (x: 0.0, y: 2.0)];
        let l_shape: Polygon<f64> = polygon![
            (x: 3.0, y: 0.0), (x: 9.0, y: 0.0), (x: 9.0, y: 6.0), (x: 8.0, y: 6.0),
            (x: 8.0, y: 1.0), (x: 3.0, y: 1.0)
        ];
        let lands = Landmasses::new(&MultiPolygon(vec![island, l_shape]), vec![0, 0, 0, 1, 1, 1]);
        assert_eq!(lands.of(), [0, 0, 0, 1, 1, 1]);
        // (4, 3): the island's corner (2, 2) is √5 ≈ 2.24 away, the L's foot 2: nearer the L.
        let p = Coord { x: 4.0, y: 3.0 };
        assert!(lands.misplaced(0, p) && lands.nearer_another(0, p));
        assert!(
            !lands.misplaced(3, p),
            "outside its own L but nearer it than the island"
        );
        // (3.5, 4.5), inside the L's box: the island √(1.5² + 2.5²) ≈ 2.92 away, the L's land 3.5.
        let q = Coord { x: 3.5, y: 4.5 };
        assert!(!lands.nearer_another(0, q));
        assert!(lands.nearer_another(1, q));
        // (-1, 1): the island 1 away, the L's box 4: the L is not searched, and not nearer.
        assert!(!lands.nearer_another(0, Coord { x: -1.0, y: 1.0 }));
        assert!(lands.nearer_another(1, Coord { x: -1.0, y: 1.0 }));
        // Inside its own landmass a region is never misplaced; a landmass that does not count
        // (no such landmass) answers false.
        assert!(!lands.nearer_another(1, Coord { x: 8.5, y: 3.0 }));
        assert!(!lands.nearer_another(7, p));
    }
}
