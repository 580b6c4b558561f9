//! How cells tile the plane: which lattice positions are neighbours, and where a cell's corners
//! are. The metrics (pieces, holes, notches, the outline of the layout) and the refinement ask
//! this, so they read a layout the same way.
//!
//! Positions are integer (column, row) pairs, rows counted downwards. Corners are integer keys
//! of the lattice's vertices, shared exactly by the cells that meet there, so boundaries can be
//! traced without comparing floating-point coordinates.

use super::params::{CellShape, HexOrientation, Params};
use geo::Coord;
use std::ops::Deref;

/// A lattice position: (column, row) for squares, rows downwards; axial (q, r) for hexagons,
/// r downwards (see [`Tiling`]).
pub type Position = (i32, i32);

/// A lattice vertex, in the tiling's own integer coordinates.
pub type Corner = (i64, i64);

/// How cells tile the plane. Every tiling has cells of area 1 (in cells of side S).
///
/// Hexagons use axial positions (q, r) so that a translation of the lattice is the same step
/// everywhere (offset rows would change their parity): pointy hexagons have q along a row and r
/// down to the next row, half a hexagon to the right; flat hexagons q along a column of
/// hexagons to the right-and-down and r straight down. Both have the neighbours (q ± 1, r),
/// (q, r ± 1), (q + 1, r − 1) and (q − 1, r + 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tiling {
    Square,
    Hex(HexOrientation),
}

/// The side a of a hexagon of area 1: 3√3/2 · a² = 1 (constants, since the refinement asks for
/// them with every pair it weighs; a test checks them).
pub const HEX_SIDE: f64 = 0.620_403_239_401_399_7;
/// The width of a hexagon of area 1 across its edges, √3·a: its neighbours' distance.
pub const HEX_WIDTH: f64 = 1.074_569_931_823_541_8;

/// Up to six positions or corners, as a slice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ring<T> {
    items: [T; 6],
    len: usize,
}

impl<T: Copy + Default> Ring<T> {
    fn of(items: &[T]) -> Self {
        let mut ring = Ring {
            items: [T::default(); 6],
            len: items.len(),
        };
        ring.items[..items.len()].copy_from_slice(items);
        ring
    }
}

impl<T> Deref for Ring<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        &self.items[..self.len]
    }
}

/// The edge neighbours of a square, counter-clockwise in the map from the east.
const SQUARE_SIDES: [Position; 4] = [(1, 0), (0, -1), (-1, 0), (0, 1)];
/// The edge neighbours of a pointy hexagon, counter-clockwise from the east: E, NE, NW, W, SW, SE.
const POINTY_SIDES: [Position; 6] = [(1, 0), (1, -1), (0, -1), (-1, 0), (-1, 1), (0, 1)];
/// Pointy corners in units of (w/2, a/2) from the centre (w = √3·a the width, a the side), y
/// up: corner k and k + 1 bound the edge shared with `POINTY_SIDES[k]`.
const POINTY_CORNERS: [Corner; 6] = [(1, -1), (1, 1), (0, 2), (-1, 1), (-1, -1), (0, -2)];
/// The edge neighbours of a flat hexagon, counter-clockwise from the north-east: NE, N, NW, SW,
/// S, SE.
const FLAT_SIDES: [Position; 6] = [(1, -1), (0, -1), (-1, 0), (-1, 1), (0, 1), (1, 0)];
/// Flat corners in units of (a/2, w/2) from the centre, y up, as for the pointy ones.
const FLAT_CORNERS: [Corner; 6] = [(2, 0), (1, 1), (-1, 1), (-2, 0), (-1, -1), (1, -1)];

impl Tiling {
    /// The tiling the parameters ask for.
    pub fn of(params: &Params) -> Tiling {
        match params.cell {
            CellShape::Square => Tiling::Square,
            CellShape::Hex => Tiling::Hex(params.hex_orientation),
        }
    }

    /// The steps to the positions sharing an edge, counter-clockwise in the map.
    pub fn sides(self) -> &'static [Position] {
        match self {
            Tiling::Square => &SQUARE_SIDES,
            Tiling::Hex(HexOrientation::Pointy) => &POINTY_SIDES,
            Tiling::Hex(HexOrientation::Flat) => &FLAT_SIDES,
        }
    }

    /// The positions sharing an edge with `p`, counter-clockwise in the map: edge `k` of
    /// [`Tiling::corners`] is shared with the `k`-th.
    pub fn edge_neighbours(self, (c, r): Position) -> Ring<Position> {
        let sides = self.sides();
        let mut ring = Ring::of(sides);
        for (n, &(dc, dr)) in ring.items.iter_mut().zip(sides) {
            *n = (c + dc, r + dr);
        }
        ring
    }

    /// One step of each pair of opposite steps to a touching position ([`Tiling::touching`]):
    /// walking these from every cell meets each touching pair once.
    pub fn half_neighbourhood(self) -> &'static [Position] {
        match self {
            Tiling::Square => &[(1, -1), (1, 0), (1, 1), (0, 1)],
            Tiling::Hex(_) => &[(1, 0), (-1, 1), (0, 1)],
        }
    }

    /// Lattice steps between two positions: the king's moves for squares (Chebyshev), the
    /// hexagonal distance for hexagons.
    pub fn distance(self, a: Position, b: Position) -> i32 {
        let (dc, dr) = (a.0 - b.0, a.1 - b.1);
        match self {
            Tiling::Square => dc.abs().max(dr.abs()),
            Tiling::Hex(_) => (dc.abs() + dr.abs() + (dc + dr).abs()) / 2,
        }
    }

    /// Whether two positions are neighbours in the sense of C_adjacent (method.md §8): squares
    /// touching at an edge or a corner (centres closer than 1.5 cells), hexagons sharing an
    /// edge.
    pub fn touching(self, a: Position, b: Position) -> bool {
        a != b && self.distance(a, b) <= 1
    }

    /// The positions [`Tiling::touching`] `p`: its 8 neighbours for squares, 6 for hexagons.
    pub fn touching_positions(self, p: Position) -> impl Iterator<Item = Position> {
        let (c, r) = p;
        self.half_neighbourhood()
            .iter()
            .flat_map(move |&(dc, dr)| [(c + dc, r + dr), (c - dc, r - dr)])
    }

    /// Whether two positions share an edge.
    pub fn sharing_an_edge(self, a: Position, b: Position) -> bool {
        match self {
            Tiling::Square => (a.0 - b.0).abs() + (a.1 - b.1).abs() == 1,
            Tiling::Hex(_) => self.touching(a, b),
        }
    }

    /// The centre of `p` in the tiling's integer units (those of [`Tiling::corners`]), y up:
    /// orders positions from the bottom and from the left exactly.
    pub fn centre_key(self, (c, r): Position) -> Corner {
        let (c, r) = (i64::from(c), i64::from(r));
        match self {
            Tiling::Square => (c, -r),
            Tiling::Hex(HexOrientation::Pointy) => (2 * c + r, -3 * r),
            Tiling::Hex(HexOrientation::Flat) => (3 * c, -(2 * r + c)),
        }
    }

    /// The centre of `p` in cells from the centre of (0, 0), y up.
    pub fn centre_offset(self, (c, r): Position) -> Coord<f64> {
        let (c, r) = (f64::from(c), f64::from(r));
        let (a, w) = (HEX_SIDE, HEX_WIDTH);
        match self {
            Tiling::Square => Coord { x: c, y: -r },
            Tiling::Hex(HexOrientation::Pointy) => Coord {
                x: w * (c + r / 2.0),
                y: -1.5 * a * r,
            },
            Tiling::Hex(HexOrientation::Flat) => Coord {
                x: 1.5 * a * c,
                y: -w * (r + c / 2.0),
            },
        }
    }

    /// `offset` (in cells, y up) in the lattice's own coordinates: the inverse of
    /// [`Tiling::centre_offset`], not rounded.
    pub fn fractional(self, offset: Coord<f64>) -> (f64, f64) {
        let (a, w) = (HEX_SIDE, HEX_WIDTH);
        match self {
            Tiling::Square => (offset.x, -offset.y),
            Tiling::Hex(HexOrientation::Pointy) => {
                let r = -offset.y / (1.5 * a);
                (offset.x / w - r / 2.0, r)
            }
            Tiling::Hex(HexOrientation::Flat) => {
                let q = offset.x / (1.5 * a);
                (q, -offset.y / w - q / 2.0)
            }
        }
    }

    /// The shortest distance between the centres of two positions, in cells: 1 for squares,
    /// the row (pointy) or column (flat) spacing 1.5·a for hexagons.
    pub fn pitch(self) -> f64 {
        match self {
            Tiling::Square => 1.0,
            Tiling::Hex(_) => 1.5 * HEX_SIDE,
        }
    }

    /// The position whose centre is nearest `offset` (in cells from the centre of (0, 0), y
    /// up).
    pub fn position_at(self, offset: Coord<f64>) -> Position {
        let (q, r) = self.fractional(offset);
        if self == Tiling::Square {
            return (q.round() as i32, r.round() as i32);
        }
        // The cube rounding of hexagonal grids.
        let s = -q - r;
        let (mut rq, mut rr, rs) = (q.round(), r.round(), s.round());
        let (dq, dr, ds) = ((rq - q).abs(), (rr - r).abs(), (rs - s).abs());
        if dq > dr && dq > ds {
            rq = -rr - rs;
        } else if dr > ds {
            rr = -rq - rs;
        }
        (rq as i32, rr as i32)
    }

    /// The corners of `p`, counter-clockwise in the map (y up), each edge `k` running from
    /// corner `k` to corner `k + 1` and shared with `edge_neighbours(p)[k]`.
    pub fn corners(self, (c, r): Position) -> Ring<Corner> {
        let (centre, offsets): (Corner, &[Corner]) = match self {
            Tiling::Square => {
                // Corners in (x, y) = (column, −row): y points up as in the map.
                let (x, y) = (i64::from(c), -i64::from(r));
                return Ring::of(&[(x + 1, y - 1), (x + 1, y), (x, y), (x, y - 1)]);
            }
            Tiling::Hex(HexOrientation::Pointy) => (self.centre_key((c, r)), &POINTY_CORNERS),
            Tiling::Hex(HexOrientation::Flat) => (self.centre_key((c, r)), &FLAT_CORNERS),
        };
        let mut ring = Ring::of(offsets);
        for corner in ring.items.iter_mut().take(offsets.len()) {
            *corner = (centre.0 + corner.0, centre.1 + corner.1);
        }
        ring
    }

    /// Where `corner` lies, in cells from the centre of position (0, 0) (y up).
    pub fn corner_offset(self, (x, y): Corner) -> Coord<f64> {
        let (a, w) = (HEX_SIDE, HEX_WIDTH);
        match self {
            Tiling::Square => Coord {
                x: x as f64 - 0.5,
                y: y as f64 + 0.5,
            },
            Tiling::Hex(HexOrientation::Pointy) => Coord {
                x: x as f64 * w / 2.0,
                y: y as f64 * a / 2.0,
            },
            Tiling::Hex(HexOrientation::Flat) => Coord {
                x: x as f64 * a / 2.0,
                y: y as f64 * w / 2.0,
            },
        }
    }

    /// The step to the edge neighbour nearest to `direction` (y up): for squares one of the
    /// eight around (a corner neighbour too), for hexagons one of the six.
    pub fn step_towards(self, direction: Coord<f64>) -> Position {
        match self {
            Tiling::Square => {
                let octant =
                    (direction.y.atan2(direction.x) / std::f64::consts::FRAC_PI_4).round() as i32;
                let (dc, dy) = [
                    (1, 0),
                    (1, 1),
                    (0, 1),
                    (-1, 1),
                    (-1, 0),
                    (-1, -1),
                    (0, -1),
                    (1, -1),
                ][octant.rem_euclid(8) as usize];
                (dc, -dy)
            }
            Tiling::Hex(_) => {
                let best = |&&s: &&Position| {
                    let o = self.centre_offset(s);
                    (o.x * direction.x + o.y * direction.y) / (o.x.hypot(o.y))
                };
                *(self.sides().iter())
                    .max_by(|a, b| best(a).total_cmp(&best(b)))
                    .expect("a tiling has sides")
            }
        }
    }

    /// The position whose [`Tiling::offset_coordinates`] are `(col, row)`: their inverse.
    pub fn from_offset_coordinates(self, (col, row): Position) -> Position {
        match self {
            Tiling::Square => (col, row),
            Tiling::Hex(HexOrientation::Pointy) => (col - row.div_euclid(2), row),
            Tiling::Hex(HexOrientation::Flat) => (col, row - col.div_euclid(2)),
        }
    }

    /// The offset column and row of `p`: for squares `p` itself; for pointy hexagons the rows
    /// are `r` and the odd ones sit half a cell to the right; for flat hexagons the columns are
    /// `q` and the odd ones sit half a cell lower.
    pub fn offset_coordinates(self, (q, r): Position) -> Position {
        match self {
            Tiling::Square => (q, r),
            Tiling::Hex(HexOrientation::Pointy) => (q + r.div_euclid(2), r),
            Tiling::Hex(HexOrientation::Flat) => (q, r + q.div_euclid(2)),
        }
    }
}

/// The eight positions around `p`, in order round it (N, NE, E, SE, S, SW, W, NW): each is an
/// edge-neighbour of the next.
fn ring((c, r): Position) -> [Position; 8] {
    [
        (c, r - 1),
        (c + 1, r - 1),
        (c + 1, r),
        (c + 1, r + 1),
        (c, r + 1),
        (c - 1, r + 1),
        (c - 1, r),
        (c - 1, r - 1),
    ]
}

/// What taking or giving up position `p` does to the shape of a layout, from its 3×3
/// neighbourhood alone. Both cells and empty space are taken as edge-connected, as the rings of
/// a polygon union are (a hole that meets the outside only at a corner is still a hole).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Around {
    /// Edge-connected groups of cells around `p` (within its 3×3 neighbourhood) that touch `p`
    /// by an edge.
    pub cells: usize,
    /// Edge-connected groups of empty positions around `p` that touch `p` by an edge.
    pub empty: usize,
}

impl Tiling {
    /// The groups around `p` for the layout whose cells `occupied` says.
    pub fn around(self, p: Position, occupied: impl Fn(Position) -> bool) -> Around {
        match self {
            Tiling::Square => {
                let full: [bool; 8] = ring(p).map(occupied);
                Around {
                    cells: edge_runs(&full, true),
                    empty: edge_runs(&full, false),
                }
            }
            Tiling::Hex(_) => {
                // The six neighbours share an edge with `p` and each with the next: the groups
                // are the runs round the ring.
                let mut full = [false; 6];
                for (f, n) in full.iter_mut().zip(self.edge_neighbours(p).iter()) {
                    *f = occupied(*n);
                }
                let runs = |state: bool| {
                    if full.iter().all(|&f| f == state) {
                        return 1;
                    }
                    (0..6)
                        .filter(|&k| full[k] == state && full[(k + 5) % 6] != state)
                        .count()
                };
                Around {
                    cells: if full.iter().any(|&f| f) {
                        runs(true)
                    } else {
                        0
                    },
                    empty: if full.iter().any(|&f| !f) {
                        runs(false)
                    } else {
                        0
                    },
                }
            }
        }
    }
}

/// The runs of ring positions whose state is `state` (consecutive positions of the ring are
/// edge-neighbours) that hold one of `p`'s edge-neighbours (the even positions).
fn edge_runs(full: &[bool; 8], state: bool) -> usize {
    let Some(start) = (0..8).find(|&k| full[k] != state) else {
        // The whole ring: one run round `p`.
        return 1;
    };
    let (mut runs, mut in_run, mut has_edge) = (0, false, false);
    for step in 1..=8 {
        let k = (start + step) % 8;
        if full[k] == state {
            in_run = true;
            has_edge |= k % 2 == 0;
        } else if in_run {
            runs += usize::from(has_edge);
            in_run = false;
            has_edge = false;
        }
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_edge_is_shared_with_its_neighbour() {
        let all = [
            Tiling::Square,
            Tiling::Hex(HexOrientation::Pointy),
            Tiling::Hex(HexOrientation::Flat),
        ];
        for t in all {
            for p in [(3, -2), (0, 0), (-5, 7)] {
                let corners = t.corners(p);
                let n_sides = corners.len();
                for (k, &n) in t.edge_neighbours(p).iter().enumerate() {
                    let (a, b) = (corners[k], corners[(k + 1) % n_sides]);
                    // The neighbour has the same edge, the other way round.
                    let theirs = t.corners(n);
                    let shared =
                        (0..n_sides).any(|j| theirs[j] == b && theirs[(j + 1) % n_sides] == a);
                    assert!(shared, "{t:?}: edge {k} of {p:?} with {n:?}");
                    assert!(t.sharing_an_edge(p, n) && t.touching(p, n));
                    // Neighbours' centres are one edge-to-edge width apart: 1 for squares,
                    // √3·a for hexagons.
                    let d = t.centre_offset(n) - t.centre_offset(p);
                    let width = if t == Tiling::Square { 1.0 } else { HEX_WIDTH };
                    assert!((d.x.hypot(d.y) - width).abs() < 1e-12, "{t:?} {p:?} {n:?}");
                    assert_eq!(t.position_at(t.centre_offset(n)), n);
                    assert_eq!(t.step_towards(d), (n.0 - p.0, n.1 - p.1));
                }
                // The corners enclose area 1, counter-clockwise.
                let points: Vec<Coord<f64>> = corners.iter().map(|&c| t.corner_offset(c)).collect();
                let twice: f64 = (0..n_sides)
                    .map(|k| {
                        let (a, b) = (points[k], points[(k + 1) % n_sides]);
                        a.x * b.y - b.x * a.y
                    })
                    .sum();
                assert!(
                    (twice / 2.0 - 1.0).abs() < 1e-12,
                    "{t:?}: area {}",
                    twice / 2.0
                );
                let centre =
                    points.iter().fold(Coord { x: 0.0, y: 0.0 }, |s, &c| s + c) / n_sides as f64;
                let expected = t.centre_offset(p);
                assert!((centre - expected).x.abs() < 1e-12 && (centre - expected).y.abs() < 1e-12);
            }
        }
        let t = Tiling::Square;
        assert!(t.touching((0, 0), (1, 1)) && !t.sharing_an_edge((0, 0), (1, 1)));
        assert!(!t.touching((0, 0), (2, 0)));
        let hex = Tiling::Hex(HexOrientation::Pointy);
        assert!(!hex.touching((0, 0), (1, 1)) && hex.touching((0, 0), (1, -1)));
        assert_eq!(hex.distance((0, 0), (2, -1)), 2);
        // Offset rows: (q, r) = (0, 1) is below (0, 0) and half a cell to its right.
        assert_eq!(hex.offset_coordinates((0, 1)), (0, 1));
        assert_eq!(hex.offset_coordinates((-1, 2)), (0, 2));
        for t in [hex, Tiling::Hex(HexOrientation::Flat), Tiling::Square] {
            for p in [(0, 0), (3, -5), (-4, 7), (-3, -3)] {
                assert_eq!(
                    t.from_offset_coordinates(t.offset_coordinates(p)),
                    p,
                    "{t:?}"
                );
            }
        }
        assert_eq!(
            Tiling::Hex(HexOrientation::Flat).offset_coordinates((1, -1)),
            (1, -1)
        );
    }

    /// The topological numbers of the centre of a 3×3 picture (`#` a cell), the centre itself
    /// left out.
    fn around(picture: [&str; 3]) -> Around {
        let at = |(c, r): Position| {
            let row = picture[(r + 1) as usize].as_bytes();
            row[(c + 1) as usize] == b'#'
        };
        Tiling::Square.around((0, 0), at)
    }

    #[test]
    fn the_hexagon_constants_give_area_one() {
        assert!((1.5 * 3f64.sqrt() * HEX_SIDE * HEX_SIDE - 1.0).abs() < 1e-15);
        assert!((HEX_WIDTH - 3f64.sqrt() * HEX_SIDE).abs() < 1e-15);
    }

    #[test]
    fn around_a_hexagon_counts_the_runs_of_its_six_neighbours() {
        let t = Tiling::Hex(HexOrientation::Pointy);
        let sides = t.edge_neighbours((0, 0));
        let with = |taken: &[usize]| {
            let cells: Vec<Position> = taken.iter().map(|&k| sides[k]).collect();
            t.around((0, 0), |p| cells.contains(&p))
        };
        // Alone, on a straight edge, a bridge between two cells, inside a hole.
        assert_eq!(with(&[]), Around { cells: 0, empty: 1 });
        assert_eq!(with(&[3, 4, 5]), Around { cells: 1, empty: 1 });
        assert_eq!(with(&[0, 3]), Around { cells: 2, empty: 2 });
        assert_eq!(with(&[0, 1, 2, 3, 4, 5]), Around { cells: 1, empty: 0 });
        // A run that wraps round the end of the ring is one run.
        assert_eq!(with(&[5, 0, 1]), Around { cells: 1, empty: 1 });
    }

    #[test]
    fn simple_points_are_told_from_bridges_holes_and_islands() {
        // On a straight edge: simple.
        assert_eq!(around(["...", "#.#", "###"]), Around { cells: 1, empty: 1 });
        // A bridge between two cells: taking it away splits them; taking it splits the empty
        // space beside it.
        assert_eq!(around([".#.", "...", ".#."]), Around { cells: 2, empty: 2 });
        // Inside a hole: filling it removes the hole.
        assert_eq!(around(["###", "#.#", "###"]), Around { cells: 1, empty: 0 });
        // Alone: a piece of its own.
        assert_eq!(around(["...", "...", "..."]), Around { cells: 0, empty: 1 });
        // A corner cell does not touch the centre; nor does an empty corner.
        assert_eq!(around(["#..", "...", "..."]).cells, 0);
        assert_eq!(around([".#.", "#.#", ".#."]), Around { cells: 4, empty: 0 });
        // A cell at a corner does not touch the centre; taking the centre would part the empty
        // space above it from the empty space to its right and below.
        assert_eq!(around(["..#", "#..", "#.."]), Around { cells: 1, empty: 2 });
        // The bottom of a bay: taking it fills the bay a little, no hole is closed.
        assert_eq!(around(["#.#", "#.#", "###"]), Around { cells: 1, empty: 1 });
    }
}
