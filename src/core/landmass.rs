//! Step 4a′ (method.md §6, landmass budgets): each connected part of the moved outline (a
//! continent, an island group) that holds k regions gets exactly k cells in its own
//! neighbourhood of the lattice, so a large empty landmass (Antarctica) cannot take the cells a
//! crowded one (Europe) needs, and no region crosses an ocean.
//!
//! Cells are handed out best score first over all parts together, each cell to the part that
//! covers it best, until every part has its k; a part whose outline covers fewer than k cells
//! (a small landmass of many regions, a tiny island) then takes the free positions nearest to its
//! outline. The same rule, with `ratio`·k cells per part, gives the refinement its pool of free
//! cells, each tagged with its part: a region only ever moves within its own landmass.

use super::geometry::RingIndex;
use super::grid::{best_first, Lattice, LatticeCell};
use super::outline::{coords_of, rings_of};
use geo::{BoundingRect, Coord, MultiPolygon};
use std::collections::HashSet;

/// The cells the layout may use, tagged with their part: the first `demands.iter().sum()` are
/// the cells to assign (each part's k), the rest the refinement's pool.
pub struct Selection {
    pub cells: Vec<LatticeCell>,
    pub assigned: usize,
}

/// Selects cells on `lattice` (its frame: size and origin) for the moved outline's `parts` (one
/// multipolygon per part), part `p` holding `demands[p]` regions; `ratio` ≥ 1 sizes the pool.
pub fn select(
    lattice: &Lattice,
    parts: &[MultiPolygon<f64>],
    demands: &[usize],
    ratio: f64,
) -> Selection {
    let scored: Vec<LatticeCell> = {
        let mut all: Vec<LatticeCell> = (parts.iter().enumerate())
            .flat_map(|(p, polygons)| lattice.scores(polygons, p))
            .collect();
        // Best first; a position two parts cover goes to the one covering it best, then to the
        // lower part index, so that the order is fixed.
        all.sort_by(|a, b| best_first(a, b).then(a.part.cmp(&b.part)));
        all
    };
    let mut taken: HashSet<(i32, i32)> = HashSet::new();
    let assigned = pick(lattice, parts, &scored, demands, &mut taken);
    let extra: Vec<usize> = demands
        .iter()
        // Less a hair, so that 1.3 × 10 (13.000000000000002 in binary) asks for 3 more, not 4.
        .map(|&k| ((ratio - 1.0) * k as f64 - 1e-9).ceil().max(0.0) as usize)
        .collect();
    let pool = pick(lattice, parts, &scored, &extra, &mut taken);
    let count = assigned.len();
    Selection {
        cells: assigned.into_iter().chain(pool).collect(),
        assigned: count,
    }
}

/// Hands out `wanted[p]` more cells to each part `p`, free ones only: best scored first, then,
/// for parts still short, the free positions nearest their outline.
fn pick(
    lattice: &Lattice,
    parts: &[MultiPolygon<f64>],
    scored: &[LatticeCell],
    wanted: &[usize],
    taken: &mut HashSet<(i32, i32)>,
) -> Vec<LatticeCell> {
    let mut missing = wanted.to_vec();
    let mut chosen = Vec::with_capacity(wanted.iter().sum());
    for cell in scored {
        if missing[cell.part] > 0 && taken.insert((cell.col, cell.row)) {
            missing[cell.part] -= 1;
            chosen.push(*cell);
        }
    }
    let indexes: Vec<RingIndex> = parts
        .iter()
        .map(|p| RingIndex::new(&coords_of(&rings_of(p))))
        .collect();
    for (part, &short) in missing.iter().enumerate() {
        if short > 0 {
            let others: Vec<&RingIndex> = (indexes.iter().enumerate())
                .filter(|&(q, _)| q != part)
                .map(|(_, index)| index)
                .collect();
            chosen.extend(nearest_free(
                lattice,
                (&parts[part], &indexes[part]),
                &others,
                part,
                short,
                taken,
            ));
        }
    }
    chosen
}

/// Distance from `p` to the outline `index` describes (0 inside it).
fn distance_to(index: &RingIndex, p: Coord<f64>) -> f64 {
    if index.contains(p) {
        0.0
    } else {
        index.distance(p, |_| false)
    }
}

/// The `count` free positions whose centres lie nearest to `outline` (ties by row, then
/// column), marked as taken, with score 0; positions nearer one of the `others` outlines than
/// to this one come only after all that are not, so that a small landmass grows away from its
/// neighbours rather than towards them. Searched in squares of growing size around the
/// outline's bounding box, so the work follows the positions handed out.
fn nearest_free(
    lattice: &Lattice,
    (outline, index): (&MultiPolygon<f64>, &RingIndex),
    others: &[&RingIndex],
    part: usize,
    count: usize,
    taken: &mut HashSet<(i32, i32)>,
) -> Vec<LatticeCell> {
    let Some(bounds) = outline.bounding_rect() else {
        return Vec::new();
    };
    let position = |c: Coord<f64>| {
        (
            ((c.x - lattice.origin.x) / lattice.cell_size).floor() as i32,
            ((lattice.origin.y - c.y) / lattice.cell_size).floor() as i32,
        )
    };
    let (low, high) = (
        position(Coord {
            x: bounds.min().x,
            y: bounds.max().y,
        }),
        position(Coord {
            x: bounds.max().x,
            y: bounds.min().y,
        }),
    );
    // Wide enough to hold `count` free positions beyond the box even if none inside is free.
    let mut margin = (count as f64).sqrt().ceil() as i32 + 1;
    loop {
        let mut free: Vec<(bool, f64, i32, i32)> = Vec::new();
        for row in low.1 - margin..=high.1 + margin {
            for col in low.0 - margin..=high.0 + margin {
                if !taken.contains(&(col, row)) {
                    let centre = lattice.centre(col, row);
                    let own = distance_to(index, centre);
                    let elsewhere = others.iter().any(|o| distance_to(o, centre) < own);
                    free.push((elsewhere, own, row, col));
                }
            }
        }
        // A position farther than the margin could be beaten by one outside the searched
        // square: take only those the square settles.
        let settled = f64::from(margin) * lattice.cell_size;
        free.retain(|f| f.1 <= settled);
        free.sort_by(|a, b| {
            (a.0.cmp(&b.0))
                .then(a.1.total_cmp(&b.1))
                .then(a.2.cmp(&b.2))
                .then(a.3.cmp(&b.3))
        });
        // Positions nearer another landmass are settled only once the square holds enough
        // positions that are not: otherwise a wider square may offer some.
        let own_side = free.iter().filter(|f| !f.0).count();
        if own_side >= count || (free.len() >= count && margin > 4 * (count as i32 + 1)) {
            return free[..count]
                .iter()
                .map(|&(_, _, row, col)| {
                    taken.insert((col, row));
                    LatticeCell {
                        col,
                        row,
                        score: 0.0,
                        part,
                    }
                })
                .collect();
        }
        margin *= 2;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::grid::frame;
    use geo::{LineString, Polygon};

    fn rectangle(x0: f64, y0: f64, x1: f64, y1: f64) -> MultiPolygon<f64> {
        MultiPolygon(vec![Polygon::new(
            LineString::from(vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]),
            vec![],
        )])
    }

    #[test]
    fn each_part_gets_exactly_its_regions_cells_near_itself() {
        // A large empty part holding one region and a small crowded one holding nine: the
        // small one must not lose its cells to the large one.
        let big = rectangle(0.0, 0.0, 8.0, 8.0);
        let small = rectangle(20.0, 0.0, 22.0, 2.0);
        let all = MultiPolygon(big.0.iter().chain(&small.0).cloned().collect());
        let lattice = frame(&all, 10, [0.0, 0.0]);
        let selection = select(&lattice, &[big.clone(), small.clone()], &[1, 9], 1.0);
        assert_eq!(selection.assigned, 10);
        assert_eq!(selection.cells.len(), 10);
        let of = |p: usize| selection.cells.iter().filter(|c| c.part == p).count();
        assert_eq!((of(0), of(1)), (1, 9));
        let distinct: HashSet<(i32, i32)> =
            selection.cells.iter().map(|c| (c.col, c.row)).collect();
        assert_eq!(distinct.len(), 10);
        // The small part's cells lie around it, not over the big one.
        for c in selection.cells.iter().filter(|c| c.part == 1) {
            let centre = lattice.centre(c.col, c.row);
            assert!(centre.x > 14.0, "{c:?} at {centre:?}");
        }
    }

    #[test]
    fn the_pool_adds_free_cells_of_each_part() {
        let land = rectangle(0.0, 0.0, 4.0, 4.0);
        let lattice = frame(&land, 16, [0.0, 0.0]);
        let selection = select(&lattice, &[land], &[10], 1.3);
        assert_eq!(selection.assigned, 10);
        assert_eq!(selection.cells.len(), 13);
        let distinct: HashSet<(i32, i32)> =
            selection.cells.iter().map(|c| (c.col, c.row)).collect();
        assert_eq!(distinct.len(), 13);
    }
}
