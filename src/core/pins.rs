//! Pinned cells (method.md §10): regions given a cell keep it, and the rest are laid out around
//! them, numbered in the pins' own frame.
//!
//! A pin is an offset column and row, as the grid layer writes them (rows from the top; for
//! hexagons the odd rows (pointy) or columns (flat) sit half a cell further, the convention of
//! [`Tiling::offset_coordinates`]). The lattice is placed on the moved outline so that each
//! pinned region's cell lies as near its moved centroid as one scale and one shift allow
//! ([`place`]); the pinned cells are then forced, and every other region is assigned among the
//! cells the outline offers, which pins take out of the landmass budgets.
//!
//! [`from_edits`] turns a grid layer that a user edited by hand into pins: the cells moved away
//! from the position their numbers name, at the nearest lattice position.

use super::grid::{self, best_first, Lattice, LatticeCell};
use super::groups::{pieces_of, Blocks};
use super::metrics;
use super::tiling::{Position, Tiling};
use super::{Error, Region};
use geo::{Area, Coord, MultiPolygon};
use rustc_hash::{FxHashMap, FxHashSet};
use std::collections::HashMap;

/// A pin from its column and row as a layer or a caller gives them: `None` or NaN is no value,
/// and a region with neither is free. Refused: only one of the two, a value that is not a whole
/// number, one beyond ±2³⁰ (no lattice is that large, and neighbours' numbers must not
/// overflow).
pub fn pin_of(col: Option<f64>, row: Option<f64>) -> Result<Option<Position>, String> {
    let given = |v: Option<f64>| v.filter(|v| !v.is_nan());
    let whole = |what: &str, v: f64| {
        if v.fract() != 0.0 || !v.is_finite() {
            Err(format!("the pin {what} {v} is not a whole number"))
        } else if v.abs() > f64::from(1 << 30) {
            Err(format!(
                "the pin {what} {v} is out of range (at most ±2^30)"
            ))
        } else {
            Ok(v as i32)
        }
    };
    match (given(col), given(row)) {
        (None, None) => Ok(None),
        (Some(c), Some(r)) => Ok(Some((whole("column", c)?, whole("row", r)?))),
        (Some(_), None) => Err("the pin column is set but the pin row is not".into()),
        (None, Some(_)) => Err("the pin row is set but the pin column is not".into()),
    }
}

/// A fitted cell side more than this factor from the outline's own S' = sqrt(area / M) is not
/// trusted (pins far from where the Snake moved their regions): the lattice then keeps S' and
/// only its shift is fitted.
const SCALE_RANGE: f64 = 2.0;

/// How many columns or rows, per region, the pins may span: a layout of M cells in one row
/// spans M, and pins spread much wider would stretch the bent outline over a lattice of
/// millions of cells for nothing.
const SPAN_PER_REGION: i64 = 2;

/// The pinned regions (indices in the order of `order`, the method's geometric order, ascending)
/// with their pins as lattice positions, after refusing by name two regions on one cell, pins spanning more than
/// [`SPAN_PER_REGION`] columns or rows per region and, with `blocks` (groups), pins that cannot
/// lie in one block of their group's cells or, with `gap`, pins of two groups that touch.
pub fn positions(
    regions: &[Region],
    order: &[usize],
    tiling: Tiling,
    blocks: Option<&Blocks>,
    gap: bool,
) -> Result<Vec<(usize, Position)>, Error> {
    let id = |k: usize| regions[order[k]].id.as_str();
    let mut pinned: Vec<(usize, Position)> = (order.iter().enumerate())
        .filter_map(|(k, &i)| Some((k, tiling.from_offset_coordinates(regions[i].pin?))))
        .collect();
    // In the input order, so that the first clash the user's layer holds is the one named.
    pinned.sort_unstable_by_key(|&(k, _)| order[k]);
    let mut at: HashMap<Position, usize> = HashMap::new();
    for &(k, p) in &pinned {
        if let Some(&first) = at.get(&p) {
            let (col, row) = tiling.offset_coordinates(p);
            return Err(Error::input(
                Some(id(k)),
                format!(
                    "pinned to column {col}, row {row}, the cell feature {} is pinned to",
                    id(first)
                ),
            ));
        }
        at.insert(p, k);
    }
    let span = SPAN_PER_REGION * regions.len() as i64 + 2;
    for axis in [|p: Position| p.0, |p: Position| p.1] {
        let value = |k: usize| i64::from(axis(regions[order[k]].pin.unwrap_or_default()));
        let low = pinned.iter().map(|&(k, _)| value(k)).min().unwrap_or(0);
        if let Some(&(k, _)) = pinned.iter().find(|&&(k, _)| value(k) - low > span) {
            return Err(Error::input(
                Some(id(k)),
                format!(
                    "its pin lies {} cells from another's, more than a layout of {} regions \
                     spans ({span})",
                    value(k) - low,
                    regions.len()
                ),
            ));
        }
    }
    let Some(blocks) = blocks else {
        pinned.sort_unstable();
        return Ok(pinned);
    };
    let mut sizes = vec![0; blocks.count()];
    for &b in &blocks.of {
        sizes[b] += 1;
    }
    let size = |b: usize| sizes[b];
    for (n, &(a, pa)) in pinned.iter().enumerate() {
        for &(b, pb) in &pinned[n + 1..] {
            let (block_a, block_b) = (blocks.of[a], blocks.of[b]);
            // A block of k cells spans at most k − 1 steps between any two of its cells.
            if block_a == block_b && tiling.distance(pa, pb) >= size(block_a) {
                return Err(Error::input(
                    Some(id(b)),
                    format!(
                        "its pin is {} cells from that of feature {}, in the same group, whose \
                         block has only {} cells: the pins would split the group's block",
                        tiling.distance(pa, pb),
                        id(a),
                        size(block_a)
                    ),
                ));
            }
            let groups_differ = blocks.group[block_a] != blocks.group[block_b];
            if gap && groups_differ && tiling.touching(pa, pb) {
                return Err(Error::input(
                    Some(id(b)),
                    format!(
                        "its pin touches that of feature {}, of another group, and group_gap \
                         1 keeps groups a cell apart",
                        id(a)
                    ),
                ));
            }
        }
    }
    pinned.sort_unstable();
    Ok(pinned)
}

/// Rounds of [`place`]'s agreement between the cell side and the bent outline's area.
const PLACE_ROUNDS: usize = 8;

/// The lattice (without cells) for `wanted` cells on `outline`, placed by the `pinned` regions
/// (each a position and the region's moved centroid), and the [`Warp`] that bends the moved
/// network onto it so that the rest follows the pins.
///
/// The centre o of position (0, 0) and the cell side s minimise Σ |o + s·u_i − q_i|² over the
/// pins, u_i the pin's centre in cells from that of (0, 0) and q_i the region's moved
/// centroid. Bending the outline onto the pins changes its area, so s then takes the value at
/// which the bent outline holds `wanted` cells (a few rounds of s ← sqrt(area / wanted), o
/// refitted each time): a lattice finer than the outline would leave cells over and the
/// selection would drop them at one side. With fewer than two pins, or an s outside
/// [S'/2, 2·S'] (S' the unbent outline's own cell side, [`grid::frame`]), s stays S'.
pub fn place(
    outline: &MultiPolygon<f64>,
    wanted: usize,
    pinned: &[(Position, Coord<f64>)],
    tiling: Tiling,
) -> (Lattice, Warp) {
    let own = grid::frame(outline, wanted, [0.0, 0.0], tiling).cell_size;
    let units: Vec<Coord<f64>> = (pinned.iter())
        .map(|&(p, _)| unit(tiling).centre(p.0, p.1))
        .collect();
    let moved: Vec<Coord<f64>> = pinned.iter().map(|&(_, q)| q).collect();
    let trusted = |s: f64| s.is_finite() && s >= own / SCALE_RANGE && s <= own * SCALE_RANGE;
    let (fitted, _) = metrics::fit(&units, &moved);
    let n = units.len().max(1) as f64;
    let mean = |points: &[Coord<f64>]| {
        (points.iter()).fold(Coord { x: 0.0, y: 0.0 }, |acc, &p| acc + p) / n
    };
    let at = |size: f64| {
        let lattice = Lattice {
            cell_size: size,
            // The least-squares shift for this scale.
            origin: mean(&moved) - mean(&units) * size,
            ..unit(tiling)
        };
        let warp = Warp::new(
            (pinned.iter())
                .map(|&(p, q)| (q, lattice.centre(p.0, p.1)))
                .collect(),
        );
        (lattice, warp)
    };
    if !(pinned.len() > 1 && trusted(fitted)) {
        return at(own);
    }
    let mut placed = at(fitted);
    for _ in 0..PLACE_ROUNDS {
        let bent = geo::MapCoords::map_coords(outline, |c| placed.1.at(c));
        let size = (bent.unsigned_area() / wanted as f64).sqrt();
        if !trusted(size) {
            break;
        }
        let settled = (size - placed.0.cell_size).abs() <= 1e-3 * size;
        placed = at(size);
        if settled {
            break;
        }
    }
    placed
}

/// Joins each pinned cell that lies apart from the rest of its landmass's cells to them:
/// `cells` is a selection (the first `*assigned` to assign, the first `fixed` of them the
/// pinned ones, the rest the refinement's pool). A piece of a part's assigned cells that holds
/// a pinned cell and is not the part's largest gets the shortest lattice path to the largest
/// (through positions no other part holds); for each cell the path adds, the part gives up its
/// lowest-scored unpinned cell whose loss splits no piece, to the pool. The refinement cannot
/// join pieces (its moves keep the layout's topology), so the selection must.
pub fn bridge(cells: &mut Vec<LatticeCell>, fixed: usize, assigned: usize, tiling: Tiling) {
    let parts: Vec<usize> = {
        let mut parts: Vec<usize> = cells[..fixed].iter().map(|c| c.part).collect();
        parts.sort_unstable();
        parts.dedup();
        parts
    };
    for part in parts {
        let position = |c: &LatticeCell| (c.col, c.row);
        let own = |cells: &[LatticeCell]| -> Vec<Position> {
            (cells[..assigned].iter())
                .filter(|c| c.part == part)
                .map(position)
                .collect()
        };
        let pinned: FxHashSet<Position> = (cells[..fixed].iter())
            .filter(|c| c.part == part)
            .map(position)
            .collect();
        // Each round joins one piece; a piece joined stays joined, so the rounds end.
        for _ in 0..pinned.len() {
            let pieces = pieces_of(tiling, &own(cells));
            let Some(apart) = pieces[1..]
                .iter()
                .find(|piece| piece.iter().any(|p| pinned.contains(p)))
            else {
                break;
            };
            let others: FxHashSet<Position> = (cells.iter())
                .filter(|c| c.part != part)
                .map(position)
                .collect();
            let main: FxHashSet<Position> = pieces[0].iter().copied().collect();
            let path = shortest_path(tiling, apart, &main, &others);
            for &p in &path {
                let pooled = (assigned..cells.len()).find(|&k| position(&cells[k]) == p);
                let cell = match pooled {
                    Some(k) => cells.remove(k),
                    None => LatticeCell {
                        col: p.0,
                        row: p.1,
                        score: 0.0,
                        part,
                    },
                };
                // The path's cell joins the assigned ones; the part's weakest cell leaves them.
                let Some(weakest) = weakest(cells, fixed, assigned, part, &path, tiling) else {
                    cells.insert(assigned, cell);
                    continue;
                };
                let given_up = std::mem::replace(&mut cells[weakest], cell);
                cells.insert(assigned, given_up);
            }
        }
    }
}

/// The positions between `from` and the nearest position of `to`, by lattice steps (ties by
/// row, then column), avoiding `blocked`; empty when none is reachable within the search.
fn shortest_path(
    tiling: Tiling,
    from: &[Position],
    to: &FxHashSet<Position>,
    blocked: &FxHashSet<Position>,
) -> Vec<Position> {
    let mut start: Vec<Position> = from.to_vec();
    start.sort_unstable_by_key(|&(c, r)| (r, c));
    let mut came: FxHashMap<Position, Option<Position>> =
        start.iter().map(|&p| (p, None)).collect();
    let mut frontier = std::collections::VecDeque::from(start);
    // A pin beyond this many steps of its landmass is not worth a path of cells.
    let reach = 4 * (to.len() + from.len());
    while let Some(p) = frontier.pop_front() {
        for &n in tiling.edge_neighbours(p).iter() {
            if came.contains_key(&n) || blocked.contains(&n) {
                continue;
            }
            if to.contains(&n) {
                let mut path = Vec::new();
                let mut at = Some(p);
                while let Some(q) = at.filter(|q| !from.contains(q)) {
                    path.push(q);
                    at = came[&q];
                }
                return path;
            }
            came.insert(n, Some(p));
            if came.len() > reach * reach {
                return Vec::new();
            }
            frontier.push_back(n);
        }
    }
    Vec::new()
}

/// The index of the lowest-scored unpinned assigned cell of `part`, off `path`, whose loss
/// splits none of the part's pieces (the one farthest down and right among equals).
fn weakest(
    cells: &[LatticeCell],
    fixed: usize,
    assigned: usize,
    part: usize,
    path: &[Position],
    tiling: Tiling,
) -> Option<usize> {
    let mut order: Vec<usize> = (fixed..assigned)
        .filter(|&k| cells[k].part == part && !path.contains(&(cells[k].col, cells[k].row)))
        .collect();
    order.sort_by(|&a, &b| best_first(&cells[b], &cells[a]));
    let positions: Vec<Position> = (cells[..assigned].iter())
        .filter(|c| c.part == part)
        .map(|c| (c.col, c.row))
        .chain(path.iter().copied())
        .collect();
    let pieces = pieces_of(tiling, &positions).len();
    order.into_iter().find(|&k| {
        let gone = (cells[k].col, cells[k].row);
        let rest: Vec<Position> = positions.iter().copied().filter(|&p| p != gone).collect();
        pieces_of(tiling, &rest).len() <= pieces
    })
}

/// A smooth displacement of the plane that takes each pinned region's moved centroid exactly onto
/// its cell's centre and every other point by the mean of the pins' displacements weighted by
/// the inverse fourth power of the distance (Shepard's interpolation), so that a region follows
/// the pins nearest it. On us_states with five pins from the NYT's layout, C_adjacent over ten
/// seeds: 0.882 on average with the fourth power, 0.856 with the square, 0.854 with the sixth.
/// After the least-squares [`place`] the displacements have mean zero, so far from every pin
/// the network stays where the Snake put it.
pub struct Warp {
    /// (from, displacement) per pin.
    pins: Vec<(Coord<f64>, Coord<f64>)>,
}

impl Warp {
    /// The warp taking each `from` onto its `to`.
    pub fn new(pairs: Vec<(Coord<f64>, Coord<f64>)>) -> Warp {
        Warp {
            pins: pairs
                .into_iter()
                .map(|(from, to)| (from, to - from))
                .collect(),
        }
    }

    /// Where `p` goes.
    pub fn at(&self, p: Coord<f64>) -> Coord<f64> {
        let (mut sum, mut weights) = (Coord { x: 0.0, y: 0.0 }, 0.0);
        for &(from, shift) in &self.pins {
            let d = p - from;
            let squared = d.x * d.x + d.y * d.y;
            if squared == 0.0 {
                return p + shift;
            }
            let w = 1.0 / (squared * squared);
            sum = sum + shift * w;
            weights += w;
        }
        if weights > 0.0 {
            p + sum / weights
        } else {
            p
        }
    }
}

/// The lattice of unit cells whose origin is at (0, 0): [`Lattice::centre`] on it gives a
/// position's centre in cells from the origin.
fn unit(tiling: Tiling) -> Lattice {
    Lattice {
        tiling,
        cell_size: 1.0,
        origin: Coord { x: 0.0, y: 0.0 },
        cells: Vec::new(),
    }
}

/// How far, in cells, a cell's centre may lie from the position its numbers name and still
/// count as where the layout put it (the re-layout issue's figure).
pub const MOVED_BEYOND: f64 = 0.25;

/// One cell of an edited grid layer: its region, the position its numbers name (the layer's
/// `grid_q`/`grid_r`, which for squares are `grid_col`/`grid_row`: axial coordinates are
/// the same whichever rows the layer shifted), its polygon's area centroid and area, and whether
/// the user ticked it to keep.
#[derive(Clone, Debug)]
pub struct EditedCell {
    pub id: String,
    pub position: Position,
    pub centre: Coord<f64>,
    pub area: f64,
    pub keep: bool,
}

/// The pin an edited cell gives its region: where it now lies (offset coordinates, as
/// [`Region::pin`] takes them), and whether the user moved it there (else it was ticked to
/// keep).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EditPin {
    pub pin: Position,
    pub moved: bool,
}

/// The pins an edited grid layer gives, per cell: the cells the user moved, each at the nearest
/// position of the lattice the unmoved cells lie on, and the cells ticked to keep, where they
/// are; `None` for the others, which are laid out again.
///
/// The lattice: its cell side from the cells' median area (every cell has area s²), its origin
/// the median over the cells of where each one's centre puts it (robust while fewer than half
/// the cells were moved); then scale and origin fitted by least squares to the cells within
/// [`MOVED_BEYOND`] of their positions, which are the unmoved ones. A cell farther than that is
/// moved. Refused by name: a cell without area or with a non-finite centre, and two cells on
/// one position (the moved ones at their new positions, the others at theirs).
pub fn from_edits(cells: &[EditedCell], tiling: Tiling) -> Result<Vec<Option<EditPin>>, Error> {
    for cell in cells {
        let finite = cell.centre.x.is_finite() && cell.centre.y.is_finite();
        if !(finite && cell.area.is_finite() && cell.area > 0.0) {
            return Err(Error::input(
                Some(&cell.id),
                "the edited cell has no area or no finite centre",
            ));
        }
    }
    if cells.is_empty() {
        return Ok(Vec::new());
    }
    let units: Vec<Coord<f64>> = (cells.iter())
        .map(|c| unit(tiling).centre(c.position.0, c.position.1))
        .collect();
    let median = |mut values: Vec<f64>| {
        values.sort_by(f64::total_cmp);
        values[values.len() / 2]
    };
    let mut size = median(cells.iter().map(|c| c.area.sqrt()).collect());
    let mut origin = Coord {
        x: median(
            (cells.iter().zip(&units))
                .map(|(c, u)| c.centre.x - u.x * size)
                .collect(),
        ),
        y: median(
            (cells.iter().zip(&units))
                .map(|(c, u)| c.centre.y - u.y * size)
                .collect(),
        ),
    };
    let off = |k: usize, size: f64, origin: Coord<f64>| {
        let d = cells[k].centre - (origin + units[k] * size);
        d.x.hypot(d.y) / size
    };
    let unmoved: Vec<usize> = (0..cells.len())
        .filter(|&k| off(k, size, origin) <= MOVED_BEYOND)
        .collect();
    if unmoved.len() > 1 {
        let from: Vec<Coord<f64>> = unmoved.iter().map(|&k| units[k]).collect();
        let onto: Vec<Coord<f64>> = unmoved.iter().map(|&k| cells[k].centre).collect();
        let (s, o) = metrics::fit(&from, &onto);
        if s.is_finite() && s > 0.0 {
            (size, origin) = (s, o);
        }
    }
    let lattice = Lattice {
        cell_size: size,
        origin,
        ..unit(tiling)
    };
    let mut pins = Vec::with_capacity(cells.len());
    let mut at: HashMap<Position, usize> = HashMap::new();
    for (k, cell) in cells.iter().enumerate() {
        let moved = off(k, size, origin) > MOVED_BEYOND;
        let position = if moved {
            lattice.position_of(cell.centre)
        } else {
            cell.position
        };
        if let Some(&first) = at.get(&position) {
            let (col, row) = tiling.offset_coordinates(position);
            return Err(Error::input(
                Some(&cell.id),
                format!(
                    "the edited cell lies on column {col}, row {row}, where the cell of feature \
                     {} lies",
                    cells[first].id
                ),
            ));
        }
        at.insert(position, k);
        pins.push((moved || cell.keep).then(|| EditPin {
            pin: tiling.offset_coordinates(position),
            moved,
        }));
    }
    Ok(pins)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::params::HexOrientation;
    use geo::{polygon, MultiPolygon};

    fn square_outline(side: f64) -> MultiPolygon<f64> {
        MultiPolygon(vec![polygon![
            (x: 0.0, y: 0.0),
            (x: side, y: 0.0),
            (x: side, y: side),
            (x: 0.0, y: side),
        ]])
    }

    #[test]
    fn the_lattice_is_fitted_to_the_pins() {
        // Pins (0, 0) and (3, 0) at centroids 6 apart: a cell side of 2, by hand; the centre of
        // (0, 0) at (1, 9), so the top-left corner of its square at (0, 10).
        let outline = square_outline(10.0);
        let pinned = [
            ((0, 0), Coord { x: 1.0, y: 9.0 }),
            ((3, 0), Coord { x: 7.0, y: 9.0 }),
        ];
        let (lattice, _) = place(&outline, 25, &pinned, Tiling::Square);
        assert!((lattice.cell_size - 2.0).abs() < 1e-12);
        let centre = lattice.centre(3, 0);
        assert!((centre.x - 7.0).abs() < 1e-12 && (centre.y - 9.0).abs() < 1e-12);
    }

    #[test]
    fn one_pin_keeps_the_outlines_cell_side() {
        let outline = square_outline(10.0);
        let pinned = [((2, 1), Coord { x: 4.0, y: 4.0 })];
        let (lattice, _) = place(&outline, 4, &pinned, Tiling::Square);
        let own = grid::frame(&outline, 4, [0.0, 0.0], Tiling::Square).cell_size;
        assert!((lattice.cell_size - own).abs() < 1e-12);
        // The pinned position is the one under the centroid.
        assert_eq!(lattice.position_of(Coord { x: 4.0, y: 4.0 }), (2, 1));
    }

    #[test]
    fn hexagon_pins_use_the_offset_convention() {
        let tiling = Tiling::Hex(HexOrientation::Pointy);
        let outline = square_outline(10.0);
        // Offset (0, 1) is the odd row, half a cell right of (0, 0).
        let pinned = [
            ((0, 0), Coord { x: 1.0, y: 9.0 }),
            (
                tiling.from_offset_coordinates((0, 1)),
                Coord { x: 2.0, y: 7.5 },
            ),
        ];
        let (lattice, _) = place(&outline, 20, &pinned, tiling);
        let (a, b) = (
            lattice.centre(0, 0),
            lattice.centre(pinned[1].0 .0, pinned[1].0 .1),
        );
        assert!(b.x > a.x && b.y < a.y);
    }

    #[test]
    fn pins_are_whole_numbers_given_in_pairs() {
        assert_eq!(pin_of(Some(3.0), Some(-2.0)), Ok(Some((3, -2))));
        assert_eq!(pin_of(None, Some(f64::NAN)), Ok(None));
        let half = pin_of(Some(2.5), Some(1.0)).unwrap_err();
        assert_eq!(half, "the pin column 2.5 is not a whole number");
        let one = pin_of(Some(1.0), None).unwrap_err();
        assert_eq!(one, "the pin column is set but the pin row is not");
        assert!(pin_of(Some(1.0), Some(1e12)).is_err());
        assert!(pin_of(Some(f64::INFINITY), Some(1.0)).is_err());
    }

    fn edited(id: &str, col: i32, row: i32, x: f64, y: f64) -> EditedCell {
        EditedCell {
            id: id.into(),
            position: (col, row),
            centre: Coord { x, y },
            area: 4.0,
            keep: false,
        }
    }

    /// A 3 × 3 block of cells of side 2, (col, row) centred at (2·col + 1, −2·row − 1).
    fn block() -> Vec<EditedCell> {
        (0..9)
            .map(|k| {
                let (col, row) = (k % 3, k / 3);
                let (x, y) = (f64::from(2 * col + 1), f64::from(-2 * row - 1));
                edited(&format!("r{k}"), col, row, x, y)
            })
            .collect()
    }

    #[test]
    fn a_moved_cell_is_pinned_at_the_nearest_position() {
        let mut cells = block();
        // r8 (2, 2) dragged to near (4, 1): centre (9.2, −2.9).
        cells[8].centre = Coord { x: 9.2, y: -2.9 };
        // r0 nudged by less than a quarter cell (0.4 of side 2 is 0.2 cell): not moved.
        cells[0].centre = Coord { x: 1.4, y: -1.0 };
        // r1 ticked to keep.
        cells[1].keep = true;
        let pins = from_edits(&cells, Tiling::Square).unwrap();
        let mut expected = vec![None; 9];
        expected[1] = Some(EditPin {
            pin: (1, 0),
            moved: false,
        });
        expected[8] = Some(EditPin {
            pin: (4, 1),
            moved: true,
        });
        assert_eq!(pins, expected);
    }

    #[test]
    fn two_cells_on_one_position_are_refused_by_name() {
        let mut cells = block();
        // r8 dragged onto r4's cell (1, 1).
        cells[8].centre = Coord { x: 3.1, y: -3.0 };
        let error = from_edits(&cells, Tiling::Square).unwrap_err();
        let text = error.to_string();
        assert!(text.contains("r8") && text.contains("r4"), "{text}");
    }
}
