//! Step 4a′, for a landmass thinner than a cell (method.md §6): its cells follow the whole
//! landmass, drawn smaller and thicker, rather than part of it.
//!
//! A landmass gets as many cells as it has regions, best scored first. Where its outline is
//! thinner than a cell but long (a ring of regions round a lagoon, a chain of islets joined by
//! a causeway), the outline offers more cells along it than its regions need, and the best of
//! them make an arc over part of it: a ring of 300 regions 0.7 cells wide took half the ring,
//! and the regions of the other half lay 31 cells from their own on average. The Snake cannot
//! draw such a landmass in: the ring would have to shrink by dozens of cells, and each step
//! moves a node by a tenth of a cell at most.
//!
//! Such a landmass is drawn again for its cells alone: scaled about its area centroid and
//! widened by a little over half a cell, at the largest scale whose figure holds no more cells
//! than its regions. Its regions' moved centroids are scaled with it, so that each is assigned
//! among the cells where its stretch of the landmass now lies. The layout on the redrawn
//! landmass is kept only if it puts the regions much nearer home ([`GAIN`]): a strip's plain
//! cells make a shorter stretch of it, which the §8 fit scales back, and the thicker figure
//! would only turn its neighbours. A Snake run's first layout decides for the run's other
//! shifts, which share its outline and cell size. Landmasses whose cells reach their regions
//! are never drawn again.

use super::grid::{Lattice, LatticeCell};
use geo::{Area, Buffer, Centroid, Coord, MapCoords, MultiPolygon};
use rustc_hash::FxHashSet;

/// How far, in lattice steps, a region's moved centroid may lie from its landmass's nearest cell
/// and still be within reach of them.
const REACH: i32 = 3;

/// The share of a landmass's regions beyond reach of its cells from which the landmass is drawn
/// again. In every square layout of the shared layers, the generated ones and Highcharts' 210
/// maps, it is passed by rings and strips thinner than a cell (a quarter to half their regions),
/// Alaska in Highcharts' US counties (which [`ROOM`] leaves out) and a 3-region landmass of the
/// Bahamas; only the rings' redrawn layouts are kept ([`GAIN`]).
const UNREACHED_SHARE: f64 = 0.25;

/// The most room, in its regions' cells, a thin landmass's outline holds: a ring or a strip
/// alone on its layer holds exactly its cells. One that holds far more (Alaska in Highcharts' US
/// counties: 31 times its 27 regions' cells) is a large sparse landmass, whose budget takes a
/// compact block of it; drawing it again cost that layer a sixth of its time, and its layout
/// was not kept.
const ROOM: f64 = 2.0;

/// How much nearer home a layout on the redrawn landmass must put the regions (§8's C_location)
/// to be kept: the redrawn figure is thicker than the landmass, which turns its neighbours.
/// A strip 0.7 cells wide, whose plain cells make a shorter stretch of it, gains 0.63–0.65
/// (40 and 1,000 regions) at 4–7° of orientation; a ring, whose plain cells make an arc over
/// half of it, 0.04.
pub(super) const GAIN: f64 = 0.5;

/// How far, in cells, the figure is widened on each side: a band at least 1.2 cells wide holds
/// an edge-connected chain of cell centres at any slant. Half a cell left the ring of 300 open
/// at its diagonals; 0.71 made stretches two cells wide, which turned neighbours (ring of 300:
/// C_orientation 35.6° against 38.6°; of 3,000: 31.5° against 46.7°).
const WIDENING: f64 = 0.6;

/// Bisection steps for the scale: 2⁻¹² of the landmass's size, under a cell on any layer whose
/// landmass spans fewer than 4,096 cells.
const SCALE_STEPS: usize = 12;

/// A thin landmass drawn again: its figure for the cells, and how its regions' moved centroids
/// move with it.
pub struct Redrawn {
    /// Per part, the figure its cells are chosen on: the part itself unless it was thin.
    pub parts: Vec<MultiPolygon<f64>>,
    /// Per region, its moved centroid, scaled with its part.
    pub points: Vec<Coord<f64>>,
}

/// The parts of `parts` that `assigned` (the cells chosen for them, tagged with their part)
/// leaves thin, drawn again; `None` when none is. `points` are the regions' moved centroids,
/// `part_of` their parts.
pub fn redrawn(
    lattice: &Lattice,
    assigned: &[LatticeCell],
    parts: &[MultiPolygon<f64>],
    points: &[Coord<f64>],
    part_of: &[usize],
) -> Option<Redrawn> {
    let mut regions = vec![0usize; parts.len()];
    for &p in part_of {
        regions[p] += 1;
    }
    let thin = thin_parts(lattice, assigned, parts, &regions, points, part_of);
    if !thin.contains(&true) {
        return None;
    }
    let mut redrawn = Redrawn {
        parts: parts.to_vec(),
        points: points.to_vec(),
    };
    let mut drawn_in = false;
    for (p, part) in parts.iter().enumerate().filter(|&(p, _)| thin[p]) {
        let Some((figure, centre, scale)) = smaller_and_thicker(part, regions[p], lattice) else {
            continue;
        };
        redrawn.parts[p] = figure;
        for (point, _) in (redrawn.points.iter_mut().zip(part_of)).filter(|(_, &q)| q == p) {
            *point = centre + (*point - centre) * scale;
        }
        drawn_in = true;
    }
    drawn_in.then_some(redrawn)
}

/// Per part, whether it is thin: its outline holds no more than [`ROOM`] times its regions'
/// cells, every cell it took came from its own outline (it offered more than the part needs; a
/// landmass smaller than its cells takes free cells beside it instead, and a pinned cell is the
/// user's, not the outline's),
/// and yet more than [`UNREACHED_SHARE`] of its regions have none of them within [`REACH`]
/// steps of their moved centroid.
fn thin_parts(
    lattice: &Lattice,
    assigned: &[LatticeCell],
    figures: &[MultiPolygon<f64>],
    regions: &[usize],
    points: &[Coord<f64>],
    part_of: &[usize],
) -> Vec<bool> {
    let parts = figures.len();
    let mut offered = vec![true; parts];
    for cell in assigned {
        offered[cell.part] &= cell.score > 0.0;
    }
    let held: FxHashSet<((i32, i32), usize)> = (assigned.iter())
        .map(|c| ((c.col, c.row), c.part))
        .collect();
    let tiling = lattice.tiling;
    let mut unreached = vec![0usize; parts];
    for (&point, &part) in points.iter().zip(part_of) {
        let at = lattice.position_of(point);
        // The square round `at` holds every position within reach, `at` among them.
        let reached = (-REACH..=REACH)
            .flat_map(|dc| (-REACH..=REACH).map(move |dr| (at.0 + dc, at.1 + dr)))
            .filter(|&q| tiling.distance(at, q) <= REACH)
            .any(|q| held.contains(&(q, part)));
        if !reached {
            unreached[part] += 1;
        }
    }
    let cell_area = lattice.cell_size * lattice.cell_size;
    (0..parts)
        .map(|p| {
            offered[p]
                && unreached[p] as f64 > UNREACHED_SHARE * regions[p] as f64
                && figures[p].unsigned_area() <= ROOM * regions[p] as f64 * cell_area
        })
        .collect()
}

/// `part` scaled about its area centroid and widened by [`WIDENING`] cells, at the largest scale at
/// which its area is at most `cells` cells of `lattice`: the figure, the centre and the scale.
/// `None` when even the part itself, widened, holds no more (nothing to draw in).
fn smaller_and_thicker(
    part: &MultiPolygon<f64>,
    cells: usize,
    lattice: &Lattice,
) -> Option<(MultiPolygon<f64>, Coord<f64>, f64)> {
    let centre = part.centroid()?.0;
    let room = cells as f64 * lattice.cell_size * lattice.cell_size;
    let figure = |scale: f64| {
        part.map_coords(|c| centre + (c - centre) * scale)
            .buffer(WIDENING * lattice.cell_size)
    };
    let whole = figure(1.0);
    if whole.unsigned_area() <= room {
        return None;
    }
    // The widened figure's area grows with the scale, from a half-cell disc's (under a cell).
    let (mut fits, mut too_big) = ((0.0, None), (1.0, whole));
    for _ in 0..SCALE_STEPS {
        let scale = (fits.0 + too_big.0) / 2.0;
        let drawn = figure(scale);
        if drawn.unsigned_area() <= room {
            fits = (scale, Some(drawn));
        } else {
            too_big = (scale, drawn);
        }
    }
    let (scale, drawn) = fits;
    Some((drawn?, centre, scale))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::grid::frame;
    use crate::core::tiling::Tiling;
    use geo::{LineString, Polygon};

    /// A ring of `count` unit cells' area, `width` cells wide, round the origin, and one point
    /// per region evenly round its middle.
    fn ring(count: usize, width: f64) -> (MultiPolygon<f64>, Vec<Coord<f64>>) {
        let radius = count as f64 / width / std::f64::consts::TAU;
        let circle = |r: f64| {
            let steps = 720;
            LineString::from(
                (0..=steps)
                    .map(|k| {
                        let a = std::f64::consts::TAU * (k % steps) as f64 / steps as f64;
                        (r * a.cos(), r * a.sin())
                    })
                    .collect::<Vec<_>>(),
            )
        };
        let outline = MultiPolygon(vec![Polygon::new(
            circle(radius + width / 2.0),
            vec![circle(radius - width / 2.0)],
        )]);
        let points = (0..count)
            .map(|k| {
                let a = std::f64::consts::TAU * (k as f64 + 0.5) / count as f64;
                Coord {
                    x: radius * a.cos(),
                    y: radius * a.sin(),
                }
            })
            .collect();
        (outline, points)
    }

    #[test]
    fn a_ring_whose_cells_make_an_arc_is_thin_and_one_whose_cells_go_round_is_not() {
        let (outline, points) = ring(300, 0.7);
        let lattice = frame(&outline, 300, [0.0, 0.0], Tiling::Square);
        let offered = lattice.scores(&outline, 0);
        let outlines = std::slice::from_ref(&outline);
        // Whether the one part is thin with these cells and these regions' moved centroids.
        let thin = |cells: &[LatticeCell], points: &[Coord<f64>]| {
            let part_of = vec![0; points.len()];
            thin_parts(&lattice, cells, outlines, &[points.len()], points, &part_of)
        };
        // The plain selection's failure: cells only over the northern half.
        let north: Vec<LatticeCell> = (offered.iter())
            .filter(|c| lattice.centre(c.col, c.row).y > 0.0)
            .copied()
            .collect();
        assert_eq!(thin(&north, &points), [true]);
        // Cells all round it (more than its regions, which does not matter here).
        assert_eq!(thin(&offered, &points), [false]);
        // A third of the regions on the same ring: its outline holds three times their cells,
        // a sparse landmass rather than a thin one.
        let sparse: Vec<Coord<f64>> = points.iter().step_by(3).copied().collect();
        assert_eq!(thin(&north, &sparse), [false]);
        // Cells that are not the outline's own (a landmass smaller than its cells took free
        // positions beside it) are never a thin landmass's.
        let beside: Vec<LatticeCell> = (north.iter())
            .map(|c| LatticeCell { score: 0.0, ..*c })
            .collect();
        assert_eq!(thin(&beside, &points), [false]);
    }

    #[test]
    fn a_thin_ring_is_drawn_smaller_and_thicker_with_room_for_its_regions() {
        let (outline, points) = ring(300, 0.7);
        let lattice = frame(&outline, 300, [0.0, 0.0], Tiling::Square);
        let north: Vec<LatticeCell> = (lattice.scores(&outline, 0).into_iter())
            .filter(|c| lattice.centre(c.col, c.row).y > 0.0)
            .collect();
        let part_of = vec![0; points.len()];
        let redrawn = redrawn(
            &lattice,
            &north,
            std::slice::from_ref(&outline),
            &points,
            &part_of,
        )
        .expect("the ring is thin");
        let figure = &redrawn.parts[0];
        let room = 300.0 * lattice.cell_size * lattice.cell_size;
        // Within a bisection step of its regions' cells, and still round its lake.
        let area = figure.unsigned_area();
        assert!(area <= room && area > 0.98 * room, "{area} for {room}");
        assert_eq!(figure.0.len(), 1);
        assert_eq!(figure.0[0].interiors().len(), 1);
        // The points moved in with it, towards the centre, keeping their directions: a ring
        // 0.7 cells wide widened to 1.2 + 0.7·s holds its cells at about s = 0.45.
        let scale = redrawn.points[0].x.hypot(redrawn.points[0].y) / points[0].x.hypot(points[0].y);
        assert!((0.35..0.55).contains(&scale), "{scale}");
        for (moved, &was) in redrawn.points.iter().zip(&points) {
            let turned = (moved.y.atan2(moved.x) - was.y.atan2(was.x)).abs();
            assert!(turned < 1e-9, "{moved:?} from {was:?}");
        }
    }

    #[test]
    fn a_landmass_whose_cells_reach_its_regions_is_not_drawn_again() {
        // A square of 10 × 10 cells with a region in each.
        let outline = MultiPolygon(vec![Polygon::new(
            LineString::from(vec![
                (0.0, 0.0),
                (10.0, 0.0),
                (10.0, 10.0),
                (0.0, 10.0),
                (0.0, 0.0),
            ]),
            vec![],
        )]);
        let points: Vec<Coord<f64>> = (0..100)
            .map(|k| Coord {
                x: (k % 10) as f64 + 0.5,
                y: (k / 10) as f64 + 0.5,
            })
            .collect();
        let lattice = frame(&outline, 100, [0.0, 0.0], Tiling::Square);
        let mut cells = lattice.scores(&outline, 0);
        cells.truncate(100);
        let part_of = vec![0; 100];
        assert!(redrawn(&lattice, &cells, &[outline], &points, &part_of).is_none());
    }
}
