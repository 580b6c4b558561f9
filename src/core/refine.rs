//! Step 4c (method.md §6b, beyond the paper): a seeded simulated-annealing search that swaps and
//! moves cells to keep neighbours next to each other and in the right direction.
//!
//! A proposal picks a region at random and a lattice position: half of the time (when the region
//! has neighbours) a position next to the cell of one of its neighbours, so that a region far
//! from its neighbours can jump back in one swap; otherwise a position within 2 cells of its own
//! cell. A region already there swaps cells with it; a free cell among the best
//! `ceil(refine_cell_ratio·M)` cells is moved to, if it is within 2 cells and moves are allowed;
//! anything else is a wasted proposal (it still counts as a move, so the run time is fixed).
//! The energy change of a proposal is evaluated on the pairs and locations of the one or two
//! regions involved only, O(degree). The best state seen is recovered at the end by undoing the
//! moves accepted since it, so it is never copied.

use super::grid::{Lattice, LatticeCell};
use super::Params;
use geo::Coord;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rustc_hash::FxHashMap;

/// What the refinement needs to know of a layout, all in the unit-cell frame.
pub struct Layout<'a> {
    /// Adjacent region pairs (i < j).
    pub adjacency: &'a [(usize, usize)],
    /// Original centroids: the directions to keep.
    pub centroids: &'a [Coord<f64>],
    /// Moved centroids: the positions to stay near.
    pub moved: &'a [Coord<f64>],
    pub lattice: &'a Lattice,
}

/// Improves `cells` (per region, an index into `layout.lattice.cells`) and returns the new
/// assignment; deterministic for a given `seed`.
///
/// The result never has a higher energy (method.md §6b, weights from `params`) than `cells`,
/// its cells are distinct, and with fewer than `params.refine_swap_only_below` regions it uses
/// exactly the cells of `cells` (only swaps), so the outline keeps its shape.
///
/// # Panics
/// If two regions share a cell, or a cell index is outside the lattice.
pub fn refine(layout: &Layout, cells: &[usize], params: &Params, seed: u64) -> Vec<usize> {
    if cells.is_empty() {
        // No region to draw a proposal for.
        return Vec::new();
    }
    let problem = Problem::new(layout, params);
    let (best, _) = anneal(&problem, cells, params, seed);
    // The search tracks its energy as a sum of many deltas; comparing exact totals makes the
    // promise never to return a worse state hold even to the last bit.
    if problem.energy(&best) <= problem.energy(cells) {
        best
    } else {
        cells.to_vec()
    }
}

/// Runs the annealing from `cells` and returns the best state seen and its (tracked) energy.
fn anneal(problem: &Problem, cells: &[usize], params: &Params, seed: u64) -> (Vec<usize>, f64) {
    let regions = cells.len();
    let pool = ((params.refine_cell_ratio * regions as f64).ceil() as usize)
        .min(problem.layout.lattice.cells.len());
    let mut board = Board::new(problem.layout.lattice, cells, pool);
    let may_move = regions >= params.refine_swap_only_below;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut energy = problem.energy(cells);
    let mut best = energy;
    // Inverses of the moves accepted since the best state, to walk back to it at the end.
    let mut since_best = Vec::new();
    let moves = params.refine_moves;
    for step in 0..moves {
        let temperature = params.refine_temperature * (1.0 - step as f64 / moves as f64);
        let Some(proposal) = board.propose(problem, &mut rng, may_move) else {
            continue;
        };
        let involved = proposal.regions();
        let before = problem.local_energy(&involved, &board.at);
        let undo = board.apply(proposal);
        let delta = problem.local_energy(&involved, &board.at) - before;
        let accept = delta <= 0.0
            || (temperature > 0.0 && rng.random::<f64>() < (-delta / temperature).exp());
        if !accept {
            board.apply(undo);
            continue;
        }
        energy += delta;
        since_best.push(undo);
        // Gains below rounding noise do not make a new best: they would only be drift.
        if energy < best - 1e-9 {
            best = energy;
            since_best.clear();
        }
    }
    for undo in since_best.into_iter().rev() {
        board.apply(undo);
    }
    (board.at, best)
}

/// The energy of method.md §6b with its weights, and each region's neighbours.
struct Problem<'a> {
    layout: &'a Layout<'a>,
    w_adjacent: f64,
    w_angle: f64,
    w_misdirected: f64,
    /// `refine_w_location` per S'², so that distances count in cells.
    w_location: f64,
    /// Per region, each adjacent region and the original direction towards it.
    neighbours: Vec<Vec<(usize, Coord<f64>)>>,
}

impl<'a> Problem<'a> {
    fn new(layout: &'a Layout<'a>, params: &Params) -> Self {
        let mut neighbours = vec![Vec::new(); layout.centroids.len()];
        for &(i, j) in layout.adjacency.iter().filter(|(i, j)| i != j) {
            let direction = layout.centroids[j] - layout.centroids[i];
            neighbours[i].push((j, direction));
            neighbours[j].push((i, -direction));
        }
        Problem {
            layout,
            w_adjacent: params.refine_w_adjacent,
            w_angle: params.refine_w_angle,
            w_misdirected: params.refine_w_misdirected,
            w_location: params.refine_w_location / layout.lattice.cell_size.powi(2),
            neighbours,
        }
    }

    fn cell(&self, index: usize) -> LatticeCell {
        self.layout.lattice.cells[index]
    }

    /// The energy of an adjacent pair whose original direction is `direction` and whose cells
    /// are `from` and `to`. Both orders of the pair give the same value.
    fn pair(&self, direction: Coord<f64>, from: LatticeCell, to: LatticeCell) -> f64 {
        let (cols, rows) = (to.col - from.col, to.row - from.row);
        // Rows grow downwards, y upwards.
        let (x, y) = (f64::from(cols), -f64::from(rows));
        let cross = direction.x * y - direction.y * x;
        let dot = direction.x * x + direction.y * y;
        // In [0°, 180°]; 0 when the original centroids coincide.
        let angle = cross.abs().atan2(dot).to_degrees();
        let mut energy = self.w_angle * angle / 90.0;
        if cols.abs().max(rows.abs()) > 1 {
            energy += self.w_adjacent;
        }
        if angle > 45.0 {
            energy += self.w_misdirected;
        }
        energy
    }

    fn location(&self, region: usize, cell: LatticeCell) -> f64 {
        let centre = self.layout.lattice.centre(cell.col, cell.row);
        let offset = self.layout.moved[region] - centre;
        self.w_location * (offset.x * offset.x + offset.y * offset.y)
    }

    /// The whole energy of the assignment `at`.
    fn energy(&self, at: &[usize]) -> f64 {
        let pairs: f64 = (self.layout.adjacency.iter())
            .filter(|(i, j)| i != j)
            .map(|&(i, j)| {
                let direction = self.layout.centroids[j] - self.layout.centroids[i];
                self.pair(direction, self.cell(at[i]), self.cell(at[j]))
            })
            .sum();
        let locations: f64 = (at.iter().enumerate())
            .map(|(region, &cell)| self.location(region, self.cell(cell)))
            .sum();
        pairs + locations
    }

    /// The part of the energy that depends on the cells of `regions`: their locations and every
    /// pair touching them, a pair between two of them counted once.
    fn local_energy(&self, regions: &[usize], at: &[usize]) -> f64 {
        let mut energy = 0.0;
        for (k, &region) in regions.iter().enumerate() {
            let here = self.cell(at[region]);
            energy += self.location(region, here);
            for &(other, direction) in &self.neighbours[region] {
                if !regions[..k].contains(&other) {
                    energy += self.pair(direction, here, self.cell(at[other]));
                }
            }
        }
        energy
    }
}

/// A change of the assignment.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Move {
    /// Two regions exchange their cells.
    Swap(usize, usize),
    /// A region goes to a free cell (an index into the lattice's cells).
    Shift(usize, usize),
}

impl Move {
    /// The regions whose cells change.
    fn regions(self) -> Vec<usize> {
        match self {
            Move::Swap(a, b) => vec![a, b],
            Move::Shift(region, _) => vec![region],
        }
    }
}

/// Which lattice cell and which region sit at each lattice position.
#[derive(Clone, Copy, Debug, Default)]
struct Slot {
    cell: Option<usize>,
    region: Option<usize>,
}

/// The current assignment and a map of the lattice positions it may use. The map holds only the
/// positions of the pool and of the assigned cells, so its size follows the regions and not the
/// empty space between them (two clusters far apart would otherwise need one slot per cell of
/// their bounding box).
struct Board<'a> {
    lattice: &'a Lattice,
    /// Per region, its index into `lattice.cells`.
    at: Vec<usize>,
    /// Cells with an index below this may be moved to.
    pool: usize,
    slots: FxHashMap<(i32, i32), Slot>,
}

impl<'a> Board<'a> {
    fn new(lattice: &'a Lattice, cells: &[usize], pool: usize) -> Self {
        let mut slots = FxHashMap::default();
        slots.reserve(pool + cells.len());
        for index in (0..pool).chain(cells.iter().copied()) {
            let cell = lattice.cells[index];
            slots.insert(
                (cell.col, cell.row),
                Slot {
                    cell: Some(index),
                    region: None,
                },
            );
        }
        let mut board = Board {
            lattice,
            at: cells.to_vec(),
            pool,
            slots,
        };
        for (region, &index) in cells.iter().enumerate() {
            let slot = board.slot_mut(index);
            assert!(
                slot.region.is_none(),
                "refine: two regions share cell {index}"
            );
            slot.region = Some(region);
        }
        board
    }

    /// The slot at (`col`, `row`), if the map holds that position.
    fn slot(&self, col: i32, row: i32) -> Option<Slot> {
        self.slots.get(&(col, row)).copied()
    }

    /// The slot of lattice cell `index`, which the map always holds.
    fn slot_mut(&mut self, index: usize) -> &mut Slot {
        let cell = self.lattice.cells[index];
        self.slots
            .get_mut(&(cell.col, cell.row))
            .expect("the board holds every cell it was made with")
    }

    /// Draws a proposal; `None` when the drawn position offers nothing (see the module notes).
    fn propose(&self, problem: &Problem, rng: &mut ChaCha8Rng, may_move: bool) -> Option<Move> {
        let region = rng.random_range(0..self.at.len());
        let here = self.lattice.cells[self.at[region]];
        let neighbours = &problem.neighbours[region];
        let (around, reach) = if !neighbours.is_empty() && rng.random_bool(0.5) {
            let (other, _) = neighbours[rng.random_range(0..neighbours.len())];
            (self.lattice.cells[self.at[other]], 1)
        } else {
            (here, 2)
        };
        let (col, row) = offset(rng, around, reach);
        let slot = self.slot(col, row)?;
        match slot.region {
            Some(other) if other != region => Some(Move::Swap(region, other)),
            Some(_) => None,
            None => {
                let index = slot.cell.filter(|&index| index < self.pool)?;
                let near = (col - here.col).abs().max((row - here.row).abs()) <= 2;
                (may_move && near).then_some(Move::Shift(region, index))
            }
        }
    }

    /// Makes the move and returns the move that undoes it.
    fn apply(&mut self, proposal: Move) -> Move {
        match proposal {
            Move::Swap(a, b) => {
                let (cell_a, cell_b) = (self.at[a], self.at[b]);
                self.at[a] = cell_b;
                self.at[b] = cell_a;
                self.slot_mut(cell_b).region = Some(a);
                self.slot_mut(cell_a).region = Some(b);
                proposal
            }
            Move::Shift(region, to) => {
                let from = self.at[region];
                self.slot_mut(from).region = None;
                self.slot_mut(to).region = Some(region);
                self.at[region] = to;
                Move::Shift(region, from)
            }
        }
    }
}

/// A position drawn uniformly among those within Chebyshev distance `reach` of `around`,
/// `around` itself excluded.
fn offset(rng: &mut ChaCha8Rng, around: LatticeCell, reach: i32) -> (i32, i32) {
    let side = 2 * reach + 1;
    let centre = side * side / 2;
    let mut k = rng.random_range(0..side * side - 1);
    if k >= centre {
        k += 1;
    }
    (around.col + k % side - reach, around.row + k / side - reach)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::seq::SliceRandom;

    /// A `cols` × `rows` block of cells of score 2 in reading order, origin (0, rows), with a
    /// frame of `frame` extra cells of score 1 around it (after the block in the list).
    fn lattice(cols: i32, rows: i32, frame: i32) -> Lattice {
        let block = |col: i32, row: i32| (0..cols).contains(&col) && (0..rows).contains(&row);
        let mut cells: Vec<LatticeCell> = (0..rows)
            .flat_map(|row| {
                (0..cols).map(move |col| LatticeCell {
                    col,
                    row,
                    score: 2.0,
                })
            })
            .collect();
        for row in -frame..rows + frame {
            for col in (-frame..cols + frame).filter(|&col| !block(col, row)) {
                cells.push(LatticeCell {
                    col,
                    row,
                    score: 1.0,
                });
            }
        }
        Lattice {
            cell_size: 1.0,
            origin: Coord {
                x: 0.0,
                y: f64::from(rows),
            },
            cells,
        }
    }

    /// Regions whose centroids sit on the centres of the block's cells, in reading order, with
    /// rook adjacency.
    struct Map {
        lattice: Lattice,
        centroids: Vec<Coord<f64>>,
        adjacency: Vec<(usize, usize)>,
    }

    impl Map {
        fn new(cols: i32, rows: i32, frame: i32) -> Self {
            let lattice = lattice(cols, rows, frame);
            let m = (cols * rows) as usize;
            let centroids: Vec<Coord<f64>> = (lattice.cells[..m].iter())
                .map(|c| lattice.centre(c.col, c.row))
                .collect();
            let cols = cols as usize;
            let mut adjacency = Vec::new();
            for i in 0..m {
                if (i + 1) % cols != 0 {
                    adjacency.push((i, i + 1));
                }
                if i + cols < m {
                    adjacency.push((i, i + cols));
                }
            }
            Map {
                lattice,
                centroids,
                adjacency,
            }
        }

        fn layout(&self) -> Layout<'_> {
            Layout {
                adjacency: &self.adjacency,
                centroids: &self.centroids,
                moved: &self.centroids,
                lattice: &self.lattice,
            }
        }
    }

    /// A map whose centroids are jittered off the cell centres and whose assignment is a
    /// random permutation of the block: plenty to improve.
    fn scrambled(cols: i32, rows: i32, seed: u64) -> (Map, Vec<usize>) {
        let mut map = Map::new(cols, rows, 2);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        for c in &mut map.centroids {
            c.x += rng.random_range(-0.3..0.3);
            c.y += rng.random_range(-0.3..0.3);
        }
        let mut cells: Vec<usize> = (0..map.centroids.len()).collect();
        cells.shuffle(&mut rng);
        (map, cells)
    }

    fn energy(layout: &Layout, cells: &[usize]) -> f64 {
        Problem::new(layout, &Params::default()).energy(cells)
    }

    fn distinct(cells: &[usize]) -> bool {
        let mut sorted = cells.to_vec();
        sorted.sort_unstable();
        sorted.windows(2).all(|w| w[0] != w[1])
    }

    #[test]
    fn pair_energy_counts_gap_angle_and_misdirection() {
        let map = Map::new(2, 2, 0);
        let layout = map.layout();
        let problem = Problem::new(&layout, &Params::default());
        let east = Coord { x: 1.0, y: 0.0 };
        let at = |col, row| LatticeCell {
            col,
            row,
            score: 2.0,
        };
        let pair = |to| problem.pair(east, at(0, 0), to);
        assert_eq!(pair(at(1, 0)), 0.0);
        // One row down is south: 90° off, misdirected, but still a neighbour.
        assert!((pair(at(0, 1)) - 1.5).abs() < 1e-12);
        // North-east, diagonal neighbour: 45° is not yet misdirected.
        assert!((pair(at(1, -1)) - 0.5).abs() < 1e-12);
        // Two cells west: apart, 180°, misdirected.
        assert!((pair(at(-2, 0)) - 3.5).abs() < 1e-12);
        // The same pair seen from the other side.
        assert_eq!(problem.pair(-east, at(-2, 0), at(0, 0)), pair(at(-2, 0)));
    }

    #[test]
    fn incremental_deltas_match_full_recomputation() {
        let (map, cells) = scrambled(6, 5, 3);
        let layout = map.layout();
        let problem = Problem::new(&layout, &Params::default());
        let mut board = Board::new(&map.lattice, &cells, 40);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let (mut swaps, mut adjacent_swaps, mut shifts) = (0, 0, 0);
        for _ in 0..3_000 {
            let Some(proposal) = board.propose(&problem, &mut rng, true) else {
                continue;
            };
            let total_before = problem.energy(&board.at);
            let involved = proposal.regions();
            let before = problem.local_energy(&involved, &board.at);
            let from = board.at.clone();
            board.apply(proposal);
            let delta = problem.local_energy(&involved, &board.at) - before;
            assert!((problem.energy(&board.at) - total_before - delta).abs() < 1e-9);
            assert!(distinct(&board.at));
            match proposal {
                Move::Swap(a, b) => {
                    swaps += 1;
                    adjacent_swaps += usize::from(problem.neighbours[a].iter().any(|n| n.0 == b));
                }
                Move::Shift(region, to) => {
                    shifts += 1;
                    let (old, new) = (map.lattice.cells[from[region]], map.lattice.cells[to]);
                    assert!(to < 40 && !from.contains(&to));
                    assert!((old.col - new.col).abs().max((old.row - new.row).abs()) <= 2);
                }
            }
        }
        assert!(swaps > 100 && adjacent_swaps > 50 && shifts > 100);
    }

    #[test]
    fn restores_scrambled_neighbours() {
        let map = Map::new(6, 6, 1);
        let layout = map.layout();
        let mut cells: Vec<usize> = (0..36).collect();
        for (a, b) in [(0, 35), (7, 9), (14, 27), (20, 21), (5, 30)] {
            cells.swap(a, b);
        }
        let refined = refine(&layout, &cells, &Params::default(), 1);
        // Every region back on the cell under its centroid: the only state of energy 0.
        assert_eq!(refined, (0..36).collect::<Vec<_>>());
        assert!(energy(&layout, &cells) > 10.0);
        assert_eq!(energy(&layout, &refined), 0.0);
    }

    #[test]
    fn never_worse_distinct_and_within_the_pool() {
        for (seed, moves, temperature) in [(1, 40_000, 0.5), (2, 60, 5.0), (3, 0, 0.5)] {
            let (map, cells) = scrambled(7, 6, seed);
            let layout = map.layout();
            let params = Params {
                refine_moves: moves,
                refine_temperature: temperature,
                ..Params::default()
            };
            let refined = refine(&layout, &cells, &params, seed);
            assert!(energy(&layout, &refined) <= energy(&layout, &cells));
            assert!(distinct(&refined));
            let pool = (1.3_f64 * 42.0).ceil() as usize;
            assert!(refined.iter().all(|&c| c < pool || cells.contains(&c)));
            if moves == 40_000 {
                // A full run undoes most of a random scramble (from 296 to 31 here; a block in
                // reading order would have 9).
                let (before, after) = (energy(&layout, &cells), energy(&layout, &refined));
                assert!(after < 0.2 * before, "{before} → {after}");
            }
        }
    }

    #[test]
    fn the_tracked_best_energy_is_the_energy_of_the_result() {
        let (map, cells) = scrambled(8, 5, 4);
        let layout = map.layout();
        let params = Params::default();
        let problem = Problem::new(&layout, &params);
        let (best, tracked) = anneal(&problem, &cells, &params, 5);
        assert!((problem.energy(&best) - tracked).abs() < 1e-6);
    }

    #[test]
    fn deterministic_for_a_seed() {
        let (map, cells) = scrambled(6, 6, 5);
        let layout = map.layout();
        let params = Params {
            refine_moves: 5_000,
            ..Params::default()
        };
        let first = refine(&layout, &cells, &params, 11);
        assert_eq!(refine(&layout, &cells, &params, 11), first);
        assert_ne!(first, cells);
    }

    #[test]
    fn nothing_to_do_changes_nothing() {
        let map = Map::new(3, 3, 1);
        let empty = Layout {
            adjacency: &[],
            centroids: &[],
            moved: &[],
            lattice: &map.lattice,
        };
        assert!(refine(&empty, &[], &Params::default(), 1).is_empty());
        let scrambled = [8, 7, 6, 5, 4, 3, 2, 1, 0];
        let still = Params {
            refine_moves: 0,
            ..Params::default()
        };
        assert_eq!(refine(&map.layout(), &scrambled, &still, 1), scrambled);
    }

    #[test]
    fn small_maps_only_swap() {
        let (map, cells) = scrambled(4, 4, 6);
        let layout = map.layout();
        let params = Params::default();
        assert!(cells.len() < params.refine_swap_only_below);
        let refined = refine(&layout, &cells, &params, 7);
        assert!(energy(&layout, &refined) < energy(&layout, &cells));
        let (mut before, mut after) = (cells.clone(), refined.clone());
        before.sort_unstable();
        after.sort_unstable();
        assert_eq!(before, after);
    }
}
