//! Step 4a (method.md §6): a square lattice fitted to the moved outline, each cell scored by how
//! much of it the outline covers.
//!
//! The covered areas come from one exact scanline pass over the outline's segments (the
//! "cover and area" accumulation of anti-aliasing rasterisers), not from a polygon boolean per
//! cell. Work in lattice units, u to the right and v downwards, so that cell (col, row) is the
//! unit square [col, col+1] × [row, row+1]. For a closed ring, the area of a cell that lies
//! inside the ring is the integral over the cell's rows of the signed length of the edges to
//! the right of each point (Green's theorem). A segment piece inside one cell contributes
//! (mean u − col)·Δv to that cell and the full Δv to every cell on its left in the same row. So
//! each segment only touches the cells it passes through (the boundary cells); a right-to-left
//! running sum over each row gives every other cell's area, which is then exactly 0 or 1. The
//! centre test uses the same running sum on the winding number of the row's centre line.
//! Everything is linear in the number of boundary cells plus inside cells, independent of the
//! number of outline vertices per cell.

use super::params::HexOrientation;
use super::tiling::{Position, Tiling, HEX_SIDE, HEX_WIDTH};
use geo::{Area, BoundingRect, Coord, LineString, MultiPolygon, Polygon};
use rustc_hash::{FxHashMap, FxHashSet};

/// One lattice cell and its score (1 if its centre is inside the outline, plus the covered
/// share of its area), and the part of the outline (landmass) it is for. `col` and `row` are
/// the cell's [`Position`] in the tiling's coordinates (axial q and r for hexagons).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LatticeCell {
    pub col: i32,
    pub row: i32,
    pub score: f64,
    pub part: usize,
}

/// A lattice of cells of area `cell_size²`. Squares: column `col` spans x from
/// `origin.x + col·cell_size`, row `row` spans y downwards from `origin.y − row·cell_size`.
/// Hexagons: the centre of (q, r) lies [`Tiling::centre_offset`] cells from `origin`.
#[derive(Clone, Debug, PartialEq)]
pub struct Lattice {
    pub tiling: Tiling,
    pub cell_size: f64,
    /// Squares: the top-left corner of cell (0, 0); hexagons: its centre.
    pub origin: Coord<f64>,
    /// Every cell with a positive score, best first (score descending, then row, then column).
    pub cells: Vec<LatticeCell>,
}

impl Lattice {
    /// The centre of cell (`col`, `row`).
    pub fn centre(&self, col: i32, row: i32) -> Coord<f64> {
        match self.tiling {
            Tiling::Square => Coord {
                x: self.x_at(f64::from(col) + 0.5),
                y: self.y_at(f64::from(row) + 0.5),
            },
            Tiling::Hex(_) => self.origin + self.tiling.centre_offset((col, row)) * self.cell_size,
        }
    }

    /// The position whose cell holds `point` (the nearest centre).
    pub fn position_of(&self, point: Coord<f64>) -> Position {
        match self.tiling {
            Tiling::Square => (
                ((point.x - self.origin.x) / self.cell_size).floor() as i32,
                ((self.origin.y - point.y) / self.cell_size).floor() as i32,
            ),
            Tiling::Hex(_) => (self.tiling).position_at((point - self.origin) / self.cell_size),
        }
    }

    /// The polygon of cell (`col`, `row`), counter-clockwise. Each corner is computed from the
    /// lattice's own integer corner key (squares: from its lattice lines), so neighbouring cells
    /// share bit-identical corners and their union has no slivers.
    pub fn polygon(&self, col: i32, row: i32) -> Polygon<f64> {
        if self.tiling == Tiling::Square {
            return self.square(col, row);
        }
        let mut points: Vec<Coord<f64>> = (self.tiling.corners((col, row)).iter())
            .map(|&c| self.origin + self.tiling.corner_offset(c) * self.cell_size)
            .collect();
        points.push(points[0]);
        Polygon::new(LineString::from(points), vec![])
    }

    /// The square of cell (`col`, `row`), counter-clockwise from its bottom-left corner.
    fn square(&self, col: i32, row: i32) -> Polygon<f64> {
        let (x0, x1) = (self.x_at(f64::from(col)), self.x_at(f64::from(col) + 1.0));
        let (y1, y0) = (self.y_at(f64::from(row)), self.y_at(f64::from(row) + 1.0));
        Polygon::new(
            LineString::from(vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]),
            vec![],
        )
    }

    /// The x of lattice column coordinate `u` (cells from the left edge of column 0).
    fn x_at(&self, u: f64) -> f64 {
        self.origin.x + u * self.cell_size
    }

    /// The y of lattice row coordinate `v` (cells down from the top edge of row 0).
    fn y_at(&self, v: f64) -> f64 {
        self.origin.y - v * self.cell_size
    }
}

/// The lattice fitted to `outline` for `regions` cells, without its cells (they come from
/// [`Lattice::scores`]): S' = sqrt(area / regions), origin at the outline's (x_min, y_max) moved
/// right by `shift[0]·S'` and down by `shift[1]·S'`, extended by a cell on every side so the
/// outline is covered.
///
/// The extension puts the top-left corner of cell (0, 0) one cell left of and one cell above the
/// shifted origin, so with shifts in [0, 1) every point of the outline has u, v > 0 and no cell
/// that the outline reaches has a negative column or row.
///
/// With no regions or an outline without area there is nothing to fit: the lattice then has a
/// cell size of 0 and its origin at (0, 0).
///
/// Hexagons: the centre of (0, 0) at (x_min, y_max) moved `shift[0]` cells along the lattice's
/// q axis and `shift[1]` along its r axis; positions may then be negative.
pub fn frame(
    outline: &MultiPolygon<f64>,
    regions: usize,
    shift: [f64; 2],
    tiling: Tiling,
) -> Lattice {
    let size = (outline.unsigned_area() / regions as f64).sqrt();
    let corner = outline.bounding_rect();
    let (Some(corner), true) = (corner, size.is_finite() && size > 0.0) else {
        return Lattice {
            tiling,
            cell_size: 0.0,
            origin: Coord { x: 0.0, y: 0.0 },
            cells: Vec::new(),
        };
    };
    let origin = match tiling {
        Tiling::Square => Coord {
            x: corner.min().x + (shift[0] - 1.0) * size,
            y: corner.max().y - (shift[1] - 1.0) * size,
        },
        Tiling::Hex(_) => {
            let along = |p: Position, t: f64| tiling.centre_offset(p) * (t * size);
            Coord {
                x: corner.min().x,
                y: corner.max().y,
            } + along((1, 0), shift[0])
                + along((0, 1), shift[1])
        }
    };
    Lattice {
        tiling,
        cell_size: size,
        origin,
        cells: Vec::new(),
    }
}

/// Orders cells best first: score descending, then row, then column (method.md §6).
pub fn best_first(a: &LatticeCell, b: &LatticeCell) -> std::cmp::Ordering {
    b.score
        .total_cmp(&a.score)
        .then(a.row.cmp(&b.row))
        .then(a.col.cmp(&b.col))
}

impl Lattice {
    /// Every cell that `polygons` cover at all, with its score, tagged as belonging to `part`
    /// (unsorted). Only cells with a positive score are listed, so the lattice has no fixed
    /// width: it reaches as far right and down as the outline.
    ///
    /// Holes count as outside. A cell whose covered share is within 1e-9 of a whole number gets
    /// exactly that number, so that cells wholly inside tie at a score of exactly 2 and are
    /// ordered by row and column rather than by rounding noise, and cells the outline only
    /// grazes drop out.
    pub fn scores(&self, polygons: &MultiPolygon<f64>, part: usize) -> Vec<LatticeCell> {
        let mut cells = match self.tiling {
            Tiling::Square => {
                let to_lattice = |c: Coord<f64>| Coord {
                    x: (c.x - self.origin.x) / self.cell_size,
                    y: (self.origin.y - c.y) / self.cell_size,
                };
                let mut cells = Vec::new();
                sweep(unit_events(polygons, to_lattice), |col, row, area, wind| {
                    push_cell(&mut cells, col, row, area, wind)
                });
                cells
            }
            Tiling::Hex(orientation) => self.hex_scores(polygons, orientation),
        };
        for cell in &mut cells {
            cell.part = part;
        }
        cells
    }

    /// [`Lattice::scores`] for hexagons, exactly. Each hexagon is 6 cells of a fine rectangular
    /// grid: 4 whole ones and 4 halves cut along their diagonals (see [`diagonal_halves`]). The
    /// fine grid's whole cells, the parallelograms between its diagonals of either direction
    /// (unit squares after a shear, which keeps areas) and the winding number at the
    /// hexagons' centres all come from the square scanline.
    ///
    /// Pointy hexagons of side a (width w = √3·a) use fine cells of w/2 × a/2, with X to the
    /// right and Y up in those units: (q, r) is centred at X = 2q + r, Y = −3r. Flat hexagons
    /// are pointy ones with x and y exchanged: flat (q, r) is pointy (−r, −q).
    fn hex_scores(
        &self,
        polygons: &MultiPolygon<f64>,
        orientation: HexOrientation,
    ) -> Vec<LatticeCell> {
        let size = self.cell_size;
        let (half_w, half_a) = (HEX_WIDTH * size / 2.0, HEX_SIDE * size / 2.0);
        let o = self.origin;
        // (u, v) = (X, −Y): v downwards, as the scanline counts rows.
        let fine = |c: Coord<f64>| match orientation {
            HexOrientation::Pointy => Coord {
                x: (c.x - o.x) / half_w,
                y: -(c.y - o.y) / half_a,
            },
            HexOrientation::Flat => Coord {
                x: (c.y - o.y) / half_w,
                y: -(c.x - o.x) / half_a,
            },
        };
        let areas = |shear: fn(Coord<f64>) -> Coord<f64>| {
            let mut cells = FxHashMap::default();
            sweep(
                unit_events(polygons, |c| shear(fine(c))),
                |i, j, area, _| {
                    if area != 0.0 {
                        cells.insert((i, j), area);
                    }
                },
            );
            cells
        };
        let whole = areas(|c| c);
        let plus = diagonal_halves(&whole, &areas(|c| Coord { x: c.x + c.y, ..c }), |i, j| {
            i + j + 1
        });
        let minus = diagonal_halves(&whole, &areas(|c| Coord { x: c.x - c.y, ..c }), |i, j| {
            i - j
        });
        // The winding number at fine-cell centres half a cell up and left: at the fine grid's
        // vertices, where the hexagons' centres are.
        let mut inside = FxHashSet::default();
        sweep(
            unit_events(polygons, |c| fine(c) + Coord { x: 0.5, y: 0.5 }),
            |i, j, _, wind| {
                if wind != 0 {
                    inside.insert((i, j));
                }
            },
        );
        let mut hexes: Vec<Position> = Vec::new();
        let mut seen = FxHashSet::default();
        for &(i, j) in whole.keys() {
            for cx in [i, i + 1] {
                for cy in (-j - 2..=-j + 1).filter(|cy| cy.rem_euclid(3) == 0) {
                    let r = -cy / 3;
                    if (cx - r).rem_euclid(2) == 0 && seen.insert((cx, cy)) {
                        hexes.push(((cx - r) / 2, r));
                    }
                }
            }
        }
        let mut cells = Vec::with_capacity(hexes.len());
        for (q, r) in hexes {
            let (cx, cy) = (2 * q + r, -3 * r);
            let full = |i, j| whole.get(&(i, j)).copied().unwrap_or(0.0);
            let half = |h: &FxHashMap<Position, (f64, f64)>, i, j, second: bool| {
                h.get(&(i, j))
                    .map_or(0.0, |&(x, y)| if second { y } else { x })
            };
            let covered = full(cx - 1, -cy - 1)
                + full(cx, -cy - 1)
                + full(cx - 1, -cy)
                + full(cx, -cy)
                + half(&plus, cx - 1, -cy - 2, false)
                + half(&minus, cx, -cy - 2, true)
                + half(&minus, cx - 1, 1 - cy, false)
                + half(&plus, cx, 1 - cy, true);
            let wind = i32::from(inside.contains(&(cx, -cy)));
            let (col, row) = match orientation {
                HexOrientation::Pointy => (q, r),
                HexOrientation::Flat => (-r, -q),
            };
            push_cell(&mut cells, col, row, covered / 6.0, wind);
        }
        cells
    }
}

/// Splits each fine cell's covered area between the two halves its diagonal cuts it into, from
/// the areas of the sheared cells (parallelograms between two neighbouring diagonals). The
/// sheared cell `key(i, j)` of row `j` holds the first half of fine cell (i, j) and the second
/// half of (i + 1, j); the halves of each fine cell add up to its area. Solved along each row
/// from the right, where nothing is covered. Returns (first, second) per fine cell.
///
/// With u + v diagonals (`key` i + j + 1) the first half is the one below-right of the
/// diagonal (v down), the second above-left; with u − v diagonals (`key` i − j) the first half
/// is above-right, the second below-left.
fn diagonal_halves(
    whole: &FxHashMap<Position, f64>,
    sheared: &FxHashMap<Position, f64>,
    key: fn(i32, i32) -> i32,
) -> FxHashMap<Position, (f64, f64)> {
    let mut rows: FxHashMap<i32, Vec<i32>> = FxHashMap::default();
    for &(i, j) in whole.keys() {
        rows.entry(j).or_default().push(i);
    }
    let mut halves = FxHashMap::default();
    for (j, mut columns) in rows {
        // Fine cells not covered have empty halves, so only covered ones need solving.
        columns.sort_unstable_by(|a, b| b.cmp(a));
        for i in columns {
            let second_of_next = halves
                .get(&(i + 1, j))
                .map_or(0.0, |&(_, y): &(f64, f64)| y);
            let share = sheared.get(&(key(i, j), j)).copied().unwrap_or(0.0);
            let first = share - second_of_next;
            halves.insert((i, j), (first, whole[&(i, j)] - first));
        }
    }
    halves
}

/// What one segment piece (or one crossing of a row's centre line) does to one row of cells.
#[derive(Clone, Copy, Debug)]
struct Event {
    row: i32,
    col: i32,
    /// Area added to cell `col` itself, in cells.
    own: f64,
    /// Area added to every cell left of `col` in the row.
    left: f64,
    /// Winding number added to the centre of every cell left of `col` in the row.
    wind: i32,
}

/// The events of every ring of `polygons`, taken into unit-square coordinates (u right, v
/// down) by `to_unit`.
fn unit_events(
    polygons: &MultiPolygon<f64>,
    to_unit: impl Fn(Coord<f64>) -> Coord<f64>,
) -> Vec<Event> {
    let mut events = Vec::new();
    for polygon in polygons {
        // Exteriors add area, holes remove it, whatever the orientation of their rings.
        ring_events(polygon.exterior(), &to_unit, 1.0, &mut events);
        for hole in polygon.interiors() {
            ring_events(hole, &to_unit, -1.0, &mut events);
        }
    }
    events
}

/// Adds the events of one closed ring. `role` is +1 for an exterior and −1 for a hole; the
/// ring's own orientation is normalised so that its inside counts `role` times.
fn ring_events(
    ring: &LineString<f64>,
    to_unit: &impl Fn(Coord<f64>) -> Coord<f64>,
    role: f64,
    events: &mut Vec<Event>,
) {
    let points: Vec<Coord<f64>> = ring.coords().map(|&c| to_unit(c)).collect();
    // Shoelace area in lattice coordinates; with u right and v down, a ring with a positive
    // value here has its inside on the side that the edge integral counts positively.
    let twice_area: f64 = points
        .windows(2)
        .map(|w| w[0].x * w[1].y - w[1].x * w[0].y)
        .sum();
    if twice_area == 0.0 {
        // A ring without area covers nothing and its centre-line crossings cancel out.
        return;
    }
    let sign = role * twice_area.signum();
    for w in points.windows(2) {
        edge_events(w[0], w[1], sign, events);
    }
}

/// Adds the events of the edge `a → b` (lattice coordinates) of a ring counted `sign` times.
fn edge_events(a: Coord<f64>, b: Coord<f64>, sign: f64, events: &mut Vec<Event>) {
    let dv = b.y - a.y;
    if dv == 0.0 {
        // A horizontal edge has no cells beside it in v and crosses no centre line.
        return;
    }
    let u_at = |v: f64| a.x + (v - a.y) / dv * (b.x - a.x);
    let (v_min, v_max) = (a.y.min(b.y), a.y.max(b.y));
    let first = v_min.floor() as i32;
    let last = (v_max.ceil() as i32 - 1).max(first);
    let wind = (sign * dv.signum()) as i32;
    for row in first..=last {
        let top = f64::from(row);
        let (lo, hi) = (v_min.max(top), v_max.min(top + 1.0));
        if hi > lo {
            // The piece of the edge inside this row, in the edge's own direction.
            let (v0, v1) = if dv > 0.0 { (lo, hi) } else { (hi, lo) };
            piece_events(row, (u_at(v0), u_at(v1)), v1 - v0, sign, events);
        }
        // Half-open test, so a vertex exactly on the centre line is counted once.
        let centre = top + 0.5;
        if (a.y < centre) != (b.y < centre) {
            let col = (u_at(centre) - 0.5).ceil() as i32;
            events.push(Event {
                row,
                col,
                own: 0.0,
                left: 0.0,
                wind,
            });
        }
    }
}

/// Adds the events of a segment piece within one row, running from u = `us.0` to `us.1` while
/// v changes by `dv` (≠ 0), split at every column line it crosses.
fn piece_events(row: i32, us: (f64, f64), dv: f64, sign: f64, events: &mut Vec<Event>) {
    let (u_min, u_max) = (us.0.min(us.1), us.0.max(us.1));
    let first = u_min.floor() as i32;
    let last = (u_max.ceil() as i32 - 1).max(first);
    for col in first..=last {
        let left_edge = f64::from(col);
        let (lo, hi) = if first == last {
            (u_min, u_max)
        } else {
            (u_min.max(left_edge), u_max.min(left_edge + 1.0))
        };
        // v is linear in u along the piece, so its change within the column is the piece's
        // change in proportion to the u covered.
        let dv_part = if first == last {
            dv
        } else {
            dv * (hi - lo) / (u_max - u_min)
        };
        events.push(Event {
            row,
            col,
            own: sign * ((lo + hi) / 2.0 - left_edge) * dv_part,
            left: sign * dv_part,
            wind: 0,
        });
    }
}

/// Turns the events into the covered area and the winding number at the centre of every unit
/// cell that has either, handed to `emit(col, row, area, wind)`: per row, from right to left, a
/// running sum of the `left` areas and windings gives each cell what the segments right of it
/// add.
fn sweep(mut events: Vec<Event>, mut emit: impl FnMut(i32, i32, f64, i32)) {
    events.sort_unstable_by(|a, b| a.row.cmp(&b.row).then(b.col.cmp(&a.col)));
    for row_events in events.chunk_by(|a, b| a.row == b.row) {
        let row = row_events[0].row;
        let (mut area, mut wind) = (0.0, 0);
        let mut next_col = i32::MAX;
        for group in row_events.chunk_by(|a, b| a.col == b.col) {
            let col = group[0].col;
            // Cells between two event columns are crossed by no segment: wholly in or out.
            if wind != 0 || snap(area) > 0.0 {
                for gap in (col.saturating_add(1)..next_col).rev() {
                    emit(gap, row, area, wind);
                }
            }
            let own: f64 = group.iter().map(|e| e.own).sum();
            emit(col, row, area + own, wind);
            area += group.iter().map(|e| e.left).sum::<f64>();
            wind += group.iter().map(|e| e.wind).sum::<i32>();
            next_col = col;
        }
        // Left of the leftmost event the row is outside: every ring has closed by then, so the
        // running sums are back to 0.
        debug_assert!(
            wind == 0 && snap(area) == 0.0,
            "row {row} does not close: {area}"
        );
    }
}

/// Records cell (`col`, `row`) if it has a positive score.
fn push_cell(cells: &mut Vec<LatticeCell>, col: i32, row: i32, area: f64, wind: i32) {
    let score = if wind != 0 { 1.0 } else { 0.0 } + snap(area);
    if score > 0.0 {
        cells.push(LatticeCell {
            col,
            row,
            score,
            part: 0,
        });
    }
}

/// Clamps a covered share to [0, 1] and snaps it to 0 or 1 when within 1e-9 (see [`fit`]).
fn snap(area: f64) -> f64 {
    const TOLERANCE: f64 = 1e-9;
    let area = area.clamp(0.0, 1.0);
    if area < TOLERANCE {
        0.0
    } else if area > 1.0 - TOLERANCE {
        1.0
    } else {
        area
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lattice with every cell `outline` covers, best first: the one-part case.
    fn fit(outline: &MultiPolygon<f64>, regions: usize, shift: [f64; 2]) -> Lattice {
        let mut lattice = frame(outline, regions, shift, Tiling::Square);
        if lattice.cell_size > 0.0 {
            lattice.cells = lattice.scores(outline, 0);
            lattice.cells.sort_by(best_first);
        }
        lattice
    }
    use geo::{BooleanOps, Contains, Point};
    use std::f64::consts::TAU;

    fn rectangle(x0: f64, y0: f64, x1: f64, y1: f64) -> Polygon<f64> {
        Polygon::new(
            LineString::from(vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]),
            vec![],
        )
    }

    /// A closed ring of `n` points around `centre`, its radius wobbling with `angle`.
    fn wobbly_ring(centre: (f64, f64), radius: f64, n: usize) -> LineString<f64> {
        let mut points: Vec<(f64, f64)> = (0..n)
            .map(|k| {
                let t = TAU * k as f64 / n as f64;
                let r = radius * (1.0 + 0.2 * (7.0 * t).sin() + 0.07 * (31.0 * t).cos());
                (centre.0 + r * t.cos(), centre.1 + r * t.sin())
            })
            .collect();
        points.push(points[0]);
        LineString::from(points)
    }

    /// A mainland with a lake and an island, far from the origin and not in unit cells.
    fn map() -> MultiPolygon<f64> {
        let mut lake = wobbly_ring((5_000.0, -3_000.0), 700.0, 40);
        lake.0.reverse(); // holes run the other way round, as in valid polygons
        MultiPolygon(vec![
            Polygon::new(wobbly_ring((5_300.0, -2_900.0), 3_000.0, 300), vec![lake]),
            Polygon::new(wobbly_ring((10_500.0, -1_000.0), 900.0, 50), vec![]),
        ])
    }

    fn assert_ordered(lattice: &Lattice) {
        for pair in lattice.cells.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let ordered =
                a.score > b.score || (a.score == b.score && (a.row, a.col) < (b.row, b.col));
            assert!(ordered, "{a:?} before {b:?}");
        }
    }

    #[test]
    fn an_aligned_rectangle_gives_exactly_its_whole_cells() {
        let outline = MultiPolygon(vec![rectangle(0.0, 0.0, 10.0, 6.0)]);
        let lattice = fit(&outline, 60, [0.0, 0.0]);
        assert_eq!(lattice.cell_size, 1.0);
        assert_eq!(lattice.origin, Coord { x: -1.0, y: 7.0 });
        // Cells touching the rectangle from outside share only its border: no area, no centre.
        let expected: Vec<LatticeCell> = (1..=6)
            .flat_map(|row| {
                (1..=10).map(move |col| LatticeCell {
                    col,
                    row,
                    score: 2.0,
                    part: 0,
                })
            })
            .collect();
        assert_eq!(lattice.cells, expected);
        assert_eq!(lattice.centre(1, 1), Coord { x: 0.5, y: 5.5 });
        assert_eq!(lattice.square(1, 1), rectangle(0.0, 5.0, 1.0, 6.0));
    }

    #[test]
    fn a_shifted_lattice_scores_partial_cells_by_area_and_centre() {
        let outline = MultiPolygon(vec![rectangle(0.0, 0.0, 10.0, 6.0)]);
        let lattice = fit(&outline, 60, [0.25, 0.25]);
        assert_eq!(lattice.origin, Coord { x: -0.75, y: 6.75 });
        // Column 0 covers x in [-0.75, 0.25], column 10 [9.25, 10.25]; row 0 covers y in
        // [5.75, 6.75], row 6 [-0.25, 0.75]. The edge column and row on the left and top hold
        // a quarter and miss the centre, those on the right and bottom hold three quarters
        // and their centre.
        let share = |i: i32, last: i32| match i {
            0 => (0.25, false),
            i if i == last => (0.75, true),
            _ => (1.0, true),
        };
        assert_eq!(lattice.cells.len(), 11 * 7);
        for cell in &lattice.cells {
            let ((x, x_in), (y, y_in)) = (share(cell.col, 10), share(cell.row, 6));
            let expected = x * y + if x_in && y_in { 1.0 } else { 0.0 };
            assert!(
                (cell.score - expected).abs() < 1e-12,
                "{cell:?}: {expected}"
            );
        }
        let total: f64 = lattice.cells.iter().map(|c| c.score.fract()).sum::<f64>()
            + lattice.cells.iter().filter(|c| c.score == 2.0).count() as f64;
        assert!((total - 60.0).abs() < 1e-9, "covered area {total}");
        assert_ordered(&lattice);
    }

    #[test]
    fn scores_match_a_polygon_boolean_per_cell_with_holes_and_islands() {
        let outline = map();
        let lattice = fit(&outline, 150, [0.3, 0.7]);
        let s = lattice.cell_size;
        let expected_size = (outline.unsigned_area() / 150.0).sqrt();
        assert!((s - expected_size).abs() < 1e-9 * s);
        assert_ordered(&lattice);
        let reference = |col: i32, row: i32| {
            let square = lattice.square(col, row);
            let area = square.intersection(&outline).unsigned_area() / (s * s);
            let inside = outline.contains(&Point::from(lattice.centre(col, row)));
            area + if inside { 1.0 } else { 0.0 }
        };
        let listed: Vec<(i32, i32)> = lattice.cells.iter().map(|c| (c.col, c.row)).collect();
        let (mut partial, mut lake_cells) = (0, 0);
        for cell in &lattice.cells {
            let expected = reference(cell.col, cell.row);
            assert!((cell.score - expected).abs() < 1e-6, "{cell:?}: {expected}");
            partial += usize::from(cell.score.fract() != 0.0);
            let centre = lattice.centre(cell.col, cell.row);
            lake_cells += usize::from((centre.x - 5_000.0).hypot(centre.y + 3_000.0) < 300.0);
        }
        // The test means something only if it met cut cells, and the lake's middle is empty.
        assert!(partial > 30, "{partial} partial cells");
        assert_eq!(lake_cells, 0);
        // Every cell of the lattice that is not listed scores 0, including the lake's.
        let (max_col, max_row) = listed
            .iter()
            .fold((0, 0), |m, c| (m.0.max(c.0), m.1.max(c.1)));
        for row in 0..=max_row + 1 {
            for col in 0..=max_col + 1 {
                if !listed.contains(&(col, row)) {
                    assert!(reference(col, row) < 1e-9, "({col}, {row}) missing");
                }
            }
        }
        let covered: f64 = lattice
            .cells
            .iter()
            .map(|c| c.score - c.score.floor())
            .sum::<f64>()
            + lattice.cells.iter().filter(|c| c.score == 2.0).count() as f64;
        assert!((covered - 150.0).abs() < 1e-6, "covered {covered} cells");
    }

    #[test]
    fn hexagon_scores_match_a_polygon_boolean_per_hexagon() {
        // Both orientations, shifts along both axes, a map with a lake and an island: every
        // listed hexagon's score is its covered share (by geo's overlay) plus its centre, every
        // hexagon near the map that is not listed scores 0, and the shares add up to the area.
        let outline = map();
        for orientation in [HexOrientation::Pointy, HexOrientation::Flat] {
            for shift in [[0.0, 0.0], [0.3, 0.7]] {
                let tiling = Tiling::Hex(orientation);
                let mut lattice = frame(&outline, 150, shift, tiling);
                lattice.cells = lattice.scores(&outline, 0);
                let s = lattice.cell_size;
                let reference = |col: i32, row: i32| {
                    let hexagon = lattice.polygon(col, row);
                    let area = hexagon.intersection(&outline).unsigned_area() / (s * s);
                    let inside = outline.contains(&Point::from(lattice.centre(col, row)));
                    area + if inside { 1.0 } else { 0.0 }
                };
                let mut partial = 0;
                for cell in &lattice.cells {
                    let expected = reference(cell.col, cell.row);
                    assert!(
                        (cell.score - expected).abs() < 1e-6,
                        "{orientation:?} {shift:?} {cell:?}: {expected}"
                    );
                    partial += usize::from(cell.score.fract() != 0.0);
                }
                assert!(partial > 30, "{partial} partial hexagons");
                let listed: std::collections::HashSet<(i32, i32)> =
                    lattice.cells.iter().map(|c| (c.col, c.row)).collect();
                let bounds = outline.bounding_rect().unwrap();
                let (low, high) = (
                    lattice.position_of(Coord {
                        x: bounds.min().x,
                        y: bounds.max().y,
                    }),
                    lattice.position_of(Coord {
                        x: bounds.max().x,
                        y: bounds.min().y,
                    }),
                );
                let reach = (high.0 - low.0).abs() + (high.1 - low.1).abs() + 2;
                for q in low.0 - reach..=low.0 + reach {
                    for r in low.1 - reach..=low.1 + reach {
                        let centre = lattice.centre(q, r);
                        let near = centre.x > bounds.min().x - 2.0 * s
                            && centre.x < bounds.max().x + 2.0 * s
                            && centre.y > bounds.min().y - 2.0 * s
                            && centre.y < bounds.max().y + 2.0 * s;
                        if near && !listed.contains(&(q, r)) {
                            assert!(reference(q, r) < 1e-9, "({q}, {r}) missing");
                        }
                    }
                }
                let covered: f64 = (lattice.cells.iter())
                    .map(|c| {
                        if c.score >= 1.0 {
                            c.score - 1.0
                        } else {
                            c.score
                        }
                    })
                    .sum();
                assert!((covered - 150.0).abs() < 1e-6, "covered {covered} hexagons");
            }
        }
    }

    #[test]
    fn ring_orientation_does_not_matter() {
        let outline = map();
        let mut reversed = outline.clone();
        for polygon in &mut reversed.0 {
            polygon.exterior_mut(|ring| ring.0.reverse());
            polygon.interiors_mut(|holes| holes.iter_mut().for_each(|h| h.0.reverse()));
        }
        let (a, b) = (
            fit(&outline, 80, [0.5, 0.0]),
            fit(&reversed, 80, [0.5, 0.0]),
        );
        assert_eq!(a.cells.len(), b.cells.len());
        for (x, y) in a.cells.iter().zip(&b.cells) {
            assert_eq!((x.col, x.row), (y.col, y.row));
            assert!((x.score - y.score).abs() < 1e-12);
        }
    }

    #[test]
    fn nothing_to_fit_gives_no_cells() {
        let square = MultiPolygon(vec![rectangle(0.0, 0.0, 1.0, 1.0)]);
        assert!(fit(&square, 0, [0.0, 0.0]).cells.is_empty());
        assert!(fit(&MultiPolygon(vec![]), 5, [0.0, 0.0]).cells.is_empty());
    }
}
