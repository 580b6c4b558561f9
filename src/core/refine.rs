//! Step 4c (method.md §6b, beyond the paper): a seeded simulated-annealing search that swaps and
//! moves cells to keep neighbours next to each other and in the right direction, regions near
//! their places and on their landmass, and the layout in one piece, without holes or notches.
//!
//! A proposal picks a region at random and a lattice position: half of the time (when the region
//! has neighbours) a position next to the cell of one of its neighbours, so that a region far
//! from its neighbours can jump back in one swap; otherwise a position within 2 cells of its own
//! cell. A region of the same landmass already there swaps cells with it; a free cell of the
//! region's landmass in the pool is moved to, if it is within 2 cells, moves are allowed, and
//! the move keeps the layout's topology (see [`Board::keeps_topology`]); anything else is a
//! wasted proposal (it still counts as a move, so the run time is fixed).
//!
//! The energy change of a proposal is evaluated on the pairs and locations of the one or two
//! regions involved, and for a move on the positions around the two cells, O(degree). The best
//! state seen is recovered at the end by undoing the moves accepted since it, so it is never
//! copied.
//!
//! From 3,000 regions on, one layout is refined (see `Params::refined_count`), which would leave
//! all cores but one idle: the board is then annealed in stripes at once ([`Stripes`]), phase
//! after phase, each stripe keeping its best state.

use super::grid::{Lattice, LatticeCell};
use super::tiling::{Position, Tiling};
use super::Params;
use super::{derived_seed, Tick};
use geo::Coord;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rustc_hash::FxHashMap;
use std::cell::RefCell;

/// What the refinement needs to know of a layout, all in the unit-cell frame.
pub struct Layout<'a> {
    /// Adjacent region pairs (i < j).
    pub adjacency: &'a [(usize, usize)],
    /// The regions' area centroids: the directions to keep (as §8 measures them).
    pub centroids: &'a [Coord<f64>],
    /// Where each region belongs in the lattice's frame: the place its cell should be near.
    pub targets: &'a [Coord<f64>],
    /// The cells the layout may use: each tagged with its landmass (part), the ones beyond the
    /// assigned ones free to move to.
    pub lattice: &'a Lattice,
    /// Per region, its landmass: a region only ever takes a cell of its own.
    pub part_of: &'a [usize],
    /// Which positions would put a region nearer another landmass than its own; `None` when no
    /// region can (fewer than two landmasses count), which spares the refinement a cache lookup
    /// per proposal (a quarter of its time on 10,000 regions).
    pub misplaced: Option<Misplaced<'a>>,
    /// The area of the regions' own holes (lakes), in cells: the layout's holes up to it are the
    /// source's, not defects (method.md §8), as the candidates' ranking counts them.
    pub lakes: u32,
    /// Whether the refinement keeps any region from being left stranded
    /// ([`Problem::stranded`]; how, see [`refine`]). Off with pins.
    pub keep_company: bool,
}

/// Which positions put a region nearer another landmass than its own (method.md §8's
/// wrong-landmass share), asked per landmass and position: the regions of one landmass get one
/// answer, so each position is worked out once per landmass, not once per region that tries it
/// (on a world map at 10⁶ vertices the questions, each a search of a full-resolution coast, were
/// a sixth of the run).
#[derive(Clone, Copy)]
pub struct Misplaced<'a> {
    /// Per region, the landmass it is measured from.
    pub landmass_of: &'a [usize],
    /// Whether a region of landmass `landmass` at a position lies nearer another landmass.
    pub nearer_another: &'a (dyn Fn(usize, Position) -> bool + Sync),
}

impl Layout<'_> {
    /// The squared distance, in cells, from region `region`'s place to the centre of `cell`.
    fn squared_distance(&self, region: usize, cell: LatticeCell) -> f64 {
        let offset = self.targets[region] - self.lattice.centre(cell.col, cell.row);
        let size = self.lattice.cell_size;
        (offset.x * offset.x + offset.y * offset.y) / (size * size)
    }
}

/// Improves `cells` (per region, an index into `layout.lattice.cells`) and returns the new
/// assignment; deterministic for a given `seed`.
///
/// The result never has a higher energy (method.md §6b, weights from `params`) than `cells`,
/// its cells are distinct, its pieces and holes are no more than those of `cells`, and with
/// fewer than `params.refine_swap_only_below` regions it uses exactly the cells of `cells`
/// (only swaps), so the outline keeps its shape.
///
/// `tick` hears the share of the moves made since it was last called, every [`TICK_MOVES`]
/// moves, and stops the refinement (the result is then `None`) when it returns false.
///
/// # Panics
/// If two regions share a cell, or a cell index is outside the lattice.
pub fn refine(
    layout: &Layout,
    cells: &[usize],
    params: &Params,
    seed: u64,
    tick: Tick,
) -> Option<Vec<usize>> {
    if cells.is_empty() {
        // No region to draw a proposal for.
        return Some(Vec::new());
    }
    let links = Links::of(layout, params);
    let far = far_from_home(layout, cells, params);
    let problem = Problem::new(layout, params, &links, &far);
    let stripes = stripe_count(cells.len());
    // Losing every neighbour costs a region with few of them (a capital district, a city
    // enclave) less than the room it frees is worth to the crowd around it, so a free search
    // may send one far off alone (Washington DC beside Arkansas). A small layout is searched
    // freely first and, only if that strands a region, again from the same start refusing every
    // move that strands one: its other layouts stay as they were. A striped layout (thousands of
    // regions) strands some in every search (the US counties: 17 to 23), so it keeps the rule
    // from the start instead of searching twice. Each of a small layout's searches has half of
    // the refinement's share of the progress bar.
    let best = if stripes == 1 {
        let half = |share: f64| tick(share / 2.0);
        let free = anneal(&problem, cells, params, seed, false, &half)?.0;
        let board = Board::new(layout.lattice, &free, layout.lattice.cells.len());
        let strands = |region| problem.stranded(region, &board);
        if layout.keep_company && (0..cells.len()).any(strands) {
            anneal(&problem, cells, params, seed, true, &half)?.0
        } else if tick(0.5) {
            free
        } else {
            return None;
        }
    } else {
        anneal_in_stripes(&problem, cells, params, seed, stripes, tick)?
    };
    // The search tracks its energy as a sum of many deltas; comparing exact totals makes the
    // promise never to return a worse state hold even to the last bit.
    let defects = |at: &[usize]| {
        let positions: Vec<Position> = (at.iter())
            .map(|&k| (layout.lattice.cells[k].col, layout.lattice.cells[k].row))
            .collect();
        let shape = super::metrics::LayoutShape::of(&positions, layout.lattice.tiling);
        shape.pieces() + shape.holes().saturating_sub(layout.lakes) as usize
    };
    let (before, after) = (defects(cells), defects(&best));
    if after < before || (after == before && problem.energy(&best) <= problem.energy(cells)) {
        Some(best)
    } else {
        Some(cells.to_vec())
    }
}

/// Moves between two questions to the tick: well under a millisecond.
const TICK_MOVES: usize = 4096;

/// `atan2(y, x)` for `y ≥ 0`, in [0, π], within 3e-5 rad (0.002°) and exact at every multiple of
/// 45°, where the misdirection threshold lies. The refinement asks it for every pair of every
/// move, and libm's atan2 took a sixth of a run on the US counties; this takes a few
/// multiplications (Abramowitz and Stegun 4.4.49, scaled to be exact at 1).
fn unsigned_angle(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let (a, b) = (y, x.abs());
    if a == 0.0 && b == 0.0 {
        return 0.0;
    }
    let atan = |t: f64| {
        // atan on [0, 1]; the coefficients' sum is atan(1) within 1.2e-5, made exact.
        const C: [f64; 5] = [0.999_866, -0.330_299_5, 0.180_141, -0.085_133, 0.020_835_1];
        let t2 = t * t;
        let p = t * (C[0] + t2 * (C[1] + t2 * (C[2] + t2 * (C[3] + t2 * C[4]))));
        p * (FRAC_PI_4 / (C[0] + C[1] + C[2] + C[3] + C[4]))
    };
    let first_quadrant = if a <= b {
        atan(a / b)
    } else {
        FRAC_PI_2 - atan(b / a)
    };
    if x < 0.0 {
        PI - first_quadrant
    } else {
        first_quadrant
    }
}

/// The share of proposals that are pushes (see [`Board::push`]).
const PUSHES: f64 = 0.25;

/// The refinement's moves for `regions` regions: `refine_moves_per_region` each.
fn moves(params: &Params, regions: usize) -> usize {
    params.refine_moves_per_region.saturating_mul(regions)
}

/// Per region, the distance from its place beyond which it must keep a neighbour beside it
/// ([`Problem::stranded`]) and its cost grows with the square again (`refine_w_far`): where it
/// starts, and at least `refine_location_far` cells. Beyond `refine_location_knee` the cost
/// grows only linearly, so that a region may move a little for its neighbours; without a limit,
/// a region with few neighbours (Kuwait, Palestine on the world map) was sent five cells off to
/// make room for others. A region that starts far (the US counties of the crowded east
/// spread west, 5 cells on average) is held only from going farther: a fixed limit pulled the
/// whole tail back in and broke the outline (shape 0.930 → 0.892).
fn far_from_home(layout: &Layout, cells: &[usize], params: &Params) -> Vec<f64> {
    (cells.iter().enumerate())
        .map(|(region, &k)| {
            let start = layout
                .squared_distance(region, layout.lattice.cells[k])
                .sqrt();
            start.max(params.refine_location_far)
        })
        .collect()
}

/// Runs the annealing from `cells` over the whole board and returns the best state seen and its
/// (tracked) energy.
fn anneal(
    problem: &Problem,
    cells: &[usize],
    params: &Params,
    seed: u64,
    company: bool,
    tick: Tick,
) -> Option<(Vec<usize>, f64)> {
    let lattice = problem.layout.lattice;
    let board = Board::new(lattice, cells, lattice.cells.len());
    let terms = Terms::of(problem, &board);
    let regions: Vec<usize> = (0..cells.len()).collect();
    let search = Search {
        regions: &regions,
        owner: None,
        moves: moves(params, cells.len()),
        schedule: (0.0, 1.0),
        may_move: cells.len() >= params.refine_swap_only_below,
        seed,
        temperature: params.refine_temperature,
        company,
    };
    let energy = problem.energy(cells);
    search.run(problem, board, terms, energy, tick)
}

/// One annealing run: the regions it draws from, the stripe it is confined to, its moves and
/// its share of the temperature schedule.
struct Search<'s> {
    regions: &'s [usize],
    /// The phase's stripes and the one this run owns; `None`: the whole board.
    owner: Option<(&'s Stripes, &'s [Option<usize>], usize)>,
    moves: usize,
    /// The share of the schedule done before this run, and the share it covers.
    schedule: (f64, f64),
    may_move: bool,
    seed: u64,
    /// The temperature at the start of the whole schedule.
    temperature: f64,
    /// Whether moves that leave a region stranded ([`Problem::strands`]) are refused.
    company: bool,
}

impl Search<'_> {
    /// Anneals `board` (whose terms `terms` holds and whose energy is `energy`) and returns the
    /// best state seen and its (tracked) energy.
    fn run(
        &self,
        problem: &Problem,
        mut board: Board,
        mut terms: Terms,
        mut energy: f64,
        tick: Tick,
    ) -> Option<(Vec<usize>, f64)> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut best = energy;
        // Inverses of the moves accepted since the best state, to walk back to it at the end.
        let mut since_best = Vec::new();
        let moves = self.moves;
        let (done_before, span) = self.schedule;
        // Reused by every proposal: a move allocates nothing.
        let mut scope = Scope::default();
        for step in 0..moves {
            if step % TICK_MOVES == TICK_MOVES - 1 && !tick(TICK_MOVES as f64 / moves as f64) {
                return None;
            }
            let temperature =
                self.temperature * (1.0 - (done_before + step as f64 / moves as f64 * span));
            let region = self.regions[rng.random_range(0..self.regions.len())];
            let Some(proposal) = board.propose(problem, &mut rng, region, self.may_move) else {
                continue;
            };
            if !self.owns(proposal, &board) {
                continue;
            }
            problem.fill_scope(proposal, &board, &mut scope);
            let before = problem.kept_energy(&scope, &board, &terms);
            let undo = board.apply(proposal);
            if self.company && problem.strands(&scope, &board, &terms.beyond_limit) {
                board.apply(undo);
                continue;
            }
            let delta = problem.local_energy(&scope, &board, &mut terms.staged) - before;
            let accept = delta <= 0.0
                || (temperature > 0.0 && rng.random::<f64>() < (-delta / temperature).exp());
            if !accept {
                board.apply(undo);
                continue;
            }
            terms.commit(problem, &board);
            energy += delta;
            since_best.push(undo);
            // Gains below rounding noise do not make a new best: they would only be drift.
            if energy < best - 1e-9 {
                best = energy;
                since_best.clear();
            }
        }
        // The moves after the last tick complete the share.
        if !tick((moves % TICK_MOVES) as f64 / moves.max(1) as f64) {
            return None;
        }
        for undo in since_best.into_iter().rev() {
            board.apply(undo);
        }
        Some((board.at, best))
    }

    /// Whether `proposal` stays within this run's stripe: it moves only regions the stripe
    /// owns, onto positions it owns.
    fn owns(&self, proposal: Move, board: &Board) -> bool {
        let Some((stripes, owner, stripe)) = self.owner else {
            return true;
        };
        match proposal {
            Move::Swap(a, b) => owner[a] == Some(stripe) && owner[b] == Some(stripe),
            Move::Chain(chain) => chain.cells().iter().enumerate().all(|(k, &index)| {
                let cell = board.lattice.cells[index];
                let last = k + 1 == chain.len;
                stripes.owner((cell.col, cell.row)) == Some(stripe)
                    && (last
                        || board
                            .region_on(index)
                            .is_some_and(|r| owner[r] == Some(stripe)))
            }),
        }
    }
}

/// Regions per stripe of a refinement that anneals its stripes at once. From this many regions
/// on, one layout is refined (see `Params::refined_count`), in two stripes at least, so that it
/// uses more than one core; below, the board is annealed whole. On us_counties (3,107 regions)
/// one layout in two stripes against two layouts whole, each on a core: 3.4 s against 4.4 s,
/// and over seeds 0–3 the same adjacency (0.799 against 0.798), orientation 24.1° against
/// 24.4°, location 4.63 against 4.61 cells, shape 0.913 against 0.917 (BENCHMARKS.md).
pub(crate) const STRIPE_REGIONS: usize = 3_000;

/// The most stripes, however many the regions: each cut freezes a band of regions for a phase.
const MOST_STRIPES: usize = 8;

/// The phases of a striped refinement: the stripes run across the columns, then across the
/// rows, then both again, shifted by half a stripe, so that every frozen band is free in
/// another phase.
const PHASES: usize = 8;

/// How many stripes the refinement of `regions` regions anneals at once. It follows the regions
/// only, so that the result does not depend on the number of threads.
fn stripe_count(regions: usize) -> usize {
    if regions < STRIPE_REGIONS {
        1
    } else {
        (regions / STRIPE_REGIONS).clamp(2, MOST_STRIPES)
    }
}

/// A phase's split of the lattice into parallel stripes of about equal regions, with a frozen
/// band of two columns (or rows) at each cut. Everything a move reads lies within two
/// positions of the positions it changes, so stripes three apart never see each other's moves:
/// their energy changes add up, and their pieces and holes are kept as one board's are.
struct Stripes {
    across_rows: bool,
    /// The first position of each stripe but the first; the two before it are the band.
    cuts: Vec<i32>,
}

impl Stripes {
    /// The stripes of `phase` for the regions at `positions`.
    fn of(phase: usize, count: usize, positions: &[Position]) -> Stripes {
        let across_rows = phase % 2 == 1;
        let shift = if (phase / 2) % 2 == 1 { 0.5 } else { 0.0 };
        let mut along: Vec<i32> = (positions.iter())
            .map(|p| if across_rows { p.1 } else { p.0 })
            .collect();
        along.sort_unstable();
        let mut cuts: Vec<i32> = (1..=count)
            .map(|j| (j as f64 - shift) / count as f64)
            .filter(|&q| q > 0.0 && q < 1.0)
            .map(|q| along[(q * along.len() as f64) as usize])
            .collect();
        cuts.dedup();
        Stripes { across_rows, cuts }
    }

    fn count(&self) -> usize {
        self.cuts.len() + 1
    }

    /// The stripe that owns position `p`; `None` in a band.
    fn owner(&self, p: Position) -> Option<usize> {
        let x = if self.across_rows { p.1 } else { p.0 };
        let stripe = self.cuts.partition_point(|&cut| cut <= x);
        let in_band = self.cuts.get(stripe).is_some_and(|&cut| x >= cut - 2);
        (!in_band).then_some(stripe)
    }
}

/// The refinement of `cells` in [`PHASES`] phases, each annealing `stripes` stripes of the
/// board at once (their regions only, in their share of the schedule, each from its own seed)
/// and keeping each stripe's best state. A region is frozen for a phase when its cell lies in a
/// band or a neighbour's cell lies in another stripe, so that no pair term is shared. Each
/// stripe anneals a fresh copy of `problem` ([`Problem::fresh`]). The result depends on the
/// seed and the input, not on the threads.
fn anneal_in_stripes(
    problem: &Problem,
    cells: &[usize],
    params: &Params,
    seed: u64,
    stripes: usize,
    tick: Tick,
) -> Option<Vec<usize>> {
    use rayon::prelude::*;
    let lattice = problem.layout.lattice;
    let n = cells.len();
    let position = |index: usize| (lattice.cells[index].col, lattice.cells[index].row);
    let mut at = cells.to_vec();
    let per_phase = moves(params, n) / PHASES;
    for phase in 0..PHASES {
        let positions: Vec<Position> = at.iter().map(|&k| position(k)).collect();
        let split = Stripes::of(phase, stripes, &positions);
        let owner: Vec<Option<usize>> = (0..n)
            .map(|region| {
                let stripe = split.owner(positions[region])?;
                (problem.neighbours(region).iter())
                    .all(|&(other, _)| split.owner(positions[other]).is_none_or(|s| s == stripe))
                    .then_some(stripe)
            })
            .collect();
        let mut owned = vec![Vec::new(); split.count()];
        for (region, stripe) in owner.iter().enumerate() {
            if let Some(stripe) = stripe {
                owned[*stripe].push(region);
            }
        }
        let owned_regions: usize = owned.iter().map(Vec::len).sum();
        let budgets: Vec<usize> = (owned.iter())
            .map(|r| per_phase * r.len() / owned_regions.max(1))
            .collect();
        let total: usize = budgets.iter().sum();
        let board = Board::new(lattice, &at, lattice.cells.len());
        let terms = Terms::of(problem, &board);
        let schedule = (phase as f64 / PHASES as f64, 1.0 / PHASES as f64);
        // A problem per stripe: its cache of landmass answers is for one thread.
        let problems: Vec<Problem> = (0..split.count()).map(|_| problem.fresh()).collect();
        let results = (problems.into_par_iter().enumerate())
            .map(|(stripe, problem)| {
                let (regions, moves) = (&owned[stripe], budgets[stripe]);
                if regions.is_empty() || moves == 0 {
                    return Some(None);
                }
                let search = Search {
                    regions,
                    owner: Some((&split, &owner, stripe)),
                    moves,
                    schedule,
                    may_move: n >= params.refine_swap_only_below,
                    seed: derived_seed(seed, phase as u64 + 1, stripe),
                    temperature: params.refine_temperature,
                    company: problem.layout.keep_company,
                };
                let weight = moves as f64 / total as f64 / PHASES as f64;
                let (best, _) =
                    search.run(&problem, board.clone(), terms.clone(), 0.0, &|share| {
                        tick(share * weight)
                    })?;
                Some(Some(best))
            })
            .collect::<Option<Vec<Option<Vec<usize>>>>>()?;
        for (region, stripe) in owner.iter().enumerate() {
            if let Some(best) = stripe.and_then(|s| results[s].as_ref()) {
                at[region] = best[region];
            }
        }
        if total == 0 && !tick(1.0 / PHASES as f64) {
            return None;
        }
    }
    Some(at)
}

/// The energy of method.md §6b with its weights, and each region's neighbours.
/// The refinement's energy of one adjacent pair (method.md §6b): a lost neighbour, the
/// direction error and a misdirection. Landmass blocks are placed by it too
/// ([`super::landmass::settle`]).
#[derive(Clone)]
pub(crate) struct PairWeights {
    tiling: Tiling,
    adjacent: f64,
    angle: f64,
    misdirected: f64,
}

impl PairWeights {
    pub(crate) fn of(params: &Params) -> PairWeights {
        PairWeights {
            tiling: Tiling::of(params),
            adjacent: params.refine_w_adjacent,
            angle: params.refine_w_angle,
            misdirected: params.refine_w_misdirected,
        }
    }

    /// The energy of an adjacent pair whose original direction is `direction` and whose cells
    /// are at `from` and `to`. Both orders of the pair give the same value.
    pub(crate) fn energy(&self, direction: Coord<f64>, from: Position, to: Position) -> f64 {
        let (dc, dr) = (to.0 - from.0, to.1 - from.1);
        // Squares spelled out: this runs for every pair of every proposal.
        let (x, y, touching) = match self.tiling {
            Tiling::Square => (
                f64::from(dc),
                -f64::from(dr),
                (dc, dr) != (0, 0) && dc.abs() <= 1 && dr.abs() <= 1,
            ),
            tiling => {
                let c = tiling.centre_offset((dc, dr));
                (c.x, c.y, tiling.touching(from, to))
            }
        };
        let cross = direction.x * y - direction.y * x;
        let dot = direction.x * x + direction.y * y;
        // In [0°, 180°]; 0 when the original centroids coincide.
        let angle = unsigned_angle(cross.abs(), dot).to_degrees();
        let mut energy = self.angle * angle / 90.0;
        if !touching {
            energy += self.adjacent;
        }
        if angle > 45.0 {
            energy += self.misdirected;
        }
        energy
    }
}

/// Each region's adjacent regions and the original directions towards them, region after
/// region: those of region `i` are `links[first[i]..first[i + 1]]`. Made once per refinement
/// and shared by its searches.
struct Links {
    links: Vec<(usize, Coord<f64>)>,
    first: Vec<usize>,
    /// Per link, the index of the same pair seen from the other region.
    reverse: Vec<usize>,
    /// Per link, its pair's energy ([`PairWeights::energy`]) for each offset of the other
    /// region's cell within [`TABLE_REACH`] of its own, row by row: the energy depends on the
    /// offset alone, and working it out (an arctangent, two divisions) was most of a proposal.
    /// Empty above [`TABLE_BYTES`].
    energies: Vec<f64>,
    /// The weights the energies are made with, and pairs outside the table worked out with.
    weights: PairWeights,
}

/// The offsets (in columns and rows) for which [`Links`] holds each pair's energy; a pair
/// further apart has it worked out.
const TABLE_REACH: i32 = 2;
const TABLE_SIDE: i32 = 2 * TABLE_REACH + 1;

/// The largest table of pair energies [`Links`] keeps: one that stays in a processor's cache.
/// Read from memory, a look-up costs more than working the energy out: with 100,000 regions (a
/// table of 120 MB) the layout took 48 s against 43 s without; with 10,000 (12 MB, within this
/// machine's 32 MB cache) 3.29 s against 3.35 s.
const TABLE_BYTES: usize = 8 << 20;

impl Links {
    /// The indices of region `region`'s links.
    fn range(&self, region: usize) -> std::ops::Range<usize> {
        self.first[region]..self.first[region + 1]
    }

    /// The regions adjacent to `region`, each with the original direction towards it.
    fn of_region(&self, region: usize) -> &[(usize, Coord<f64>)] {
        &self.links[self.range(region)]
    }

    /// The energy of link `link`'s pair with its cells at `from` and `to`.
    fn energy(&self, link: usize, from: Position, to: Position) -> f64 {
        let (dc, dr) = (to.0 - from.0, to.1 - from.1);
        if dc.abs() <= TABLE_REACH && dr.abs() <= TABLE_REACH && !self.energies.is_empty() {
            let at = (dr + TABLE_REACH) * TABLE_SIDE + dc + TABLE_REACH;
            self.energies[link * (TABLE_SIDE * TABLE_SIDE) as usize + at as usize]
        } else {
            self.weights.energy(self.links[link].1, from, to)
        }
    }

    fn of(layout: &Layout, params: &Params) -> Links {
        let weights = PairWeights::of(params);
        let regions = layout.centroids.len();
        let pairs = || layout.adjacency.iter().filter(|(i, j)| i != j);
        let mut first = vec![0; regions + 1];
        for &(i, j) in pairs() {
            first[i + 1] += 1;
            first[j + 1] += 1;
        }
        for k in 0..regions {
            first[k + 1] += first[k];
        }
        let mut next = first.clone();
        let mut links = vec![(0, Coord::default()); first[regions]];
        let mut reverse = vec![0; first[regions]];
        for &(i, j) in pairs() {
            let direction = layout.centroids[j] - layout.centroids[i];
            let (at_i, at_j) = (next[i], next[j]);
            links[at_i] = (j, direction);
            links[at_j] = (i, -direction);
            reverse[at_i] = at_j;
            reverse[at_j] = at_i;
            next[i] += 1;
            next[j] += 1;
        }
        let offsets: Vec<Position> = (-TABLE_REACH..=TABLE_REACH)
            .flat_map(|dr| (-TABLE_REACH..=TABLE_REACH).map(move |dc| (dc, dr)))
            .collect();
        let energies = if links.len() * offsets.len() * std::mem::size_of::<f64>() <= TABLE_BYTES {
            let weights = &weights;
            (links.iter())
                .flat_map(|&(_, direction)| {
                    (offsets.iter()).map(move |&offset| weights.energy(direction, (0, 0), offset))
                })
                .collect()
        } else {
            Vec::new()
        };
        Links {
            links,
            first,
            reverse,
            energies,
            weights,
        }
    }
}

struct Problem<'a> {
    layout: &'a Layout<'a>,
    /// `refine_w_location`, on distances in cells ([`Problem::placement`]).
    w_location: f64,
    /// `refine_location_knee`, in cells.
    location_knee: f64,
    /// Per region, where the square comes back ([`far_from_home`]), in cells; and `refine_w_far`.
    location_far: &'a [f64],
    w_far: f64,
    w_landmass: f64,
    w_notch: f64,
    links: &'a Links,
    /// [`Layout::misplaced`], asked once per landmass and position.
    misplaced: RefCell<FxHashMap<(usize, Position), bool>>,
}

impl<'a> Problem<'a> {
    /// The problem of refining `layout`, a region's distance costing more with the square
    /// beyond `far` cells ([`far_from_home`]).
    fn new(layout: &'a Layout<'a>, params: &Params, links: &'a Links, far: &'a [f64]) -> Self {
        Problem {
            layout,
            w_location: params.refine_w_location,
            location_knee: params.refine_location_knee,
            location_far: far,
            w_far: params.refine_w_far,
            w_landmass: params.refine_w_landmass,
            w_notch: params.refine_w_notch,
            links,
            misplaced: RefCell::default(),
        }
    }

    /// The same problem with its cache of landmass answers empty, for another thread.
    fn fresh(&self) -> Problem<'a> {
        Problem {
            misplaced: RefCell::default(),
            ..*self
        }
    }

    /// The regions adjacent to `region`, each with the original direction towards it.
    fn neighbours(&self, region: usize) -> &[(usize, Coord<f64>)] {
        self.links.of_region(region)
    }

    fn cell(&self, index: usize) -> LatticeCell {
        self.layout.lattice.cells[index]
    }

    fn tiling(&self) -> Tiling {
        self.layout.lattice.tiling
    }

    /// The energy of an adjacent pair whose original direction is `direction` and whose cells
    /// are `from` and `to`.
    fn pair(&self, direction: Coord<f64>, from: LatticeCell, to: LatticeCell) -> f64 {
        (self.links.weights).energy(direction, (from.col, from.row), (to.col, to.row))
    }

    /// What region `region` costs on `cell` by itself: its distance from its place, and being
    /// nearer another landmass than its own.
    fn placement(&self, region: usize, cell: LatticeCell) -> f64 {
        let position = (cell.col, cell.row);
        let misplaced = self.layout.misplaced.is_some_and(|misplaced| {
            let landmass = misplaced.landmass_of[region];
            *self
                .misplaced
                .borrow_mut()
                .entry((landmass, position))
                .or_insert_with(|| (misplaced.nearer_another)(landmass, position))
        });
        // The squared distance in cells, and beyond the knee the tangent line of the square,
        // which grows with the distance itself (a Huber cost).
        let squared = self.layout.squared_distance(region, cell);
        let knee = self.location_knee;
        let distance_cost = if squared <= knee * knee {
            squared
        } else {
            knee * (2.0 * squared.sqrt() - knee)
        };
        self.w_location * distance_cost
            + self.far_cost(region, squared)
            + if misplaced { self.w_landmass } else { 0.0 }
    }

    /// What region `region`, `squared` cells² from its place, pays beyond its limit
    /// ([`far_from_home`]); with `refine_w_far` at 0, the default, nothing is looked up.
    fn far_cost(&self, region: usize, squared: f64) -> f64 {
        if self.w_far == 0.0 {
            return 0.0;
        }
        let far = self.location_far[region];
        if squared <= far * far {
            return 0.0;
        }
        self.w_far * (squared.sqrt() - far).powi(2)
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
        let placements: f64 = (at.iter().enumerate())
            .map(|(region, &cell)| self.placement(region, self.cell(cell)))
            .sum();
        let occupied: std::collections::HashSet<Position> = at
            .iter()
            .map(|&k| (self.cell(k).col, self.cell(k).row))
            .collect();
        let empty_sides: std::collections::HashSet<Position> = (occupied.iter())
            .flat_map(|&p| self.tiling().edge_neighbours(p).to_vec())
            .filter(|p| !occupied.contains(p))
            .collect();
        let notches = (empty_sides.iter())
            .filter(|&&p| is_notch(self.tiling(), p, |q| occupied.contains(&q)))
            .count();
        pairs + placements + self.w_notch * notches as f64
    }

    /// Sets `scope` to what a move changes: the regions it moves, and for a chain the positions
    /// whose notches it may change (its two ends and their sides).
    fn fill_scope(&self, proposal: Move, board: &Board, scope: &mut Scope) {
        scope.regions.clear();
        scope.around.clear();
        match proposal {
            Move::Swap(a, b) => scope.regions.extend([a, b]),
            Move::Chain(chain) => {
                let cells = chain.cells();
                for &k in [cells[0], cells[cells.len() - 1]].iter() {
                    let p = (self.cell(k).col, self.cell(k).row);
                    scope.around.push(p);
                    scope.around.extend(self.tiling().edge_neighbours(p).iter());
                }
                scope.around.sort_unstable();
                scope.around.dedup();
                (scope.regions)
                    .extend((cells[..cells.len() - 1].iter()).filter_map(|&k| board.region_on(k)));
            }
        }
    }

    /// The part of the energy within `scope`, on `board` as it is: the placements and every pair
    /// of the regions, a pair between two of them counted once, and the notches among the
    /// positions. Each placement and pair term is also put in `staged`, for [`Terms::commit`].
    fn local_energy(&self, scope: &Scope, board: &Board, staged: &mut Staged) -> f64 {
        staged.placements.clear();
        staged.pairs.clear();
        let mut energy = 0.0;
        for (k, &region) in scope.regions.iter().enumerate() {
            let here = self.cell(board.at[region]);
            let placement = self.placement(region, here);
            staged.placements.push((region, placement));
            energy += placement;
            for link in self.links.range(region) {
                let other = self.links.links[link].0;
                if !scope.regions[..k].contains(&other) {
                    let there = self.cell(board.at[other]);
                    let pair =
                        (self.links).energy(link, (here.col, here.row), (there.col, there.row));
                    staged.pairs.push((link, pair));
                    energy += pair;
                }
            }
        }
        energy + self.notch_energy(scope, board)
    }

    /// [`Problem::local_energy`] on the board whose terms `terms` holds, summed in the same
    /// order from the kept terms, so that it is the same to the bit.
    fn kept_energy(&self, scope: &Scope, board: &Board, terms: &Terms) -> f64 {
        let mut energy = 0.0;
        for (k, &region) in scope.regions.iter().enumerate() {
            energy += terms.placements[region];
            for link in self.links.range(region) {
                if !scope.regions[..k].contains(&self.links.links[link].0) {
                    energy += terms.pairs[link];
                }
            }
        }
        energy + self.notch_energy(scope, board)
    }

    /// Whether `board` leaves a region of `scope` (the regions the move moved), or one adjacent
    /// to one of them, stranded: beyond its limit from home ([`far_from_home`]) with none of its
    /// neighbours touching it. `beyond_limit` holds, per region, whether it was beyond its limit
    /// before the move: a neighbour that did not move has not come nearer or gone farther, and
    /// most are well within theirs, so their distances are read, not measured again (this
    /// check runs for every proposal, a tenth of a us_counties run when it measured them all).
    fn strands(&self, scope: &Scope, board: &Board, beyond_limit: &[bool]) -> bool {
        (scope.regions.iter()).any(|&region| {
            self.stranded(region, board)
                || (self.neighbours(region).iter()).any(|&(other, _)| {
                    beyond_limit[other]
                        && !scope.regions.contains(&other)
                        && self.alone(other, board)
                })
        })
    }

    /// Whether `region` is stranded on `board`: beyond its limit from home ([`far_from_home`])
    /// with none of its neighbours touching it.
    fn stranded(&self, region: usize, board: &Board) -> bool {
        self.beyond_limit(region, self.cell(board.at[region])) && self.alone(region, board)
    }

    /// Whether `region` on `cell` lies beyond its limit from home ([`far_from_home`]).
    fn beyond_limit(&self, region: usize, cell: LatticeCell) -> bool {
        let far = self.location_far[region];
        self.layout.squared_distance(region, cell) > far * far
    }

    /// Whether `region` has neighbours and none of them touches it on `board`.
    fn alone(&self, region: usize, board: &Board) -> bool {
        let links = self.links.range(region);
        if links.is_empty() {
            return false;
        }
        let here = self.cell(board.at[region]);
        let p = (here.col, here.row);
        !links.into_iter().any(|link| {
            let there = self.cell(board.at[self.links.links[link].0]);
            self.tiling().touching(p, (there.col, there.row))
        })
    }

    /// The notches among `scope`'s positions, weighted.
    fn notch_energy(&self, scope: &Scope, board: &Board) -> f64 {
        let notches = (scope.around.iter())
            .filter(|&&p| !board.occupied(p) && is_notch(self.tiling(), p, |q| board.occupied(q)))
            .count();
        self.w_notch * notches as f64
    }
}

/// Every placement and pair term of the current assignment, so that a proposal's energy before
/// it is read, not computed again: most proposals are turned down, and computing both sides
/// was most of a refinement.
#[derive(Clone)]
struct Terms {
    /// Per region.
    placements: Vec<f64>,
    /// Per link of [`Problem::links`] (a pair is held under both its links).
    pairs: Vec<f64>,
    /// Per region, whether it lies beyond its limit from home ([`Problem::beyond_limit`]).
    beyond_limit: Vec<bool>,
    /// The terms of the proposal last evaluated, which become current if it is accepted.
    staged: Staged,
}

/// The terms [`Problem::local_energy`] computed: (region, placement) and (link, pair).
#[derive(Clone, Default)]
struct Staged {
    placements: Vec<(usize, f64)>,
    pairs: Vec<(usize, f64)>,
}

impl Terms {
    fn of(problem: &Problem, board: &Board) -> Terms {
        let cell = |region: usize| problem.cell(board.at[region]);
        Terms {
            placements: (0..board.at.len())
                .map(|region| problem.placement(region, cell(region)))
                .collect(),
            pairs: (0..board.at.len())
                .flat_map(|region| {
                    (problem.neighbours(region).iter()).map(move |&(other, direction)| {
                        problem.pair(direction, cell(region), cell(other))
                    })
                })
                .collect(),
            beyond_limit: (0..board.at.len())
                .map(|region| problem.beyond_limit(region, cell(region)))
                .collect(),
            staged: Staged::default(),
        }
    }

    /// Makes the staged terms current: the proposal they were computed for was accepted, and
    /// `board` is the board it made.
    fn commit(&mut self, problem: &Problem, board: &Board) {
        for &(region, placement) in &self.staged.placements {
            self.placements[region] = placement;
            self.beyond_limit[region] =
                problem.beyond_limit(region, problem.cell(board.at[region]));
        }
        for &(link, pair) in &self.staged.pairs {
            self.pairs[link] = pair;
            self.pairs[problem.links.reverse[link]] = pair;
        }
    }
}

/// The regions and positions a move touches.
#[derive(Default)]
struct Scope {
    regions: Vec<usize>,
    around: Vec<Position>,
}

/// Whether the empty position `p` is a notch: at most one of its sides free (method.md §8).
fn is_notch(tiling: Tiling, p: Position, occupied: impl Fn(Position) -> bool) -> bool {
    let sides = tiling.edge_neighbours(p);
    sides.iter().filter(|&&q| occupied(q)).count() + 1 >= sides.len()
}

/// The longest chain a push moves along (regions pushed in a row, plus the free cell at the end).
const LONGEST_CHAIN: usize = 6;

/// A change of the assignment.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Move {
    /// Two regions exchange their cells.
    Swap(usize, usize),
    /// Cells (indices into the lattice's cells) along a straight line, the last one free: each
    /// region moves one cell along, so the first cell is freed. A plain shift is a chain of two.
    Chain(Chain),
}

/// The cells of a [`Move::Chain`].
#[derive(Clone, Copy, Debug, PartialEq)]
struct Chain {
    cells: [usize; LONGEST_CHAIN + 1],
    len: usize,
}

impl Chain {
    fn new(cells: &[usize]) -> Chain {
        let mut chain = Chain {
            cells: [0; LONGEST_CHAIN + 1],
            len: cells.len(),
        };
        chain.cells[..cells.len()].copy_from_slice(cells);
        chain
    }

    fn cells(&self) -> &[usize] {
        &self.cells[..self.len]
    }

    fn push(&mut self, cell: usize) {
        self.cells[self.len] = cell;
        self.len += 1;
    }

    /// The chain that undoes this one once it is made.
    fn reversed(&self) -> Chain {
        let mut cells = self.cells;
        cells[..self.len].reverse();
        Chain {
            cells,
            len: self.len,
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
#[derive(Clone)]
struct Board<'a> {
    lattice: &'a Lattice,
    /// Per region, its index into `lattice.cells`.
    at: Vec<usize>,
    /// Cells with an index below this may be moved to.
    pool: usize,
    slots: FxHashMap<Position, Slot>,
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

    /// The slot at `p`, if the map holds that position.
    fn slot(&self, p: Position) -> Option<Slot> {
        self.slots.get(&p).copied()
    }

    /// Whether a region sits at `p`.
    fn occupied(&self, p: Position) -> bool {
        self.slots.get(&p).is_some_and(|s| s.region.is_some())
    }

    /// The slot of lattice cell `index`, which the map always holds.
    fn slot_mut(&mut self, index: usize) -> &mut Slot {
        let cell = self.lattice.cells[index];
        self.slots
            .get_mut(&(cell.col, cell.row))
            .expect("the board holds every cell it was made with")
    }

    /// Whether moving the region at `from` to the free position `to` keeps the layout's pieces
    /// and holes or improves them: giving up `from` must split no piece and leave no hole (a
    /// lone cell may leave: a piece fewer), and taking `to` (with `from` given up) must join no
    /// two groups and close off no empty space, or fill a one-cell hole (a hole fewer).
    fn keeps_topology(&self, from: Position, to: Position) -> bool {
        let tiling = self.lattice.tiling;
        let before = tiling.around(from, |p| self.occupied(p));
        let leaves = before.cells <= 1 && before.empty >= 1;
        let after = tiling.around(to, |p| p != from && self.occupied(p));
        let arrives = after.cells == 1 && after.empty <= 1;
        leaves && arrives
    }

    /// The region on lattice cell `index`, if any.
    fn region_on(&self, index: usize) -> Option<usize> {
        let cell = self.lattice.cells[index];
        self.slot((cell.col, cell.row))?.region
    }

    /// Draws a proposal for `region`; `None` when the drawn position offers nothing (see the
    /// module notes).
    fn propose(
        &self,
        problem: &Problem,
        rng: &mut ChaCha8Rng,
        region: usize,
        may_move: bool,
    ) -> Option<Move> {
        let here = self.lattice.cells[self.at[region]];
        if may_move && rng.random_bool(PUSHES) {
            let sides = self.lattice.tiling.sides().len();
            return self.push(problem, region, rng.random_range(0..sides));
        }
        let neighbours = problem.neighbours(region);
        let (col, row) = if !neighbours.is_empty() && rng.random_bool(0.5) {
            let (other, direction) = neighbours[rng.random_range(0..neighbours.len())];
            let there = self.lattice.cells[self.at[other]];
            if rng.random_bool(0.5) {
                // The position beside the neighbour in the direction the region lies from it.
                let (dc, dr) = self.lattice.tiling.step_towards(-direction);
                (there.col + dc, there.row + dr)
            } else {
                offset(rng, self.lattice.tiling, there, 1)
            }
        } else {
            offset(rng, self.lattice.tiling, here, 2)
        };
        let slot = self.slot((col, row))?;
        let part_of = problem.layout.part_of;
        match slot.region {
            Some(other) if other != region && part_of[other] == part_of[region] => {
                Some(Move::Swap(region, other))
            }
            Some(_) => None,
            None => {
                let index = slot.cell.filter(|&index| index < self.pool)?;
                let near = (self.lattice.tiling).distance((col, row), (here.col, here.row)) <= 2;
                let own = self.lattice.cells[index].part == part_of[region];
                (may_move && near && own && self.keeps_topology((here.col, here.row), (col, row)))
                    .then_some(Move::Chain(Chain::new(&[self.at[region], index])))
            }
        }
    }

    /// A push of `region` one cell in `direction` (an index of the edge neighbours): the regions
    /// in a straight line ahead of it each move one cell on, the last into a free cell of the
    /// pool. All must be of one landmass, and the layout's topology must hold.
    fn push(&self, problem: &Problem, region: usize, direction: usize) -> Option<Move> {
        let part = problem.layout.part_of[region];
        let start = self.lattice.cells[self.at[region]];
        let mut chain = Chain::new(&[self.at[region]]);
        let mut p = (start.col, start.row);
        for _ in 0..LONGEST_CHAIN {
            p = self.lattice.tiling.edge_neighbours(p)[direction];
            let slot = self.slot(p)?;
            let index = slot.cell?;
            match slot.region {
                Some(other) if problem.layout.part_of[other] == part => chain.push(index),
                Some(_) => return None,
                None => {
                    let own = index < self.pool && self.lattice.cells[index].part == part;
                    chain.push(index);
                    return (own && self.keeps_topology((start.col, start.row), p))
                        .then_some(Move::Chain(chain));
                }
            }
        }
        None
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
            Move::Chain(chain) => {
                let cells = chain.cells();
                for k in (0..cells.len() - 1).rev() {
                    let region = self
                        .region_on(cells[k])
                        .expect("every cell of a chain but its end holds a region");
                    self.slot_mut(cells[k]).region = None;
                    self.slot_mut(cells[k + 1]).region = Some(region);
                    self.at[region] = cells[k + 1];
                }
                Move::Chain(chain.reversed())
            }
        }
    }
}

/// A position drawn uniformly among those within `reach` steps of `around` (Chebyshev
/// distance for squares, hexagonal distance for hexagons), `around` itself excluded.
fn offset(rng: &mut ChaCha8Rng, tiling: Tiling, around: LatticeCell, reach: i32) -> Position {
    if tiling != Tiling::Square {
        // Axial offsets within the square of side 2·reach + 1 that lie within `reach` steps:
        // drawn from that square until one does (3·reach·(reach + 1) of its cells).
        loop {
            let d = (
                rng.random_range(-reach..=reach),
                rng.random_range(-reach..=reach),
            );
            if d != (0, 0) && tiling.distance(d, (0, 0)) <= reach {
                return (around.col + d.0, around.row + d.1);
            }
        }
    }
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
                    part: 0,
                })
            })
            .collect();
        for row in -frame..rows + frame {
            for col in (-frame..cols + frame).filter(|&col| !block(col, row)) {
                cells.push(LatticeCell {
                    col,
                    row,
                    score: 1.0,
                    part: 0,
                });
            }
        }
        Lattice {
            tiling: Tiling::Square,
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
        part_of: Vec<usize>,
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
                part_of: vec![0; m],
            }
        }

        fn layout(&self) -> Layout<'_> {
            Layout {
                adjacency: &self.adjacency,
                centroids: &self.centroids,
                targets: &self.centroids,
                lattice: &self.lattice,
                part_of: &self.part_of,
                misplaced: None,
                lakes: 0,
                keep_company: true,
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

    /// The energy of `cells` as a refinement from `start` with the defaults weighs it.
    fn energy(layout: &Layout, start: &[usize], cells: &[usize]) -> f64 {
        let params = Params::default();
        let far = far_from_home(layout, start, &params);
        Problem::new(layout, &params, &Links::of(layout, &params), &far).energy(cells)
    }

    /// Pieces and holes of the layout `at`, as the metrics count them.
    fn shape(lattice: &Lattice, at: &[usize]) -> (usize, u32) {
        let cells: Vec<Position> = at
            .iter()
            .map(|&k| (lattice.cells[k].col, lattice.cells[k].row))
            .collect();
        let shape = crate::core::metrics::LayoutShape::of(&cells, Tiling::Square);
        (shape.pieces(), shape.holes())
    }

    fn distinct(cells: &[usize]) -> bool {
        let mut sorted = cells.to_vec();
        sorted.sort_unstable();
        sorted.windows(2).all(|w| w[0] != w[1])
    }

    #[test]
    fn the_unsigned_angle_is_atan2_within_its_bound() {
        for k in 0..=2000 {
            let theta = std::f64::consts::PI * f64::from(k) / 2000.0;
            for r in [1e-3, 1.0, 7.0] {
                let (y, x) = (r * theta.sin(), r * theta.cos());
                let error = (unsigned_angle(y.abs(), x) - y.abs().atan2(x)).abs();
                assert!(error < 3e-5, "{theta}: {error}");
            }
        }
        // Exact where the misdirection threshold and the lattice's directions lie.
        assert_eq!(unsigned_angle(1.0, 1.0), std::f64::consts::FRAC_PI_4);
        assert_eq!(unsigned_angle(1.0, 0.0), std::f64::consts::FRAC_PI_2);
        assert_eq!(unsigned_angle(0.0, -2.0), std::f64::consts::PI);
        assert_eq!(unsigned_angle(0.0, 0.0), 0.0);
    }

    #[test]
    fn pair_energy_counts_gap_angle_and_misdirection() {
        let map = Map::new(2, 2, 0);
        let layout = map.layout();
        let links = Links::of(&layout, &Params::default());
        let no_limit = vec![f64::INFINITY; layout.targets.len()];
        let problem = Problem::new(&layout, &Params::default(), &links, &no_limit);
        let east = Coord { x: 1.0, y: 0.0 };
        let at = |col, row| LatticeCell {
            col,
            row,
            score: 2.0,
            part: 0,
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
    fn the_links_table_holds_each_pairs_energy_to_the_bit() {
        // Every link of a jittered map, for squares and both hexagons, at offsets within the
        // table and beyond it, from cells anywhere (the energy depends on the offset alone).
        let (map, _) = scrambled(5, 4, 3);
        let layout = map.layout();
        for (cell, orientation) in [("square", "pointy"), ("hex", "pointy"), ("hex", "flat")] {
            let mut params = Params::default();
            params.set("cell", cell).unwrap();
            params.set("hex_orientation", orientation).unwrap();
            let (links, weights) = (Links::of(&layout, &params), PairWeights::of(&params));
            assert!(!links.links.is_empty());
            for (link, &(_, direction)) in links.links.iter().enumerate() {
                for dc in -4..=4 {
                    for dr in -4..=4 {
                        let (from, to) = ((7, -3), (7 + dc, -3 + dr));
                        assert_eq!(
                            links.energy(link, from, to).to_bits(),
                            weights.energy(direction, from, to).to_bits(),
                            "{cell}, link {link}, offset ({dc}, {dr})"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn the_distance_cost_is_squared_within_the_knee_and_linear_beyond() {
        // Region 0 belongs at cell (0, 0); cells are 1 apart (hand-computed costs).
        let map = Map::new(4, 4, 0);
        let layout = map.layout();
        let links = Links::of(&layout, &Params::default());
        let no_limit = vec![f64::INFINITY; layout.targets.len()];
        let cost = |knee: f64, col: i32, row: i32| {
            let params = Params {
                refine_location_knee: knee,
                ..Params::default()
            };
            let problem = Problem::new(&layout, &params, &links, &no_limit);
            let cell = LatticeCell {
                col,
                row,
                score: 2.0,
                part: 0,
            };
            problem.placement(0, cell) / params.refine_w_location
        };
        assert_eq!(cost(1.0, 0, 0), 0.0);
        // Up to the knee, the square; both forms meet there.
        assert!((cost(1.0, 1, 0) - 1.0).abs() < 1e-12);
        assert!((cost(2.0, 1, 1) - 2.0).abs() < 1e-12);
        // Beyond it, k·(2d − k): 3 cells away, 5 with a knee of 1 (9 squared), 8 with 2.
        assert!((cost(1.0, 3, 0) - 5.0).abs() < 1e-12);
        assert!((cost(2.0, 3, 0) - 8.0).abs() < 1e-12);
        assert!((cost(1000.0, 3, 0) - 9.0).abs() < 1e-12);
        assert!((cost(1.0, 1, 1) - (2.0 * 2f64.sqrt() - 1.0)).abs() < 1e-12);
    }

    #[test]
    fn a_region_pays_the_square_beyond_where_it_started() {
        // Region 0 belongs at cell (0, 0) and starts on (3, 0), region 3 the other way round;
        // the others start on their own cells.
        let map = Map::new(4, 4, 0);
        let layout = map.layout();
        let links = Links::of(&layout, &Params::default());
        let mut start: Vec<usize> = (0..16).collect();
        start.swap(0, 3);
        let params = Params {
            refine_w_far: 1.0,
            refine_location_far: 2.0,
            ..Params::default()
        };
        let far = far_from_home(&layout, &start, &params);
        // Where each started, or 2 cells for the regions that started nearer.
        assert!((far[0] - 3.0).abs() < 1e-12 && (far[3] - 3.0).abs() < 1e-12);
        assert!((far.iter().enumerate()).all(|(i, &f)| i == 0 || i == 3 || f == 2.0));
        let problem = Problem::new(&layout, &params, &links, &far);
        let on = |col, row| LatticeCell {
            col,
            row,
            score: 2.0,
            part: 0,
        };
        let linear = |d: f64| params.refine_w_location * (2.0 * d - 1.0);
        // Region 0 where it started, 3 cells off: nothing more; on (3, 3), √18 cells off:
        // (√18 − 3)² more. Region 4, at (0, 1), 3 cells off on (3, 1): (3 − 2)² more.
        assert!((problem.placement(0, on(3, 0)) - linear(3.0)).abs() < 1e-12);
        let farther = problem.placement(0, on(3, 3)) - linear(18f64.sqrt());
        assert!((farther - (18f64.sqrt() - 3.0).powi(2)).abs() < 1e-12);
        assert!((problem.placement(4, on(3, 1)) - (linear(3.0) + 1.0)).abs() < 1e-12);
    }

    #[test]
    fn incremental_deltas_match_full_recomputation() {
        let (map, cells) = scrambled(6, 5, 3);
        let layout = map.layout();
        let links = Links::of(&layout, &Params::default());
        // A limit from home that many moves cross, so that the company rule's kept flags
        // change; without refine_w_far it costs nothing.
        let limit = vec![3.0; layout.targets.len()];
        let problem = Problem::new(&layout, &Params::default(), &links, &limit);
        let pool = map.lattice.cells.len();
        let mut board = Board::new(&map.lattice, &cells, pool);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let (mut swaps, mut adjacent_swaps, mut shifts) = (0, 0, 0);
        let mut strands = [0, 0];
        let mut terms = Terms::of(&problem, &board);
        for _ in 0..3_000 {
            let region = rng.random_range(0..cells.len());
            let Some(proposal) = board.propose(&problem, &mut rng, region, true) else {
                continue;
            };
            let total_before = problem.energy(&board.at);
            let shape_before = shape(&map.lattice, &board.at);
            let mut scope = Scope::default();
            problem.fill_scope(proposal, &board, &mut scope);
            let mut staged = Staged::default();
            let before = problem.local_energy(&scope, &board, &mut staged);
            // The kept terms give the same energy to the bit.
            assert_eq!(problem.kept_energy(&scope, &board, &terms), before);
            let from = board.at.clone();
            board.apply(proposal);
            // The company rule from the kept flags is the rule measured afresh.
            let measured = (scope.regions.iter()).any(|&region| {
                problem.stranded(region, &board)
                    || (problem.neighbours(region).iter())
                        .any(|&(other, _)| problem.stranded(other, &board))
            });
            assert_eq!(
                problem.strands(&scope, &board, &terms.beyond_limit),
                measured
            );
            strands[usize::from(measured)] += 1;
            let delta = problem.local_energy(&scope, &board, &mut terms.staged) - before;
            terms.commit(&problem, &board);
            // Every kept term is the one the board now has.
            let fresh = Terms::of(&problem, &board);
            assert_eq!(
                (&terms.placements, &terms.pairs, &terms.beyond_limit),
                (&fresh.placements, &fresh.pairs, &fresh.beyond_limit)
            );
            assert!((problem.energy(&board.at) - total_before - delta).abs() < 1e-9);
            assert!(distinct(&board.at));
            // No move adds a piece or a hole.
            let shape_after = shape(&map.lattice, &board.at);
            assert!(shape_after.0 <= shape_before.0 && shape_after.1 <= shape_before.1);
            match proposal {
                Move::Swap(a, b) => {
                    swaps += 1;
                    adjacent_swaps += usize::from(problem.neighbours(a).iter().any(|n| n.0 == b));
                }
                Move::Chain(chain) => {
                    shifts += 1;
                    let cells = chain.cells();
                    let (first, last) = (cells[0], cells[cells.len() - 1]);
                    assert!(last < pool && !from.contains(&last) && from.contains(&first));
                    // Straight: every step is one cell in the same direction.
                    let step = |k: usize| {
                        let (a, b) = (map.lattice.cells[cells[k]], map.lattice.cells[cells[k + 1]]);
                        (b.col - a.col, b.row - a.row)
                    };
                    let (dc, dr) = step(0);
                    assert!(
                        (dc.abs() + dr.abs() == 1 || cells.len() == 2)
                            && (0..cells.len() - 1)
                                .all(|k| cells.len() == 2 || step(k) == (dc, dr))
                    );
                }
            }
        }
        assert!(
            swaps > 100 && adjacent_swaps > 50 && shifts > 100,
            "{swaps} swaps ({adjacent_swaps} of neighbours), {shifts} chains"
        );
        // Both answers of the company rule were compared.
        assert!(strands[0] > 100 && strands[1] > 100, "{strands:?}");
    }

    #[test]
    fn a_region_is_stranded_far_from_home_without_a_neighbour_beside_it() {
        // A 4 × 3 block of regions, each on the cell under its centroid, rook neighbours.
        let map = Map::new(4, 3, 0);
        let layout = map.layout();
        let params = Params {
            refine_location_far: 2.0,
            ..Params::default()
        };
        let start: Vec<usize> = (0..12).collect();
        let links = Links::of(&layout, &params);
        let far = far_from_home(&layout, &start, &params);
        let problem = Problem::new(&layout, &params, &links, &far);
        let stranded = |at: &[usize], region: usize| {
            problem.stranded(
                region,
                &Board::new(&map.lattice, at, map.lattice.cells.len()),
            )
        };
        assert!((0..12).all(|region| !stranded(&start, region)));
        // Region 0 swapped with region 11, into the far corner (√13 cells from home): neither
        // of its neighbours (1 and 4) is beside it there. So is region 11, on region 0's cell.
        let mut at = start.clone();
        at.swap(0, 11);
        assert!(stranded(&at, 0) && stranded(&at, 11));
        // Region 1 taken along, to the cell beside it: both are far from home, neither alone.
        at.swap(1, 10);
        assert!(!stranded(&at, 0) && !stranded(&at, 1));
        // A region that starts far is held only to that distance.
        let far = far_from_home(&layout, &at, &params);
        let problem = Problem::new(&layout, &params, &links, &far);
        let board = Board::new(&map.lattice, &at, map.lattice.cells.len());
        assert!(!problem.stranded(11, &board));
    }

    #[test]
    fn restores_scrambled_neighbours() {
        let map = Map::new(6, 6, 1);
        let layout = map.layout();
        let mut cells: Vec<usize> = (0..36).collect();
        for (a, b) in [(0, 35), (7, 9), (14, 27), (20, 21), (5, 30)] {
            cells.swap(a, b);
        }
        let refined = refine(&layout, &cells, &Params::default(), 1, &|_| true).unwrap();
        // Every region back on the cell under its centroid: the only state of energy 0.
        assert_eq!(refined, (0..36).collect::<Vec<_>>());
        assert!(energy(&layout, &cells, &cells) > 10.0);
        assert_eq!(energy(&layout, &cells, &refined), 0.0);
    }

    #[test]
    fn never_worse_distinct_and_within_the_pool() {
        for (seed, moves, temperature) in [(1, 1000, 0.5), (2, 2, 5.0), (3, 0, 0.5)] {
            let (mut map, cells) = scrambled(7, 6, seed);
            // The pool the landmass selection would give: the best 1.3·M cells.
            let pool = (1.3_f64 * 42.0).ceil() as usize;
            map.lattice.cells.truncate(pool);
            let layout = map.layout();
            let params = Params {
                refine_moves_per_region: moves,
                refine_temperature: temperature,
                ..Params::default()
            };
            let refined = refine(&layout, &cells, &params, seed, &|_| true).unwrap();
            assert!(energy(&layout, &cells, &refined) <= energy(&layout, &cells, &cells));
            assert!(distinct(&refined));
            assert!(refined.iter().all(|&c| c < pool));
            if moves == 1000 {
                // A full run undoes most of a random scramble (from 296 to 31 here; a block in
                // reading order would have 9).
                let (before, after) = (
                    energy(&layout, &cells, &cells),
                    energy(&layout, &cells, &refined),
                );
                assert!(after < 0.2 * before, "{before} → {after}");
            }
        }
    }

    #[test]
    fn the_tracked_best_energy_is_the_energy_of_the_result() {
        let (map, cells) = scrambled(8, 5, 4);
        let layout = map.layout();
        let params = Params::default();
        let links = Links::of(&layout, &params);
        let far = far_from_home(&layout, &cells, &params);
        let problem = Problem::new(&layout, &params, &links, &far);
        let (best, tracked) = anneal(&problem, &cells, &params, 5, false, &|_| true).unwrap();
        assert!((problem.energy(&best) - tracked).abs() < 1e-6);
    }

    #[test]
    fn the_ticks_add_up_to_the_whole_and_a_cancel_stops_it() {
        let (map, cells) = scrambled(10, 10, 5);
        let layout = map.layout();
        // 100 regions × 100 moves: two ticks of 4,096 moves and the rest.
        let params = Params {
            refine_moves_per_region: 100,
            ..Params::default()
        };
        let shares = std::sync::Mutex::new(Vec::new());
        refine(&layout, &cells, &params, 3, &|share| {
            shares.lock().unwrap().push(share);
            true
        })
        .unwrap();
        let shares = shares.into_inner().unwrap();
        // The free search's three ticks, each of half its share, then the second search's
        // three or, when none strands a region, the half it did not need at once.
        assert!([4, 6].contains(&shares.len()), "{shares:?}");
        assert!(
            (shares.iter().sum::<f64>() - 1.0).abs() < 1e-12,
            "{shares:?}"
        );
        assert_eq!(refine(&layout, &cells, &params, 3, &|_| false), None);
    }

    #[test]
    fn deterministic_for_a_seed() {
        let (map, cells) = scrambled(6, 6, 5);
        let layout = map.layout();
        let params = Params {
            refine_moves_per_region: 140,
            ..Params::default()
        };
        let first = refine(&layout, &cells, &params, 11, &|_| true).unwrap();
        assert_eq!(
            refine(&layout, &cells, &params, 11, &|_| true).unwrap(),
            first
        );
        assert_ne!(first, cells);
    }

    #[test]
    fn nothing_to_do_changes_nothing() {
        let map = Map::new(3, 3, 1);
        let empty = Layout {
            adjacency: &[],
            centroids: &[],
            targets: &[],
            lattice: &map.lattice,
            part_of: &[],
            misplaced: None,
            lakes: 0,
            keep_company: true,
        };
        assert!(refine(&empty, &[], &Params::default(), 1, &|_| true)
            .unwrap()
            .is_empty());
        let scrambled = [8, 7, 6, 5, 4, 3, 2, 1, 0];
        let still = Params {
            refine_moves_per_region: 0,
            ..Params::default()
        };
        assert_eq!(
            refine(&map.layout(), &scrambled, &still, 1, &|_| true).unwrap(),
            scrambled
        );
    }

    /// The block in reading order with `swaps` random swaps of cells at most 2 apart: every
    /// region near its place, as after the assignment.
    fn perturbed(cols: i32, rows: i32, seed: u64, swaps: usize) -> (Map, Vec<usize>) {
        let map = Map::new(cols, rows, 2);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut cells: Vec<usize> = (0..map.centroids.len()).collect();
        let index = |c: i32, r: i32| (r * cols + c) as usize;
        for _ in 0..swaps {
            let (c, r) = (rng.random_range(0..cols), rng.random_range(0..rows));
            let (dc, dr) = (rng.random_range(-2..=2), rng.random_range(-2..=2));
            let (c2, r2) = ((c + dc).clamp(0, cols - 1), (r + dr).clamp(0, rows - 1));
            cells.swap(index(c, r), index(c2, r2));
        }
        (map, cells)
    }

    #[test]
    fn stripes_are_three_apart_with_bands_between() {
        let positions: Vec<Position> = (0..40).flat_map(|c| (0..5).map(move |r| (c, r))).collect();
        for phase in 0..PHASES {
            let stripes = Stripes::of(phase, 3, &positions);
            assert!((3..=4).contains(&stripes.count()), "phase {phase}");
            let owned: Vec<(Position, usize)> = (positions.iter())
                .filter_map(|&p| stripes.owner(p).map(|s| (p, s)))
                .collect();
            // Two frozen columns (or rows) at each cut: all the rest is owned.
            let band = 2 * (stripes.count() - 1) * if phase % 2 == 0 { 5 } else { 40 };
            let banded = positions.len() - owned.len();
            assert!(banded <= band && banded > 0, "phase {phase}: {banded}");
            for &(p, s) in &owned {
                for &(q, t) in &owned {
                    if s != t {
                        assert!(Tiling::Square.distance(p, q) >= 3, "{p:?} {q:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn striped_refinement_keeps_the_promises_of_a_whole_one() {
        let (map, cells) = perturbed(60, 40, 8, 1_500);
        let layout = map.layout();
        let params = Params::default();
        let links = Links::of(&layout, &params);
        let pool = map.lattice.cells.len();
        let far = far_from_home(&layout, &cells, &params);
        let problem = Problem::new(&layout, &params, &links, &far);
        let striped = anneal_in_stripes(&problem, &cells, &params, 3, 4, &|_| true).unwrap();
        let whole = refine(&layout, &cells, &params, 3, &|_| true).unwrap();
        assert!(distinct(&striped) && striped.iter().all(|&c| c < pool));
        let (before, after) = (shape(&map.lattice, &cells), shape(&map.lattice, &striped));
        assert!(after.0 <= before.0 && after.1 <= before.1);
        let (start, stripes, one) = (
            energy(&layout, &cells, &cells),
            energy(&layout, &cells, &striped),
            energy(&layout, &cells, &whole),
        );
        // Frozen bands cost the stripes little: they end within a tenth of the whole board's
        // gain.
        assert!(
            stripes < start && start - stripes > 0.9 * (start - one),
            "{start} → {stripes}, whole {one}"
        );
    }

    #[test]
    fn striped_refinement_is_the_same_on_any_number_of_threads() {
        let (map, cells) = perturbed(50, 30, 9, 800);
        let layout = map.layout();
        let params = Params {
            refine_moves_per_region: 100,
            ..Params::default()
        };
        let links = Links::of(&layout, &params);
        let far = far_from_home(&layout, &cells, &params);
        let striped = |tick: Tick| {
            let problem = Problem::new(&layout, &params, &links, &far);
            anneal_in_stripes(&problem, &cells, &params, 5, 3, tick)
        };
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let shares = std::sync::Mutex::new(Vec::new());
            let at = pool.install(|| {
                striped(&|share| {
                    shares.lock().unwrap().push(share);
                    true
                })
            });
            (
                at.unwrap(),
                shares.into_inner().unwrap().iter().sum::<f64>(),
            )
        };
        let (one, share) = on(1);
        assert_eq!(on(4).0, one);
        assert_ne!(one, cells);
        assert!((share - 1.0).abs() < 1e-9, "{share}");
        assert_eq!(striped(&|_| false), None);
    }

    #[test]
    fn small_maps_only_swap() {
        let (map, cells) = scrambled(4, 4, 6);
        let layout = map.layout();
        let params = Params::default();
        assert!(cells.len() < params.refine_swap_only_below);
        let refined = refine(&layout, &cells, &params, 7, &|_| true).unwrap();
        assert!(energy(&layout, &cells, &refined) < energy(&layout, &cells, &cells));
        let (mut before, mut after) = (cells.clone(), refined.clone());
        before.sort_unstable();
        after.sort_unstable();
        assert_eq!(before, after);
    }
}
