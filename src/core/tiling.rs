//! How cells tile the plane: which lattice positions are neighbours, and where a cell's corners
//! are. The metrics (pieces, holes, notches, the outline of the layout) and the refinement ask
//! this, so they read a layout the same way.
//!
//! Positions are integer (column, row) pairs, rows counted downwards. Corners are integer keys
//! of the lattice's vertices, shared exactly by the cells that meet there, so boundaries can be
//! traced without comparing floating-point coordinates.

use geo::Coord;

/// A lattice position: (column, row), rows downwards.
pub type Position = (i32, i32);

/// A lattice vertex, in the tiling's own integer coordinates.
pub type Corner = (i64, i64);

/// The square tiling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Square;

impl Square {
    /// The positions sharing an edge with `p`.
    pub fn edge_neighbours(self, (c, r): Position) -> [Position; 4] {
        [(c + 1, r), (c, r - 1), (c - 1, r), (c, r + 1)]
    }

    /// Whether two positions are neighbours in the sense of C_adjacent: touching at an edge or a
    /// corner (method.md §8: centres closer than 1.5 cells).
    pub fn touching(self, a: Position, b: Position) -> bool {
        a != b && (a.0 - b.0).abs() <= 1 && (a.1 - b.1).abs() <= 1
    }

    /// Whether two positions share an edge.
    pub fn sharing_an_edge(self, a: Position, b: Position) -> bool {
        (a.0 - b.0).abs() + (a.1 - b.1).abs() == 1
    }

    /// The corners of `p`, counter-clockwise in the map (y up), each edge `k` running from
    /// corner `k` to corner `k + 1` and shared with `edge_neighbours(p)[k]`.
    pub fn corners(self, (c, r): Position) -> [Corner; 4] {
        // Corners in (x, y) = (column, −row): y points up as in the map.
        let (x, y) = (i64::from(c), -i64::from(r));
        [(x + 1, y - 1), (x + 1, y), (x, y), (x, y - 1)]
    }

    /// Where corner `k` lies, in cells from the centre of position (0, 0) (y up).
    pub fn corner_offset(self, (x, y): Corner) -> Coord<f64> {
        Coord {
            x: x as f64 - 0.5,
            y: y as f64 + 0.5,
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

impl Square {
    /// The groups around `p` for the layout whose cells `occupied` says.
    pub fn around(self, p: Position, occupied: impl Fn(Position) -> bool) -> Around {
        let full: [bool; 8] = ring(p).map(occupied);
        Around {
            cells: edge_runs(&full, true),
            empty: edge_runs(&full, false),
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
        let t = Square;
        let p = (3, -2);
        let corners = t.corners(p);
        for (k, &n) in t.edge_neighbours(p).iter().enumerate() {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            // The neighbour has the same edge, the other way round.
            let theirs = t.corners(n);
            let shared = (0..4).any(|j| theirs[j] == b && theirs[(j + 1) % 4] == a);
            assert!(shared, "edge {k} of {p:?} with {n:?}");
            assert!(t.sharing_an_edge(p, n) && t.touching(p, n));
        }
        assert!(t.touching((0, 0), (1, 1)) && !t.sharing_an_edge((0, 0), (1, 1)));
        assert!(!t.touching((0, 0), (2, 0)));
    }

    /// The topological numbers of the centre of a 3×3 picture (`#` a cell), the centre itself
    /// left out.
    fn around(picture: [&str; 3]) -> Around {
        let at = |(c, r): Position| {
            let row = picture[(r + 1) as usize].as_bytes();
            row[(c + 1) as usize] == b'#'
        };
        Square.around((0, 0), at)
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
