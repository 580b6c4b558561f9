//! The quality metrics of method.md §8: location, adjacency, orientation and shape.
//!
//! Each adjacent pair is scored once ([`PairScore`]); the layout numbers are means over all
//! pairs and the per-region numbers means over the pairs incident to the region, so both come
//! from the same helpers. Likewise the location fit is computed once and gives both the layout's
//! C_location and each region's displacement.

use super::{LayoutMetrics, RegionMetrics};
use geo::{Area, Coord, LineString, MultiPolygon, Winding};
use std::collections::{HashMap, HashSet};

/// A layout to score, in one planar frame.
pub struct Scored<'a> {
    /// Original region centroids c_i.
    pub centroids: &'a [Coord<f64>],
    /// Moved centroids q_i (for the paper's location variant).
    pub moved: &'a [Coord<f64>],
    /// Cell (column, row) of each region; row grows downwards.
    pub cells: &'a [(i32, i32)],
    /// Cell centres g_i.
    pub centres: &'a [Coord<f64>],
    /// Side of a cell.
    pub cell_size: f64,
    /// S of the original map, the unit of C_location (sqrt(total area / M)).
    pub unit: f64,
    /// Adjacent region pairs (i < j).
    pub adjacency: &'a [(usize, usize)],
    /// The union of the regions.
    pub outline: &'a MultiPolygon<f64>,
}

/// Points sampled along each outline for the Fourier descriptors.
const SAMPLES: usize = 256;
/// Harmonics kept on each side of 0 (1..=K and −1..=−K).
const HARMONICS: usize = 32;
/// A pair whose direction is off by more than this is misdirected (degrees).
const MISDIRECTED_DEG: f64 = 45.0;

/// Computes the layout metrics and the per-region metrics (in the order of `layout.centroids`)
/// of method.md §8.
///
/// Definitions where the spec leaves room:
/// - C_location: the scale-and-translation fit g ↦ s·g + t minimises Σ|s·g_i + t − c_i|² in
///   closed form (see [`fit`]); C_location = mean |c_i − (s·g_i + t)| / unit. `location_raw` =
///   mean |c_i − g_i| (map units), `location_moved` = mean |q_i − g_i| / unit; all 0 with no
///   regions.
/// - With no adjacent pairs, `adjacent` = `adjacent_rook` = 1 (nothing was lost) and
///   `orientation` = `misdirected` = 0; per region likewise `neighbours_kept` = 1 and
///   `orientation_error` = 0.
/// - Angles are directed (0..=180°); a pair whose two centroids (or cells) coincide has no
///   direction and counts as 0°.
/// - C_shape: see [`shape_similarity`].
pub fn evaluate(layout: &Scored) -> (LayoutMetrics, Vec<RegionMetrics>) {
    let m = layout.centroids.len();
    debug_assert!(
        layout.moved.len() == m && layout.cells.len() == m && layout.centres.len() == m,
        "every region needs a moved centroid, a cell and a cell centre"
    );
    let (scale, shift) = fit(layout.centres, layout.centroids);
    let displacement: Vec<f64> = (0..m)
        .map(|i| distance(layout.centroids[i], layout.centres[i] * scale + shift) / layout.unit)
        .collect();
    let pairs: Vec<PairScore> = layout
        .adjacency
        .iter()
        .map(|&(i, j)| PairScore::of(layout, i, j))
        .collect();
    // The pairs each region belongs to, for its own share and mean angle.
    let mut incident: Vec<Vec<&PairScore>> = vec![Vec::new(); m];
    for (&(i, j), pair) in layout.adjacency.iter().zip(&pairs) {
        incident[i].push(pair);
        incident[j].push(pair);
    }

    let metrics = LayoutMetrics {
        location: mean_or(displacement.iter().copied(), 0.0),
        location_raw: mean_or(
            (0..m).map(|i| distance(layout.centroids[i], layout.centres[i])),
            0.0,
        ),
        location_moved: mean_or(
            (0..m).map(|i| distance(layout.moved[i], layout.centres[i]) / layout.unit),
            0.0,
        ),
        adjacent: kept_share(&pairs),
        adjacent_rook: mean_or(pairs.iter().map(|p| indicator(p.rook)), 1.0),
        orientation: mean_angle(&pairs),
        misdirected: mean_or(
            pairs.iter().map(|p| indicator(p.angle > MISDIRECTED_DEG)),
            0.0,
        ),
        shape: shape_similarity(layout),
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
    /// Directed angle between c_j − c_i and g_j − g_i, degrees in 0..=180.
    angle: f64,
}

impl PairScore {
    fn of(layout: &Scored, i: usize, j: usize) -> PairScore {
        let (a, b) = (layout.cells[i], layout.cells[j]);
        let (dc, dr) = ((a.0 - b.0).abs(), (a.1 - b.1).abs());
        PairScore {
            queen: dc.max(dr) == 1,
            rook: dc + dr == 1,
            angle: angle_deg(
                layout.centroids[j] - layout.centroids[i],
                layout.centres[j] - layout.centres[i],
            ),
        }
    }
}

/// Share of `pairs` whose cells stayed 8-neighbours; 1 with no pairs (nothing was lost).
fn kept_share<'p>(pairs: impl IntoIterator<Item = &'p PairScore>) -> f64 {
    mean_or(pairs.into_iter().map(|p| indicator(p.queen)), 1.0)
}

/// Mean direction error of `pairs` in degrees; 0 with no pairs.
fn mean_angle<'p>(pairs: impl IntoIterator<Item = &'p PairScore>) -> f64 {
    mean_or(pairs.into_iter().map(|p| p.angle), 0.0)
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

fn distance(a: Coord<f64>, b: Coord<f64>) -> f64 {
    (a.x - b.x).hypot(a.y - b.y)
}

/// Unsigned angle from `u` to `v` in degrees (0..=180): atan2 of the cross and dot products,
/// which stays accurate near 0° and 180° where acos of the normalised dot product does not.
fn angle_deg(u: Coord<f64>, v: Coord<f64>) -> f64 {
    let cross = u.x * v.y - u.y * v.x;
    let dot = u.x * v.x + u.y * v.y;
    cross.atan2(dot).abs().to_degrees()
}

/// The least-squares scale s and translation t minimising Σ|s·from_i + t − onto_i|².
///
/// Closed form: with the means f̄, ō, s = Σ(f_i − f̄)·(o_i − ō) / Σ|f_i − f̄|² and t = ō − s·f̄.
/// The scale is left free in sign (a mirrored layout can fit best collapsed, s ≈ 0). When
/// `from` has no spread (one region) the scale is undetermined and taken as 1.
fn fit(from: &[Coord<f64>], onto: &[Coord<f64>]) -> (f64, Coord<f64>) {
    let n = from.len().max(1) as f64;
    let mean = |points: &[Coord<f64>]| {
        points
            .iter()
            .fold(Coord { x: 0.0, y: 0.0 }, |acc, &p| acc + p)
            / n
    };
    let (fm, om) = (mean(from), mean(onto));
    let (mut covariance, mut variance) = (0.0, 0.0);
    for (&f, &o) in from.iter().zip(onto) {
        let (df, d_o) = (f - fm, o - om);
        covariance += df.x * d_o.x + df.y * d_o.y;
        variance += df.x * df.x + df.y * df.y;
    }
    let scale = if variance > 0.0 {
        covariance / variance
    } else {
        1.0
    };
    (scale, om - fm * scale)
}

/// C_shape: similarity of the outer ring of the largest part of the cell union and that of the
/// largest part of the region outline, each by [`descriptor`]:
/// similarity = 1 − Σ_k |d1_k − d2_k| / Σ_k (|d1_k| + |d2_k|), in 0..=1 (triangle inequality),
/// 1 for equal descriptors. The L1 form weighs every harmonic by its own difference; a
/// Euclidean norm would be dominated by the first few (largest) harmonics and barely see the
/// corners that distinguish a blocky layout. 0 when either outline is degenerate.
fn shape_similarity(layout: &Scored) -> f64 {
    let largest = layout
        .outline
        .0
        .iter()
        .max_by(|a, b| a.unsigned_area().total_cmp(&b.unsigned_area()));
    let (Some(cells), Some(regions)) = (
        cell_ring(layout).and_then(|r| descriptor(&r)),
        largest.and_then(|p| descriptor(p.exterior())),
    ) else {
        return 0.0;
    };
    similarity(&cells, &regions)
}

/// 1 − Σ|d1 − d2| / Σ(|d1| + |d2|); see [`shape_similarity`].
fn similarity(d1: &[f64], d2: &[f64]) -> f64 {
    let (difference, total) = d1.iter().zip(d2).fold((0.0, 0.0), |(d, t), (a, b)| {
        (d + (a - b).abs(), t + a.abs() + b.abs())
    });
    if total > 0.0 {
        1.0 - difference / total
    } else {
        0.0
    }
}

/// Fourier descriptor of a closed ring, invariant to translation, scale, rotation and start
/// point: orient counter-clockwise, sample [`SAMPLES`] points evenly by arc length as complex
/// numbers z_k = x_k + i·y_k, take Z(n) = Σ_k z_k·e^(−2πi·n·k/N) and return
/// |Z(1)|, …, |Z(K)|, |Z(−1)|, …, |Z(−K)| divided by |Z(1)|, K = [`HARMONICS`].
///
/// Z(0) (the only term a translation changes) is left out; a rotation or a shifted start
/// multiplies each Z(n) by a unit complex number, so the magnitudes do not see it; the division
/// removes the scale. Counter-clockwise orientation makes Z(1) the dominant harmonic. `None` for
/// a ring without length or extent.
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
    let first = magnitude(1);
    let harmonics = HARMONICS as i64;
    (first > 0.0).then(|| {
        (1..=harmonics)
            .chain((1..=harmonics).map(|n| -n))
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

/// The outer ring of the largest part of the union of the cells, in map units: squares of side
/// `cell_size` placed as the cells' (column, row) say, anchored at the first region's centre.
///
/// Traced exactly on the lattice instead of by polygon booleans: parts are the 4-connected
/// components of the cell set (cells meeting only at a corner are separate parts, as in a
/// polygon union), the largest has the most cells (the first found on a tie), and its outer
/// ring is followed along the unit edges that separate its cells from empty ones. Linear in the
/// number of cells. `None` with no cells.
fn cell_ring(layout: &Scored) -> Option<LineString<f64>> {
    let (&(col0, row0), &centre0) = layout.cells.first().zip(layout.centres.first())?;
    let part = largest_part(layout.cells);
    let size = layout.cell_size;
    // Lattice corners are worked in (x, y) = (column, −row) so that y points up as in the map;
    // corner (x, y) lies at the first centre plus (x − col0 − ½, y + row0 + ½) cells.
    let to_map = |(x, y): (i32, i32)| Coord {
        x: centre0.x + (f64::from(x - col0) - 0.5) * size,
        y: centre0.y + (f64::from(y + row0) + 0.5) * size,
    };
    Some(trace_outer(&part).into_iter().map(to_map).collect())
}

/// The largest 4-connected component of `cells` (duplicates count once).
fn largest_part(cells: &[(i32, i32)]) -> HashSet<(i32, i32)> {
    let mut unvisited: HashSet<(i32, i32)> = cells.iter().copied().collect();
    let mut best = HashSet::new();
    for &start in cells {
        if !unvisited.remove(&start) {
            continue;
        }
        let mut part = HashSet::from([start]);
        let mut stack = vec![start];
        while let Some((c, r)) = stack.pop() {
            for next in [(c + 1, r), (c - 1, r), (c, r + 1), (c, r - 1)] {
                if unvisited.remove(&next) {
                    part.insert(next);
                    stack.push(next);
                }
            }
        }
        if part.len() > best.len() {
            best = part;
        }
    }
    best
}

/// The outer boundary of a non-empty 4-connected set of (column, row) cells as a closed ring of
/// lattice corners in (column, −row) coordinates, counter-clockwise.
///
/// Every cell side facing an empty cell is a boundary edge, directed with the cell on its left.
/// The walk starts on the bottom side of the lowest, then leftmost cell, which faces the
/// unbounded outside, so it follows the outer ring and not a hole. Where two cells of the part
/// meet only at a corner (the part closes on itself there), that corner has two outgoing edges:
/// the right turn keeps the walk along the empty space it has been following, the outside. So
/// the ring is simple, and an empty pocket that meets the outside only at that corner is left
/// inside it as a hole, as a polygon union would; the left turn would walk into the pocket and
/// touch the ring at the corner. Cells of other parts are not in `part`, so they never make
/// such corners.
fn trace_outer(part: &HashSet<(i32, i32)>) -> Vec<(i32, i32)> {
    let mut outgoing: HashMap<(i32, i32), Vec<(i32, i32)>> = HashMap::new();
    for &(c, r) in part {
        let (x, y) = (c, -r - 1);
        let sides = [
            ((c, r + 1), (x, y), (x + 1, y)),
            ((c + 1, r), (x + 1, y), (x + 1, y + 1)),
            ((c, r - 1), (x + 1, y + 1), (x, y + 1)),
            ((c - 1, r), (x, y + 1), (x, y)),
        ];
        for (neighbour, from, to) in sides {
            if !part.contains(&neighbour) {
                outgoing.entry(from).or_default().push(to);
            }
        }
    }
    let Some(&(c, r)) = part.iter().min_by_key(|&&(c, r)| (-r, c)) else {
        return Vec::new();
    };
    let start = (c, -r - 1);
    let mut ring = vec![start];
    let (mut from, mut at) = (start, (c + 1, -r - 1));
    // The start corner has only the start cell around it (nothing lies below or left of it in
    // its row), so the walk comes back to it only when the ring closes.
    while at != start {
        ring.push(at);
        let heading = (at.0 - from.0, at.1 - from.1);
        let next = outgoing[&at]
            .iter()
            .copied()
            .min_by_key(|&(x, y)| heading.0 * (y - at.1) - heading.1 * (x - at.0))
            .expect("every boundary corner has an outgoing edge");
        (from, at) = (at, next);
    }
    ring.push(start);
    ring
}

#[cfg(test)]
mod tests {
    use super::*;
    use geo::{polygon, Polygon};

    /// A 3×3 block of unit-square regions, region `3·row + col` at column `col`, row `row` (row 0
    /// on top), with rook adjacency and the block's outline.
    struct Block {
        centroids: Vec<Coord<f64>>,
        adjacency: Vec<(usize, usize)>,
        outline: MultiPolygon<f64>,
    }

    fn block() -> Block {
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
        Block {
            centroids,
            adjacency,
            outline: MultiPolygon(vec![square]),
        }
    }

    /// Unit cells for (column, row) positions, centres in the block's frame.
    fn centres_of(cells: &[(i32, i32)]) -> Vec<Coord<f64>> {
        cells
            .iter()
            .map(|&(c, r)| Coord {
                x: f64::from(c) + 0.5,
                y: 2.5 - f64::from(r),
            })
            .collect()
    }

    fn run(
        b: &Block,
        cells: &[(i32, i32)],
        centres: &[Coord<f64>],
        cell_size: f64,
    ) -> (LayoutMetrics, Vec<RegionMetrics>) {
        evaluate(&Scored {
            centroids: &b.centroids,
            moved: &b.centroids,
            cells,
            centres,
            cell_size,
            unit: 1.0,
            adjacency: &b.adjacency,
            outline: &b.outline,
        })
    }

    fn identity_cells() -> Vec<(i32, i32)> {
        (0..9).map(|i| (i % 3, i / 3)).collect()
    }

    #[test]
    fn regions_on_their_own_cells_score_perfectly() {
        let b = block();
        let cells = identity_cells();
        let (m, regions) = run(&b, &cells, &centres_of(&cells), 1.0);
        assert_eq!(b.adjacency.len(), 12);
        assert_eq!((m.adjacent, m.adjacent_rook), (1.0, 1.0));
        assert_eq!((m.orientation, m.misdirected), (0.0, 0.0));
        assert!(m.location < 1e-12 && m.location_raw < 1e-12 && m.location_moved < 1e-12);
        assert!(m.shape > 0.999_999, "{}", m.shape);
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
        let (m, _) = run(&b, &cells, &centres, 0.5);
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
    fn a_mirrored_layout_keeps_neighbours_but_flips_directions() {
        let b = block();
        let cells: Vec<(i32, i32)> = (0..9).map(|i| (2 - i % 3, i / 3)).collect();
        let centres = centres_of(&cells);
        let (m, regions) = run(&b, &cells, &centres, 1.0);
        assert_eq!(m.adjacent, 1.0);
        // The 6 left-right pairs point the opposite way, the 6 up-down pairs are unchanged.
        let pair = |i: usize, j: usize| {
            PairScore::of(
                &Scored {
                    centroids: &b.centroids,
                    moved: &b.centroids,
                    cells: &cells,
                    centres: &centres,
                    cell_size: 1.0,
                    unit: 1.0,
                    adjacency: &b.adjacency,
                    outline: &b.outline,
                },
                i,
                j,
            )
            .angle
        };
        assert_eq!(pair(0, 1), 180.0);
        assert_eq!(pair(4, 5), 180.0);
        assert_eq!(pair(0, 3), 0.0);
        assert!((m.orientation - 90.0).abs() < 1e-9, "{}", m.orientation);
        assert_eq!(m.misdirected, 0.5);
        // Region 1 (top middle) has two left-right neighbours and one below it.
        assert!((regions[1].orientation_error - 120.0).abs() < 1e-9);
        assert!((regions[4].orientation_error - 90.0).abs() < 1e-9);
        // No scale fits a mirror image: the best is to collapse onto the centroids' mean.
        let spread = b
            .centroids
            .iter()
            .map(|&c| distance(c, Coord { x: 1.5, y: 1.5 }))
            .sum::<f64>()
            / 9.0;
        assert!(
            (m.location - spread).abs() < 1e-12,
            "{} vs {spread}",
            m.location
        );
        assert!(m.shape > 0.999_999, "still a square: {}", m.shape);
    }

    #[test]
    fn swapping_two_corner_regions_loses_their_neighbours() {
        let b = block();
        let mut cells = identity_cells();
        cells.swap(0, 8);
        let (m, regions) = run(&b, &cells, &centres_of(&cells), 1.0);
        assert!((m.adjacent - 8.0 / 12.0).abs() < 1e-12, "{}", m.adjacent);
        assert!((m.adjacent_rook - 8.0 / 12.0).abs() < 1e-12);
        assert_eq!(regions[0].neighbours_kept, 0.0);
        assert_eq!(regions[1].neighbours_kept, 2.0 / 3.0);
        assert_eq!(regions[4].neighbours_kept, 1.0);
        // The fit shrinks the layout by s = 1/3 about the centre (the swap contradicts it), so
        // region 0's fitted cell lies at (1/3, −1/3) from the centre instead of (−1, 1).
        assert!((regions[0].displacement - 4.0 / 3.0 * 2f64.sqrt()).abs() < 1e-12);
        assert!(regions[4].displacement < 1e-12);
        assert!(m.orientation > 0.0 && m.misdirected > 0.0);
    }

    #[test]
    fn diagonal_cells_are_queen_but_not_rook_neighbours() {
        let centroids = [Coord { x: 0.0, y: 0.0 }, Coord { x: 1.0, y: 0.0 }];
        let cells = [(0, 0), (1, 1)];
        let centres = [Coord { x: 0.5, y: -0.5 }, Coord { x: 1.5, y: -1.5 }];
        let outline = MultiPolygon(vec![
            polygon![(x: -0.5, y: -0.5), (x: 1.5, y: -0.5), (x: 1.5, y: 0.5), (x: -0.5, y: 0.5)],
        ]);
        let scored = |adjacency: &'static [(usize, usize)]| Scored {
            centroids: &centroids,
            moved: &centroids,
            cells: &cells,
            centres: &centres,
            cell_size: 1.0,
            unit: 1.0,
            adjacency,
            outline: &outline,
        };
        let (m, regions) = evaluate(&scored(&[(0, 1)]));
        assert_eq!((m.adjacent, m.adjacent_rook), (1.0, 0.0));
        assert!((m.orientation - 45.0).abs() < 1e-9);
        assert_eq!(m.misdirected, 0.0, "exactly 45° is not misdirected");
        assert!((regions[1].orientation_error - 45.0).abs() < 1e-9);
        // Without adjacency nothing is lost and nothing is misdirected.
        let (m, regions) = evaluate(&scored(&[]));
        assert_eq!(
            (m.adjacent, m.adjacent_rook, m.orientation, m.misdirected),
            (1.0, 1.0, 0.0, 0.0)
        );
        assert_eq!(
            (regions[0].neighbours_kept, regions[0].orientation_error),
            (1.0, 0.0)
        );
        // The cells touch only at a corner: the union's largest part is one square, not the
        // 2:1 rectangle of the outline.
        assert!(m.shape < 0.99, "{}", m.shape);
    }

    /// An irregular heptagon, counter-clockwise, not closed.
    fn heptagon() -> Vec<Coord<f64>> {
        [
            (0.0, 0.0),
            (4.0, -1.0),
            (6.0, 2.0),
            (5.0, 5.0),
            (3.0, 3.5),
            (1.0, 6.0),
            (-1.0, 3.0),
        ]
        .iter()
        .map(|&(x, y)| Coord { x, y })
        .collect()
    }

    fn ring(points: &[Coord<f64>]) -> LineString<f64> {
        let mut ring = LineString::from(points.to_vec());
        ring.close();
        ring
    }

    #[test]
    fn shape_descriptors_ignore_similarity_transforms_start_and_direction() {
        let original = descriptor(&ring(&heptagon())).unwrap();
        assert_eq!(original.len(), 2 * HARMONICS);
        assert!(
            (original[0] - 1.0).abs() < 1e-12,
            "harmonic 1 divided by itself"
        );
        let (sin, cos) = 33f64.to_radians().sin_cos();
        let mut moved: Vec<Coord<f64>> = heptagon()
            .iter()
            .map(|p| Coord {
                x: 3.7 * (cos * p.x - sin * p.y) + 100.0,
                y: 3.7 * (sin * p.x + cos * p.y) - 50.0,
            })
            .collect();
        moved.rotate_left(3);
        let transformed = descriptor(&ring(&moved)).unwrap();
        let s = similarity(&original, &transformed);
        assert!(s > 0.999, "{s}");
        moved.reverse();
        let reversed = descriptor(&ring(&moved)).unwrap();
        assert!(similarity(&original, &reversed) > 0.999);
        assert!((similarity(&original, &original) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn a_square_and_a_long_rectangle_differ() {
        let rectangle = |w: f64| {
            descriptor(&ring(&[
                Coord { x: 0.0, y: 0.0 },
                Coord { x: w, y: 0.0 },
                Coord { x: w, y: 1.0 },
                Coord { x: 0.0, y: 1.0 },
            ]))
            .unwrap()
        };
        let square = rectangle(1.0);
        let near = similarity(&square, &rectangle(1.2));
        let far = similarity(&square, &rectangle(10.0));
        assert!(far < 0.8, "square vs 10:1: {far}");
        assert!(near > far && near < 1.0, "1.2:1 {near}, 10:1 {far}");
        assert!(similarity(&square, &descriptor(&ring(&heptagon())).unwrap()) < 0.95);
    }

    #[test]
    fn degenerate_rings_have_no_descriptor() {
        let point = Coord { x: 1.0, y: 1.0 };
        assert!(descriptor(&ring(&[point, point, point])).is_none());
    }

    fn ring_of(cells: &[(i32, i32)]) -> Polygon<f64> {
        let ring = trace_outer(&largest_part(cells));
        Polygon::new(
            ring.iter()
                .map(|&(x, y)| Coord {
                    x: f64::from(x),
                    y: f64::from(y),
                })
                .collect(),
            vec![],
        )
    }

    #[test]
    fn the_largest_part_ignores_corner_contacts_and_holes() {
        // A 2×2 block and a cell touching it at one corner only.
        let polygon = ring_of(&[(5, 5), (0, 0), (1, 0), (0, 1), (1, 1), (2, 2)]);
        assert_eq!(polygon.signed_area(), 4.0);
        assert_eq!(polygon.exterior().0.len(), 9, "8 unit edges, closed");
        // A 3×3 ring of cells around an empty one: the outer ring encloses all 9.
        let frame: Vec<(i32, i32)> = (0..9).filter(|&i| i != 4).map(|i| (i % 3, i / 3)).collect();
        assert_eq!(ring_of(&frame).signed_area(), 9.0);
    }

    #[test]
    fn a_part_touching_itself_at_a_corner_gives_a_simple_ring() {
        // X X X
        // X . X
        // . X X   (the empty middle meets the outside at one corner: a hole, as in a union)
        let cells = [(0, 0), (1, 0), (2, 0), (0, 1), (2, 1), (1, 2), (2, 2)];
        let polygon = ring_of(&cells);
        let corners = &polygon.exterior().0;
        let distinct: HashSet<(i64, i64)> =
            corners.iter().map(|c| (c.x as i64, c.y as i64)).collect();
        assert_eq!(distinct.len(), corners.len() - 1, "no corner visited twice");
        assert_eq!(
            polygon.signed_area(),
            8.0,
            "counter-clockwise, the pocket inside"
        );
    }

    #[test]
    fn the_cell_ring_is_in_map_units() {
        let cells: Vec<(i32, i32)> = (0..10_000).map(|i| (i % 100, i / 100)).collect();
        let centres: Vec<Coord<f64>> = cells
            .iter()
            .map(|&(c, r)| Coord {
                x: 1000.0 + 2.0 * f64::from(c) + 1.0,
                y: 500.0 - 2.0 * f64::from(r) - 1.0,
            })
            .collect();
        let outline = MultiPolygon(vec![]);
        let scored = Scored {
            centroids: &centres,
            moved: &centres,
            cells: &cells,
            centres: &centres,
            cell_size: 2.0,
            unit: 2.0,
            adjacency: &[],
            outline: &outline,
        };
        let ring = cell_ring(&scored).unwrap();
        let polygon = Polygon::new(ring, vec![]);
        assert_eq!(polygon.signed_area(), 40_000.0);
        let bounds = geo::BoundingRect::bounding_rect(&polygon).unwrap();
        assert_eq!((bounds.min().x, bounds.max().y), (1000.0, 500.0));
        assert_eq!((bounds.max().x, bounds.min().y), (1200.0, 300.0));
        // No outline to compare with: the shape metric is 0, not NaN.
        assert_eq!(evaluate(&scored).0.shape, 0.0);
    }
}
