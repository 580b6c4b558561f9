//! Step 4b (method.md §6): regions to cells, one-to-one, minimising the sum of squared distances
//! from the moved centroids to the cell centres (Eq. 9).
//!
//! Two exact solvers, both returning an optimal assignment:
//! - up to [`DENSE_LIMIT`] regions, `lsap` (scipy's shortest-augmenting-path variant of
//!   Jonker–Volgenant) on the dense cost matrix;
//! - beyond, the same shortest-augmenting-path method on a sparse graph (method.md §6: "restrict
//!   each region to its k nearest cells"), made exact by a dual certificate. On the 3,107 US
//!   counties (moved centroids from the real pipeline) the dense solver takes 18 s per call:
//!   the centroids are far denser in the east than the lattice, so almost every augmenting
//!   path crosses the continent, scanning a large share of the rows at O(n) each. The sparse
//!   solver finds the same optimum in about 0.25 s.
//!
//! The sparse graph starts with each region's [`NEAREST`] best cells plus one perfect matching
//! (regions and cells paired in x order), so an augmenting path always exists. "Best" is by
//! reduced cost under prices estimated from the same problem on half of the points and cells,
//! solved the same way (recursively): with squared distances the prices follow a transport
//! potential that an even subsample of both sides shares, and starting from it the candidates
//! already point the long way where densities differ. The halves are every other point and
//! cell along a Z-order curve, which keeps each part of the map's share of both to within one
//! at every scale; random halves left imbalances of about √k in a part of k, whose transport
//! the prices then carried, so the augmenting paths grew with the layer (33,000 regions: 380
//! rows scanned per path against 38 now). When a like problem was solved (the same points on
//! a lattice shifted by part of a cell), its prices start the solver instead ([`Prices`]).
//! When every region has a cell,
//! the duals u, v prove optimality for the full problem if no pair has a negative reduced cost
//! c_ij − u_i − v_j. A lifted R-tree finds each region's most negative cells in O(log n); every
//! region that has some gains them as candidates, gives its cell back and is assigned again.
//! Each round only adds candidates, so this ends, and it ends with the optimum.

use geo::Coord;
use rstar::{primitives::GeomWithData, RTree};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::Tick;

/// Up to this many regions the dense solver is used. Measured on crowded and uniform synthetic
/// cases, the sparse one overtakes it between 300 and 600 regions when densities differ.
const DENSE_LIMIT: usize = 500;

/// Candidate cells per region that the sparse solver starts with.
const NEAREST: usize = 16;

/// Candidate cells a region gains per round when it has negative reduced costs.
const GAINED: usize = 8;

/// Problems smaller than this start from zero prices rather than a coarser problem's.
const COARSEST: usize = 256;

/// Shortest-path searches between two questions to the tick: a few milliseconds on 100,000
/// regions, so that a cancel is heard well within 0.2 s.
const TICK_ROWS: usize = 64;

/// Rounds a solve started from a like problem's prices may take before they are given up.
/// A start from a lattice shifted by part of a cell is a good guess where both problems' cells
/// cover the same ground: on the shared layers, the generated Voronoi layers, islands, river,
/// strip and archipelago, and the US layers at 10⁶ vertices, squares and hexagons, no such
/// solve needs more rounds than this. On a thin country (1,000 regions in a strip 0.7 cells wide) two
/// layouts' cells can cover different stretches of it, the prices beyond the like problem's
/// cells are guesses from its last ones, and each round let the search reach a few cells
/// further: some 75 rounds of every row per solve, 20 s for the layer.
const WARM_ROUNDS: usize = 4;

/// How a solve ended.
enum Run {
    Solved,
    Cancelled,
    OutOfRounds,
}

/// Marks a free row or column.
const NONE: usize = usize::MAX;

/// A 3-d R-tree of cells lifted by their prices (see [`lifted_cells`]).
type LiftedTree = RTree<GeomWithData<[f64; 3], usize>>;

/// The cells' prices at the end of a sparse solve, by the cells' places. They are the transport
/// potential from the points to the cells, which a like problem shares (the same points and a
/// lattice shifted by part of a cell), so they start its solver in place of the coarser
/// problem's prices: on the US counties an assignment so started takes 0.12 s instead of
/// 0.22 s, and finds the same optimum.
#[derive(Clone, Debug)]
pub struct Prices {
    cells: Vec<Coord<f64>>,
    values: Vec<f64>,
}

/// Returns, for every point, the index of its cell: distinct cells minimising the sum of squared
/// distances. `points` and `cells` have the same length. Deterministic.
///
/// The function cannot fail: a distance that is not finite (from non-finite or astronomically
/// large coordinates) costs more than every finite one, so every cost the solvers see is finite,
/// and a complete set of finite costs always has an optimal assignment.
///
/// `tick` hears the share of the work done since it was last called and stops the search (the
/// result is then `None`) when it returns false; it is asked at least every [`TICK_ROWS`]
/// shortest-path searches.
///
/// # Panics
/// If `points` and `cells` differ in length.
pub fn assign(points: &[Coord<f64>], cells: &[Coord<f64>], tick: Tick) -> Option<Vec<usize>> {
    assign_from(points, cells, None, tick).map(|(cell_of, _)| cell_of)
}

/// [`assign`], started from the prices of a like problem when there are some, and returning its
/// own prices for the next (none from the dense solver, under [`DENSE_LIMIT`] points).
pub fn assign_from(
    points: &[Coord<f64>],
    cells: &[Coord<f64>],
    start: Option<&Prices>,
    tick: Tick,
) -> Option<(Vec<usize>, Option<Prices>)> {
    assert_eq!(
        points.len(),
        cells.len(),
        "assign needs as many cells as points"
    );
    let costs = Costs::new(points, cells);
    if points.len() <= DENSE_LIMIT {
        // At most 500², a few milliseconds: asked once.
        let cells = dense(&costs);
        tick(1.0).then_some((cells, None))
    } else {
        // The starting prices only decide how fast the optimum is found, never which it is.
        let start = start.map(|p| interpolated(&p.cells, &p.values, cells));
        let solver = Sparse::solved(&costs, start, tick)?;
        let prices = Prices {
            cells: cells.to_vec(),
            values: solver.v,
        };
        Some((solver.col_of, Some(prices)))
    }
}

/// The squared distances, with non-finite ones replaced by a finite cost above all others.
struct Costs<'a> {
    points: &'a [Coord<f64>],
    cells: &'a [Coord<f64>],
    unusable: f64,
}

impl<'a> Costs<'a> {
    fn new(points: &'a [Coord<f64>], cells: &'a [Coord<f64>]) -> Self {
        // Finite points within `reach` of the origin in x and y are less than 3·reach apart.
        let reach = (points.iter().chain(cells))
            .filter(|&&c| finite(c))
            .map(|c| c.x.abs().max(c.y.abs()))
            .fold(0.0, f64::max);
        Costs {
            points,
            cells,
            unusable: (9.0 * reach * reach + 1.0).min(f64::MAX),
        }
    }

    fn len(&self) -> usize {
        self.points.len()
    }

    fn get(&self, point: usize, cell: usize) -> f64 {
        let (p, c) = (self.points[point], self.cells[cell]);
        let cost = (p.x - c.x).powi(2) + (p.y - c.y).powi(2);
        if cost.is_finite() {
            cost
        } else {
            self.unusable
        }
    }
}

/// The dense solver: `lsap` on the full matrix.
fn dense(costs: &Costs) -> Vec<usize> {
    let n = costs.len();
    let matrix: Vec<f64> = (0..n)
        .flat_map(|i| (0..n).map(move |j| costs.get(i, j)))
        .collect();
    let (rows, cols) = lsap::solve(n, n, &matrix, false)
        .expect("a square matrix of finite costs always has an assignment");
    let mut cell_of = vec![0; n];
    for (row, col) in rows.into_iter().zip(cols) {
        cell_of[row] = col;
    }
    cell_of
}

/// The sparse shortest-augmenting-path solver (see the module notes). Rows are points, columns
/// cells; `u` and `v` are the dual prices that keep every reduced cost of a candidate pair ≥ 0
/// and those of assigned pairs 0.
struct Sparse<'a> {
    costs: &'a Costs<'a>,
    candidates: Vec<Vec<usize>>,
    u: Vec<f64>,
    v: Vec<f64>,
    col_of: Vec<usize>,
    row_of: Vec<usize>,
    /// The cells that are not finite, which the lifted tree cannot hold.
    odd_cells: Vec<usize>,
    search: Search,
}

/// Scratch space of one shortest-path search, reset after each through `touched`.
struct Search {
    dist: Vec<f64>,
    pred: Vec<usize>,
    done: Vec<bool>,
    touched: Vec<usize>,
    finalised: Vec<usize>,
    heap: BinaryHeap<Entry>,
}

/// A column in the search's heap, nearest first.
#[derive(Clone, Copy, PartialEq)]
struct Entry {
    dist: f64,
    col: usize,
}

impl Eq for Entry {}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        // Reversed, so that the max-heap pops the smallest distance; ties by column keep the
        // search deterministic.
        (other.dist.total_cmp(&self.dist)).then(other.col.cmp(&self.col))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl<'a> Sparse<'a> {
    /// Solves the problem, starting from `start` or else from the prices of a coarser one;
    /// `None` when `tick` cancels (see [`assign`]). A start that has not led to the optimum
    /// within [`WARM_ROUNDS`] rounds is given up for the coarser problem's prices.
    fn solved(costs: &'a Costs<'a>, start: Option<Vec<f64>>, tick: Tick) -> Option<Self> {
        let tried = start.is_some();
        if let Some(prices) = start {
            let mut solver = Sparse::new(costs, prices);
            match solver.run(tick, Some(WARM_ROUNDS)) {
                Run::Solved => return Some(solver),
                Run::Cancelled => return None,
                Run::OutOfRounds => {}
            }
        }
        // After a start given up, the work was counted already: only a cancel is heard.
        let quiet = |_: f64| tick(0.0);
        let tick: Tick = if tried { &quiet } else { tick };
        let prices = estimated_prices(costs, tick)?;
        let mut solver = Sparse::new(costs, prices);
        matches!(solver.run(tick, None), Run::Solved).then_some(solver)
    }

    fn new(costs: &'a Costs<'a>, prices: Vec<f64>) -> Self {
        let n = costs.len();
        let odd_cells: Vec<usize> = (0..n).filter(|&j| !finite(costs.cells[j])).collect();
        let (tree, _) = lifted_cells(costs.cells, &prices);
        let mut candidates: Vec<Vec<usize>> = (0..n)
            .map(|row| columns_to_check(costs, &tree, &odd_cells, row, NEAREST))
            .collect();
        // Any perfect matching among the candidates guarantees an augmenting path from every
        // free row; pairing in x order keeps its pairs short where densities agree.
        let by_x = |coords: &[Coord<f64>]| {
            let mut order: Vec<usize> = (0..n).collect();
            order.sort_by(|&a, &b| (coords[a].x.total_cmp(&coords[b].x)).then(a.cmp(&b)));
            order
        };
        for (i, j) in by_x(costs.points).into_iter().zip(by_x(costs.cells)) {
            if !candidates[i].contains(&j) {
                candidates[i].push(j);
            }
        }
        let u = (candidates.iter().enumerate())
            .map(|(i, row)| {
                row.iter()
                    .map(|&j| costs.get(i, j) - prices[j])
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        Sparse {
            costs,
            candidates,
            u,
            v: prices,
            col_of: vec![NONE; n],
            row_of: vec![NONE; n],
            odd_cells,
            search: Search {
                dist: vec![f64::INFINITY; n],
                pred: vec![NONE; n],
                done: vec![false; n],
                touched: Vec::new(),
                finalised: Vec::new(),
                heap: BinaryHeap::new(),
            },
        }
    }

    /// Assigns every row optimally, in at most `rounds` rounds when given. The first round,
    /// which assigns every row, counts as the whole work: the rounds after it are usually few
    /// and short.
    fn run(&mut self, tick: Tick, rounds: Option<usize>) -> Run {
        let n = self.costs.len();
        let mut first = true;
        for _ in 0..rounds.unwrap_or(usize::MAX) {
            let mut searches = 0;
            for row in 0..n {
                if self.col_of[row] == NONE {
                    self.augment(row);
                    searches += 1;
                    if searches % TICK_ROWS == 0
                        && !tick(if first {
                            TICK_ROWS as f64 / n as f64
                        } else {
                            0.0
                        })
                    {
                        return Run::Cancelled;
                    }
                }
            }
            if first && !tick((searches % TICK_ROWS) as f64 / n as f64) {
                // The searches after the last tick complete the share.
                return Run::Cancelled;
            }
            first = false;
            if !self.widen() {
                return Run::Solved;
            }
            if !tick(0.0) {
                return Run::Cancelled;
            }
        }
        Run::OutOfRounds
    }

    fn reduced(&self, row: usize, col: usize) -> f64 {
        self.costs.get(row, col) - self.u[row] - self.v[col]
    }

    /// Assigns the free `start` row by the shortest augmenting path (Dijkstra on reduced
    /// costs), then updates the duals as scipy's solver does.
    fn augment(&mut self, start: usize) {
        self.relax(start, 0.0);
        let (sink, length) = loop {
            let entry = (self.search.heap.pop())
                .expect("the candidates hold a perfect matching, so a free column is reachable");
            let col = entry.col;
            if self.search.done[col] || entry.dist > self.search.dist[col] {
                continue;
            }
            if self.row_of[col] == NONE {
                break (col, entry.dist);
            }
            self.search.done[col] = true;
            self.search.finalised.push(col);
            self.relax(self.row_of[col], entry.dist);
        };
        self.u[start] += length;
        for &col in &self.search.finalised {
            let gain = length - self.search.dist[col];
            self.u[self.row_of[col]] += gain;
            self.v[col] -= gain;
        }
        let mut col = sink;
        loop {
            let row = self.search.pred[col];
            let previous = self.col_of[row];
            self.col_of[row] = col;
            self.row_of[col] = row;
            if row == start {
                break;
            }
            col = previous;
        }
        let search = &mut self.search;
        for &col in &search.touched {
            search.dist[col] = f64::INFINITY;
            search.pred[col] = NONE;
            search.done[col] = false;
        }
        search.touched.clear();
        search.finalised.clear();
        search.heap.clear();
    }

    /// Offers the columns of `row`, reached at path length `base`, to the search.
    fn relax(&mut self, row: usize, base: f64) {
        for k in 0..self.candidates[row].len() {
            let col = self.candidates[row][k];
            if self.search.done[col] {
                continue;
            }
            let dist = base + self.reduced(row, col);
            if dist < self.search.dist[col] {
                if self.search.dist[col] == f64::INFINITY {
                    self.search.touched.push(col);
                }
                self.search.dist[col] = dist;
                self.search.pred[col] = row;
                self.search.heap.push(Entry { dist, col });
            }
        }
    }

    /// Whether no column has a negative reduced cost for `row`, by a ball query on the lifted
    /// `tree` (built with `top`): cell j lies at squared distance c_ij + top − v_j from the
    /// row's point, so the negative ones lie within u_i + top. Most rows have none, and a ball
    /// that holds about one cell is far cheaper than a nearest-neighbour search; `false` sends
    /// the row to that search, which then finds what it always found. The ball is a little
    /// wider than needed, for rounding; the test of each cell in it is [`widen`]'s own.
    fn certified(&self, row: usize, tree: &LiftedTree, top: f64) -> bool {
        let p = self.costs.points[row];
        if !finite(p) {
            return false;
        }
        let reach = self.u[row] + top;
        let radius2 = reach + 1e-9 * (1.0 + reach.abs() + top.abs());
        !(tree.locate_within_distance([p.x, p.y, 0.0], radius2))
            .map(|c| c.data)
            .chain(self.odd_cells.iter().copied())
            .any(|col| self.violated(row, col))
    }

    /// Whether the pair's reduced cost is negative; rounding in the duals must not count as a
    /// violation.
    fn violated(&self, row: usize, col: usize) -> bool {
        self.reduced(row, col) < -1e-9 * (1.0 + self.costs.get(row, col))
    }

    /// Checks the dual certificate over all pairs. Every row with negative reduced costs gains
    /// its [`GAINED`] most negative columns as candidates, is freed, and has its price lowered
    /// so that all its candidates have reduced costs ≥ 0 again. Returns whether any row was.
    fn widen(&mut self) -> bool {
        let (tree, top) = lifted_cells(self.costs.cells, &self.v);
        let mut widened = false;
        for row in 0..self.costs.len() {
            if self.certified(row, &tree, top) {
                continue;
            }
            let columns = columns_to_check(self.costs, &tree, &self.odd_cells, row, GAINED);
            let mut negative: Vec<(f64, usize)> = (columns.into_iter())
                .filter(|&col| self.violated(row, col))
                .map(|col| (self.reduced(row, col), col))
                .collect();
            if negative.is_empty() {
                continue;
            }
            widened = true;
            negative.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            for &(_, col) in negative.iter().take(GAINED) {
                if !self.candidates[row].contains(&col) {
                    self.candidates[row].push(col);
                }
            }
            let col = self.col_of[row];
            self.row_of[col] = NONE;
            self.col_of[row] = NONE;
            self.u[row] = (self.candidates[row].iter())
                .map(|&c| self.costs.get(row, c) - self.v[c])
                .fold(f64::INFINITY, f64::min);
        }
        widened
    }
}

/// Column prices for `costs` from the same problem on half of its points and cells (see the
/// module notes), [`interpolated`] to all of its cells.
fn estimated_prices(costs: &Costs, tick: Tick) -> Option<Vec<f64>> {
    let n = costs.len();
    if n < COARSEST {
        return Some(vec![0.0; n]);
    }
    // Every other point and cell along a Z-order curve over the common box: each quadtree
    // square of the box keeps half its points and half its cells, give or take one, at every
    // scale. An independent random half would leave imbalances of about √k in a square of k,
    // whose transport grows with the layer and makes the prices ever worse guesses.
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for c in costs
        .points
        .iter()
        .chain(costs.cells)
        .filter(|c| finite(**c))
    {
        lo = [lo[0].min(c.x), lo[1].min(c.y)];
        hi = [hi[0].max(c.x), hi[1].max(c.y)];
    }
    let sample = |coords: &[Coord<f64>]| -> Vec<Coord<f64>> {
        let mut keyed: Vec<(u64, usize)> =
            (0..n).map(|k| (z_order(coords[k], lo, hi), k)).collect();
        keyed.sort_unstable();
        keyed
            .iter()
            .step_by(2)
            .take(n / 2)
            .map(|&(_, k)| coords[k])
            .collect()
    };
    let (points, cells) = (sample(costs.points), sample(costs.cells));
    let coarse = Costs::new(&points, &cells);
    // The coarse problem's share of the work is not counted: only a cancel is heard.
    let prices = Sparse::solved(&coarse, None, &|_| tick(0.0))?.v;
    Some(interpolated(&cells, &prices, costs.cells))
}

/// Prices for `cells` from those of the `sampled` cells: each cell takes the value at its place
/// of the least-squares plane through the prices of the [`PLANE_POINTS`] nearest sampled cells,
/// since the potential is smooth and the nearest cell's price alone is off by the potential's
/// slope over the gap (on the US counties the augmenting paths then scan ten times as many
/// rows).
fn interpolated(sampled: &[Coord<f64>], prices: &[f64], cells: &[Coord<f64>]) -> Vec<f64> {
    let tree = RTree::bulk_load(
        (sampled.iter().enumerate())
            .filter(|(_, c)| finite(**c))
            .map(|(k, c)| GeomWithData::new([c.x, c.y], k))
            .collect(),
    );
    (cells.iter())
        .map(|c| {
            if !finite(*c) {
                return 0.0;
            }
            let near: Vec<(Coord<f64>, f64)> = tree
                .nearest_neighbor_iter(&[c.x, c.y])
                .take(PLANE_POINTS)
                .map(|s| {
                    (
                        Coord {
                            x: s.geom()[0] - c.x,
                            y: s.geom()[1] - c.y,
                        },
                        prices[s.data],
                    )
                })
                .collect();
            plane_at_origin(&near).unwrap_or_else(|| near.first().map_or(0.0, |n| n.1))
        })
        .collect()
}

/// Sampled cells a cell's price is interpolated from.
const PLANE_POINTS: usize = 8;

/// The value at the origin of the least-squares plane through `(offset, value)` samples.
fn plane_at_origin(samples: &[(Coord<f64>, f64)]) -> Option<f64> {
    let (mut sxx, mut sxy, mut syy, mut sx, mut sy, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    let (mut sv, mut sxv, mut syv) = (0.0, 0.0, 0.0);
    for &(d, v) in samples {
        sxx += d.x * d.x;
        sxy += d.x * d.y;
        syy += d.y * d.y;
        sx += d.x;
        sy += d.y;
        n += 1.0;
        sv += v;
        sxv += d.x * v;
        syv += d.y * v;
    }
    // Normal equations [n sx sy; sx sxx sxy; sy sxy syy] (a, b, c) = (sv, sxv, syv); a by Cramer.
    let det = n * (sxx * syy - sxy * sxy) - sx * (sx * syy - sxy * sy) + sy * (sx * sxy - sxx * sy);
    let det_a =
        sv * (sxx * syy - sxy * sxy) - sx * (sxv * syy - sxy * syv) + sy * (sxv * sxy - sxx * syv);
    let scale = n * (sxx * syy).max(f64::MIN_POSITIVE);
    (det.abs() > 1e-9 * scale)
        .then(|| det_a / det)
        .filter(|a| a.is_finite())
}

/// The position of `c` along a Z-order (Morton) curve over the box `lo`–`hi`; points that are
/// not finite come last.
fn z_order(c: Coord<f64>, lo: [f64; 2], hi: [f64; 2]) -> u64 {
    if !finite(c) {
        return u64::MAX;
    }
    let scaled = |v: f64, lo: f64, hi: f64| -> u64 {
        let t = if hi > lo { (v - lo) / (hi - lo) } else { 0.0 };
        (t.clamp(0.0, 1.0) * f64::from(u32::MAX)) as u64
    };
    // Spreads the 32 bits of v to the even bits of a u64.
    let spread = |mut v: u64| {
        v = (v | (v << 16)) & 0x0000_FFFF_0000_FFFF;
        v = (v | (v << 8)) & 0x00FF_00FF_00FF_00FF;
        v = (v | (v << 4)) & 0x0F0F_0F0F_0F0F_0F0F;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        (v | (v << 1)) & 0x5555_5555_5555_5555
    };
    spread(scaled(c.x, lo[0], hi[0])) | (spread(scaled(c.y, lo[1], hi[1])) << 1)
}

fn finite(c: Coord<f64>) -> bool {
    c.x.is_finite() && c.y.is_finite()
}

/// The finite cells lifted to 3-d so that Euclidean nearness to a point (x, y, 0) orders them by
/// squared distance minus price v_j, which is the reduced cost up to the row's own price: the
/// cell at (x_j, y_j, sqrt(top − v_j)) is at squared distance |p − c_j|² + top − v_j. Returns
/// the tree and `top`.
fn lifted_cells(cells: &[Coord<f64>], prices: &[f64]) -> (LiftedTree, f64) {
    let top = (cells.iter().zip(prices))
        .filter(|(c, _)| finite(**c))
        .map(|(_, &v)| v)
        .fold(f64::MIN, f64::max);
    let tree = RTree::bulk_load(
        (cells.iter().zip(prices).enumerate())
            .filter(|(_, (c, _))| finite(**c))
            .map(|(j, (c, &v))| GeomWithData::new([c.x, c.y, (top - v).sqrt()], j))
            .collect(),
    );
    (tree, top)
}

/// The columns of `row` worth looking at: its `count` best finite cells by reduced cost from
/// the lifted `tree`, and the cells that are not finite. A point that is not finite costs the
/// same to every cell, so the tree cannot rank them: then every column.
fn columns_to_check(
    costs: &Costs,
    tree: &LiftedTree,
    odd_cells: &[usize],
    row: usize,
    count: usize,
) -> Vec<usize> {
    let p = costs.points[row];
    if !finite(p) {
        return (0..costs.len()).collect();
    }
    (tree.nearest_neighbor_iter(&[p.x, p.y, 0.0]))
        .take(count)
        .map(|c| c.data)
        .chain(odd_cells.iter().copied())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn total(points: &[Coord<f64>], cells: &[Coord<f64>], assignment: &[usize]) -> f64 {
        points
            .iter()
            .zip(assignment)
            .map(|(p, &c)| (p.x - cells[c].x).powi(2) + (p.y - cells[c].y).powi(2))
            .sum()
    }

    fn is_permutation(assignment: &[usize]) -> bool {
        let mut sorted = assignment.to_vec();
        sorted.sort_unstable();
        sorted.into_iter().eq(0..assignment.len())
    }

    /// Every permutation of 0..n, by recursion.
    fn permutations(n: usize) -> Vec<Vec<usize>> {
        if n == 0 {
            return vec![Vec::new()];
        }
        let mut all = Vec::new();
        for shorter in permutations(n - 1) {
            for at in 0..n {
                let mut longer = shorter.clone();
                longer.insert(at, n - 1);
                all.push(longer);
            }
        }
        all
    }

    fn random_points(rng: &mut ChaCha8Rng, n: usize) -> Vec<Coord<f64>> {
        (0..n)
            .map(|_| Coord {
                x: rng.random_range(-5.0..5.0),
                y: rng.random_range(-5.0..5.0),
            })
            .collect()
    }

    /// Cell centres of a lattice about `n` cells wide, and points crowded into one corner of it,
    /// the hard case where optimal pairs are far apart (like the eastern US counties).
    fn crowded(rng: &mut ChaCha8Rng, n: usize) -> (Vec<Coord<f64>>, Vec<Coord<f64>>) {
        let side = (n as f64).sqrt().ceil() as usize;
        let cells = (0..n)
            .map(|k| Coord {
                x: (k % side) as f64,
                y: (k / side) as f64,
            })
            .collect();
        let points = (0..n)
            .map(|k| {
                let spread = if k % 3 == 0 {
                    side as f64
                } else {
                    0.3 * side as f64
                };
                Coord {
                    x: rng.random_range(0.0..spread),
                    y: rng.random_range(0.0..spread),
                }
            })
            .collect();
        (points, cells)
    }

    fn solve(points: &[Coord<f64>], cells: &[Coord<f64>]) -> Vec<usize> {
        assign(points, cells, &|_| true).unwrap()
    }

    #[test]
    fn a_cancel_stops_the_search_and_the_shares_add_up_to_one() {
        let mut rng = ChaCha8Rng::seed_from_u64(10);
        let (points, cells) = crowded(&mut rng, 4 * DENSE_LIMIT);
        let asked = std::sync::atomic::AtomicUsize::new(0);
        let cancelled = assign(&points, &cells, &|_| {
            asked.fetch_add(1, std::sync::atomic::Ordering::Relaxed) < 3
        });
        assert_eq!(cancelled, None);
        assert_eq!(asked.load(std::sync::atomic::Ordering::Relaxed), 4);
        let total = std::sync::Mutex::new(0.0);
        let found = assign(&points, &cells, &|share| {
            *total.lock().unwrap() += share;
            true
        });
        assert!(found.is_some_and(|f| is_permutation(&f)));
        let total = *total.lock().unwrap();
        assert!((total - 1.0).abs() < 1e-9, "{total}");
    }

    fn sparse(points: &[Coord<f64>], cells: &[Coord<f64>]) -> Vec<usize> {
        let costs = Costs::new(points, cells);
        let mut solver = Sparse::new(&costs, vec![0.0; costs.len()]);
        assert!(matches!(solver.run(&|_| true, None), Run::Solved));
        solver.col_of
    }

    #[test]
    fn both_solvers_match_the_brute_force_optimum() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for n in 1..=7 {
            for _ in 0..3 {
                let (points, cells) = (random_points(&mut rng, n), random_points(&mut rng, n));
                let best = (permutations(n).iter())
                    .map(|p| total(&points, &cells, p))
                    .fold(f64::INFINITY, f64::min);
                for found in [solve(&points, &cells), sparse(&points, &cells)] {
                    assert!(is_permutation(&found), "{found:?}");
                    let cost = total(&points, &cells, &found);
                    assert!((cost - best).abs() < 1e-9, "n = {n}: {cost} > {best}");
                }
            }
        }
    }

    #[test]
    fn the_sparse_solver_matches_the_dense_one() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        for n in [20, 150, 400] {
            let uniform = (random_points(&mut rng, n), random_points(&mut rng, n));
            for (points, cells) in [uniform, crowded(&mut rng, n)] {
                let (dense, sparse) = (solve(&points, &cells), sparse(&points, &cells));
                assert!(is_permutation(&sparse));
                let (a, b) = (
                    total(&points, &cells, &dense),
                    total(&points, &cells, &sparse),
                );
                assert!((a - b).abs() < 1e-9 * a, "n = {n}: dense {a}, sparse {b}");
            }
        }
    }

    #[test]
    fn large_inputs_get_an_optimality_certificate() {
        // Above the dense limit, optimality is proven by the duals: every reduced cost ≥ 0 and
        // the duals add up to the cost of the assignment (LP strong duality).
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let (points, cells) = crowded(&mut rng, DENSE_LIMIT + 50);
        let costs = Costs::new(&points, &cells);
        let mut solver = Sparse::new(&costs, vec![0.0; costs.len()]);
        assert!(matches!(solver.run(&|_| true, None), Run::Solved));
        assert_eq!(solve(&points, &cells), solver.col_of);
        assert!(is_permutation(&solver.col_of));
        let cost = total(&points, &cells, &solver.col_of);
        let bound: f64 = solver.u.iter().chain(&solver.v).sum();
        assert!((cost - bound).abs() < 1e-6 * cost, "{cost} against {bound}");
        for i in 0..points.len() {
            for j in 0..cells.len() {
                assert!(solver.reduced(i, j) > -1e-6, "({i}, {j})");
            }
        }
    }

    #[test]
    fn prices_from_a_shifted_lattice_start_the_solver_at_no_cost_to_the_optimum() {
        let mut rng = ChaCha8Rng::seed_from_u64(10);
        let n = DENSE_LIMIT + 300;
        let (points, cells) = crowded(&mut rng, n);
        let (_, prices) = assign_from(&points, &cells, None, &|_| true).expect("not cancelled");
        let prices = prices.expect("the sparse solver gives its prices");
        // The lattice shifted by part of a cell, as a run's other layouts have it.
        let shifted: Vec<Coord<f64>> = (cells.iter())
            .map(|c| Coord {
                x: c.x + 0.33,
                y: c.y + 0.67,
            })
            .collect();
        let (warm, _) =
            assign_from(&points, &shifted, Some(&prices), &|_| true).expect("not cancelled");
        let cold = assign(&points, &shifted, &|_| true).expect("not cancelled");
        assert!(is_permutation(&warm));
        let optimum = total(&points, &shifted, &solve(&points, &shifted));
        let (w, c) = (
            total(&points, &shifted, &warm),
            total(&points, &shifted, &cold),
        );
        assert!(
            (w - optimum).abs() < 1e-9 * optimum,
            "warm {w}, optimum {optimum}"
        );
        assert!(
            (c - optimum).abs() < 1e-9 * optimum,
            "cold {c}, optimum {optimum}"
        );
    }

    #[test]
    fn a_start_that_fails_its_rounds_is_given_up_for_the_optimum() {
        // A country one cell wide: regions in a row, three times as dense in the east as in
        // the west, so that the optimal pairs run up to an eighth of the row apart. The start comes from a row of
        // cells a quarter of the row further east (on a thin strip two layouts' cells can
        // cover different stretches of it), so the prices west of it are guessed from its end.
        let n = 1000;
        let points: Vec<Coord<f64>> = (0..n)
            .map(|k| {
                let t = k as f64 / n as f64;
                Coord {
                    x: n as f64 * (1.5 * t - 0.5 * t * t),
                    y: 0.0,
                }
            })
            .collect();
        let row = |start: f64| -> Vec<Coord<f64>> {
            (0..n)
                .map(|k| Coord {
                    x: start + k as f64,
                    y: 0.0,
                })
                .collect()
        };
        let (east, cells) = (row(0.25 * n as f64), row(0.5));
        let (_, prices) = assign_from(&points, &east, None, &|_| true).expect("not cancelled");
        let prices = prices.expect("the sparse solver gives its prices");
        let start = interpolated(&prices.cells, &prices.values, &cells);
        let costs = Costs::new(&points, &cells);
        assert!(
            matches!(
                Sparse::new(&costs, start).run(&|_| true, Some(WARM_ROUNDS)),
                Run::OutOfRounds
            ),
            "the start was good enough: this test no longer tests giving it up"
        );
        // On a line the optimum with squared distances pairs points and cells in order.
        let (found, _) =
            assign_from(&points, &cells, Some(&prices), &|_| true).expect("not cancelled");
        assert_eq!(found, (0..n).collect::<Vec<_>>());
    }

    #[test]
    fn the_plane_through_samples_gives_its_value_at_the_origin() {
        // v = 3 + 2x - y, sampled around (not at) the origin.
        let at = |x: f64, y: f64| (Coord { x, y }, 3.0 + 2.0 * x - y);
        let samples = [at(1.0, 0.5), at(-0.7, 1.2), at(0.3, -0.9), at(-1.1, -0.4)];
        let value = plane_at_origin(&samples).unwrap();
        assert!((value - 3.0).abs() < 1e-12, "{value}");
        // Collinear samples fix no plane.
        assert_eq!(
            plane_at_origin(&[at(1.0, 1.0), at(2.0, 2.0), at(3.0, 3.0)]),
            None
        );
    }

    #[test]
    fn every_other_point_along_the_z_order_halves_every_quadtree_square() {
        // 64 × 64 random points: each of the 4^k squares of the box at depth k keeps half its
        // points, give or take one (a square is one run of the curve).
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let points: Vec<Coord<f64>> = (0..4096)
            .map(|_| Coord {
                x: rng.random_range(0.0..1.0),
                y: rng.random_range(0.0..1.0),
            })
            .collect();
        let mut keyed: Vec<(u64, usize)> = (points.iter().enumerate())
            .map(|(k, &p)| (z_order(p, [0.0, 0.0], [1.0, 1.0]), k))
            .collect();
        keyed.sort_unstable();
        let kept: Vec<Coord<f64>> = keyed.iter().step_by(2).map(|&(_, k)| points[k]).collect();
        for depth in 1..=4 {
            let side = f64::from(1u32 << depth);
            let square = |p: &Coord<f64>| ((p.x * side) as usize, (p.y * side) as usize);
            let count = |set: &[Coord<f64>], s: (usize, usize)| {
                set.iter().filter(|p| square(p) == s).count() as f64
            };
            for s in points.iter().map(square) {
                let (all, half) = (count(&points, s), count(&kept, s));
                assert!(
                    (half - all / 2.0).abs() <= 1.0,
                    "depth {depth}: {half} of {all}"
                );
            }
        }
        // A point that is not finite comes last.
        let nan = Coord {
            x: f64::NAN,
            y: 0.5,
        };
        assert_eq!(z_order(nan, [0.0, 0.0], [1.0, 1.0]), u64::MAX);
    }

    #[test]
    fn squared_distance_prefers_two_short_moves_to_one_long_one() {
        // Points at 0 and 1, cells at 2 and 1: both assignments move 2 in plain distance, but
        // squared, each point moving by 1 (1 + 1) beats one moving by 2 (4 + 0).
        let at = |x: f64| Coord { x, y: 0.0 };
        assert_eq!(solve(&[at(0.0), at(1.0)], &[at(2.0), at(1.0)]), vec![1, 0]);
    }

    #[test]
    fn a_non_finite_point_still_gets_a_cell() {
        let at = |x: f64| Coord { x, y: 0.0 };
        let (points, cells) = ([at(f64::NAN), at(0.9)], [at(1.0), at(5.0)]);
        assert_eq!(solve(&points, &cells), vec![1, 0]);
        assert_eq!(sparse(&points, &cells), vec![1, 0]);
    }
}
