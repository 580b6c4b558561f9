//! Step 4a′ (method.md §6, landmass budgets): each connected part of the moved outline (a
//! continent, an island group) that holds k regions gets exactly k cells in its own
//! neighbourhood of the lattice, so a large empty landmass (Antarctica) cannot take the cells a
//! crowded one (Europe) needs, and no region crosses an ocean.
//!
//! Cells are handed out best score first over all parts together, each cell to the part that
//! covers it best, until every part has its k. A part that this leaves in pieces takes its
//! cells again by a flood (a cell not wholly inside waits until it joins the part's cells) when
//! that makes it one piece, so that a landmass thinner than a cell stays one block. A part
//! whose outline covers fewer than k cells (a small landmass of many regions, a tiny island)
//! then takes the free positions nearest to its outline. The same rule, with `ratio`·k cells
//! per part, gives the refinement its pool of free cells, each tagged with its part: a region
//! only ever moves within its own landmass.
//!
//! Once assigned, each part's block of cells is moved as a whole to where §8 measures its
//! regions from ([`settle`]): the Snake deforms the oceans between landmasses, so a block laid on
//! its moved part can sit cells away from its own landmass once the layout is fitted back onto
//! the map (Borneo's countries beside Indochina, Australia in the Indian Ocean).

use super::geometry::RingIndex;
use super::grid::{best_first, Lattice, LatticeCell};
use super::metrics::LayoutShape;
use super::outline::{coords_of, rings_of};
use super::refine::PairWeights;
use super::tiling::{Position, Tiling};
use super::Params;
use geo::{BoundingRect, Coord, MultiPolygon};
use rustc_hash::{FxHashMap, FxHashSet};
use std::cell::{OnceCell, RefCell};

/// The cells the layout may use, tagged with their part: the first `demands.iter().sum()` are
/// the cells to assign (each part's k; the fixed cells first), the rest the refinement's pool.
pub struct Selection {
    pub cells: Vec<LatticeCell>,
    pub assigned: usize,
}

/// Selects cells on `lattice` (its frame: size and origin) for the moved outline's `parts` (one
/// multipolygon per part), part `p` holding `demands[p]` regions; `ratio` ≥ 1 sizes the pool.
/// The `fixed` cells (pinned regions', at distinct positions) are taken first, each counting
/// towards its part's demand wherever it lies: pins override the budgets.
pub fn select(
    lattice: &Lattice,
    parts: &[MultiPolygon<f64>],
    demands: &[usize],
    ratio: f64,
    fixed: &[LatticeCell],
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
    // Every position handed out, with its part.
    let mut taken: FxHashMap<Position, usize> =
        fixed.iter().map(|c| ((c.col, c.row), c.part)).collect();
    let mut open = demands.to_vec();
    for cell in fixed {
        open[cell.part] = open[cell.part].saturating_sub(1);
    }
    // Indexed only if a part falls short, and then once for both picks.
    let outlines = OnceCell::new();
    let mut assigned = fixed.to_vec();
    assigned.extend(pick(lattice, parts, &outlines, &scored, &open, &mut taken));
    let extra: Vec<usize> = demands
        .iter()
        // Less a hair, so that 1.3 × 10 (13.000000000000002 in binary) asks for 3 more, not 4.
        .map(|&k| ((ratio - 1.0) * k as f64 - 1e-9).ceil().max(0.0) as usize)
        .collect();
    let pool = pick(lattice, parts, &outlines, &scored, &extra, &mut taken);
    let count = assigned.len();
    Selection {
        cells: assigned.into_iter().chain(pool).collect(),
        assigned: count,
    }
}

/// Hands out `wanted[p]` more cells to each part `p`, free ones only: best scored first (a part
/// that this breaks into pieces flooded instead, where that joins them), then, for parts still
/// short, the free positions nearest their outline.
fn pick(
    lattice: &Lattice,
    parts: &[MultiPolygon<f64>],
    outlines: &OnceCell<Outlines>,
    scored: &[LatticeCell],
    wanted: &[usize],
    taken: &mut FxHashMap<Position, usize>,
) -> Vec<LatticeCell> {
    // Best first; then again, flooded, for the parts that best first breaks into pieces (a
    // landmass is one piece of the outline, so its cells should be one block) and that the
    // flood makes one piece. A part whose cells stay apart either way (two continents joined
    // by an isthmus longer than the cells left for it) keeps the best cells.
    let count = parts.len();
    let mut best = taken.clone();
    let (mut chosen, mut missing) = offer(lattice, scored, wanted, &mut best, &vec![false; count]);
    let broken = broken_parts(lattice, &best, count);
    let mut repaired = vec![false; count];
    if broken.contains(&true) {
        let mut flooded = taken.clone();
        offer(lattice, scored, wanted, &mut flooded, &broken);
        let still = broken_parts(lattice, &flooded, count);
        repaired = (0..count).map(|p| broken[p] && !still[p]).collect();
    }
    if repaired.contains(&true) {
        (chosen, missing) = offer(lattice, scored, wanted, taken, &repaired);
    } else {
        *taken = best;
    }
    if missing.iter().all(|&short| short == 0) {
        return chosen;
    }
    let outlines = outlines.get_or_init(|| Outlines::new(parts));
    for (part, &short) in missing.iter().enumerate() {
        if short > 0 {
            chosen.extend(nearest_free(
                lattice,
                &parts[part],
                outlines,
                part,
                short,
                taken,
            ));
        }
    }
    chosen
}

/// Hands out `wanted[p]` more scored cells to each part `p`, best first, those of the
/// `flooded` parts as their flood meets them ([`flood`]); returns the cells and how many
/// each part still misses.
fn offer(
    lattice: &Lattice,
    scored: &[LatticeCell],
    wanted: &[usize],
    taken: &mut FxHashMap<Position, usize>,
    flooded: &[bool],
) -> (Vec<LatticeCell>, Vec<usize>) {
    let mut missing = wanted.to_vec();
    let mut chosen = Vec::with_capacity(wanted.iter().sum());
    // A cell sharing an edge with another landmass's would join the two into one piece: left
    // for the search for free positions, which avoids that.
    let mut take = |cell: &LatticeCell, taken: &mut FxHashMap<Position, usize>| {
        let at = (cell.col, cell.row);
        let free = missing[cell.part] > 0
            && !taken.contains_key(&at)
            && !touches_another(lattice, taken, at, cell.part);
        if free {
            taken.insert(at, cell.part);
            missing[cell.part] -= 1;
            chosen.push(*cell);
        }
        free
    };
    if flooded.contains(&true) {
        let used = flood(lattice, scored, taken, flooded, &mut take);
        // Cells the flood could not reach from its part's others (another part's cells in
        // between).
        for (cell, _) in scored.iter().zip(&used).filter(|(_, &used)| !used) {
            take(cell, taken);
        }
    } else {
        // Nothing flooded: the flood would offer every cell in this order, without its heap.
        for cell in scored {
            take(cell, taken);
        }
    }
    (chosen, missing)
}

/// Per part, whether the positions `taken` holds for it make more than one edge-connected
/// piece.
fn broken_parts(lattice: &Lattice, taken: &FxHashMap<Position, usize>, parts: usize) -> Vec<bool> {
    let mut pieces = vec![0usize; parts];
    let mut seen: FxHashSet<Position> = FxHashSet::default();
    for (&start, &part) in taken {
        if part >= parts || !seen.insert(start) {
            continue;
        }
        pieces[part] += 1;
        let mut stack = vec![start];
        while let Some(p) = stack.pop() {
            for n in lattice.tiling.edge_neighbours(p).iter() {
                if taken.get(n) == Some(&part) && seen.insert(*n) {
                    stack.push(*n);
                }
            }
        }
    }
    pieces.iter().map(|&count| count > 1).collect()
}

/// Offers the `scored` cells (best first) to `take`, those of the `flooded` parts in the order a
/// flood from the part's cells meets them: a cell wholly inside its part (score 2) is offered in
/// its turn, any other only once it shares an edge with a cell its part holds (or as the part's
/// first). Where the outline is thinner than a cell, no cell is wholly inside and the best cells
/// alone can alternate with worse ones along it (pointy hexagons along a north-south strip take
/// every other row), which breaks a landmass into pieces the refinement cannot join; flooded,
/// its cells follow the strip as one block. Returns, per scored cell, whether it was offered.
fn flood(
    lattice: &Lattice,
    scored: &[LatticeCell],
    taken: &mut FxHashMap<Position, usize>,
    flooded: &[bool],
    take: &mut dyn FnMut(&LatticeCell, &mut FxHashMap<Position, usize>) -> bool,
) -> Vec<bool> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let index: FxHashMap<(Position, usize), usize> = (scored.iter().enumerate())
        .map(|(k, c)| (((c.col, c.row), c.part), k))
        .collect();
    let parts = scored.iter().map(|c| c.part + 1).max().unwrap_or(0);
    // Per part, its scored cells in order, for its next first cell when one is refused.
    let mut own: Vec<Vec<usize>> = vec![Vec::new(); parts];
    for (k, c) in scored.iter().enumerate() {
        own[c.part].push(k);
    }
    let mut holds = vec![false; parts];
    let mut next_first = vec![0; parts];
    let mut queued = vec![false; scored.len()];
    let mut heap = BinaryHeap::new();
    let queue = |k: usize, queued: &mut [bool], heap: &mut BinaryHeap<Reverse<usize>>| {
        if !std::mem::replace(&mut queued[k], true) {
            heap.push(Reverse(k));
        }
    };
    let neighbours_of = |p: Position, part: usize| {
        (lattice.tiling.edge_neighbours(p).iter())
            .filter_map(|n| index.get(&(*n, part)).copied())
            .collect::<Vec<usize>>()
    };
    for (k, c) in scored.iter().enumerate() {
        if c.score >= 2.0 || !flooded[c.part] {
            queue(k, &mut queued, &mut heap);
        }
    }
    for (&p, &part) in taken.iter().filter(|(_, &part)| part < parts) {
        holds[part] = true;
        for k in neighbours_of(p, part) {
            queue(k, &mut queued, &mut heap);
        }
    }
    for part in (0..parts).filter(|&part| !holds[part]) {
        if let Some(&k) = own[part].first() {
            next_first[part] = 1;
            queue(k, &mut queued, &mut heap);
        }
    }
    let mut offered = vec![false; scored.len()];
    while let Some(Reverse(k)) = heap.pop() {
        let cell = scored[k];
        offered[k] = true;
        if take(&cell, taken) {
            holds[cell.part] = true;
            for n in neighbours_of((cell.col, cell.row), cell.part) {
                queue(n, &mut queued, &mut heap);
            }
        } else if !holds[cell.part] {
            // Its first cell went to another part: the next best is its first.
            let list = &own[cell.part];
            while let Some(&n) = list.get(next_first[cell.part]) {
                next_first[cell.part] += 1;
                if !queued[n] {
                    queue(n, &mut queued, &mut heap);
                    break;
                }
            }
        }
    }
    offered
}

/// The parts' outlines, each indexed for distances and all in one index, so that whether a
/// point lies nearer another part than its own takes one query, not one per part (a layer of
/// hundreds of islands asks it for every position around each).
struct Outlines {
    own: Vec<RingIndex>,
    all: RingIndex,
    /// Per ring of `all`, its part.
    part_of_ring: Vec<usize>,
    /// Each part's answers by position, kept for both picks (the assigned cells', then the
    /// pool's) and as the search square grows: a crowd of one-region islands asked the same
    /// positions again and again (300 islands beside 10,000 regions: a third of the run).
    measured: RefCell<FxHashMap<(usize, Position), (f64, bool)>>,
}

impl Outlines {
    fn new(parts: &[MultiPolygon<f64>]) -> Outlines {
        let rings: Vec<Vec<Vec<Coord<f64>>>> =
            parts.iter().map(|p| coords_of(&rings_of(p))).collect();
        Outlines {
            own: rings.iter().map(|r| RingIndex::new(r)).collect(),
            all: RingIndex::new(&rings.concat()),
            part_of_ring: (rings.iter().enumerate())
                .flat_map(|(part, r)| std::iter::repeat_n(part, r.len()))
                .collect(),
            measured: RefCell::default(),
        }
    }

    /// [`Outlines::distance`] of `lattice`'s position `at`, measured once per part.
    fn at(&self, lattice: &Lattice, part: usize, at: Position) -> (f64, bool) {
        *(self.measured.borrow_mut().entry((part, at)))
            .or_insert_with(|| self.distance(part, lattice.centre(at.0, at.1)))
    }

    /// Distance from `p` to part `part`'s outline (0 inside it), and whether another part lies
    /// nearer (or holds `p`).
    fn distance(&self, part: usize, p: Coord<f64>) -> (f64, bool) {
        if self.own[part].contains(p) {
            return (0.0, false);
        }
        let Some((nearest, d)) = self.all.nearest(p) else {
            return (f64::INFINITY, false);
        };
        let another = |ring: usize| self.part_of_ring[ring] != part;
        if !another(nearest.ring) {
            // The part's own segment is the nearest, so the disk out to it crosses no outline:
            // were `p` inside another part, the whole disk would be, and that part would reach
            // the own segment on the disk's rim, as near as it. Only then is a ray cast (the
            // ball reaches a hair beyond, so that no tie is lost to rounding: a segment it
            // catches needlessly only costs that ray).
            let tie = self
                .all
                .within(p, d * (1.0 + 1e-9))
                .any(|(s, _)| another(s.ring));
            return (d, tie && self.all.contains(p));
        }
        let own = self.own[part].nearest(p).map_or(f64::INFINITY, |(_, d)| d);
        (own, d < own || self.all.contains(p))
    }
}

/// The `count` free positions whose centres lie nearest to `outline` (ties by row, then
/// column), marked as taken, with score 0; positions nearer one of the `others` outlines than
/// to this one come only after all that are not, so that a small landmass grows away from its
/// neighbours rather than towards them. Searched in squares of growing size around the
/// outline's bounding box, so the work follows the positions handed out.
fn nearest_free(
    lattice: &Lattice,
    outline: &MultiPolygon<f64>,
    outlines: &Outlines,
    part: usize,
    count: usize,
    taken: &mut FxHashMap<Position, usize>,
) -> Vec<LatticeCell> {
    let Some(bounds) = outline.bounding_rect() else {
        return Vec::new();
    };
    let corners = [
        (bounds.min().x, bounds.max().y),
        (bounds.max().x, bounds.max().y),
        (bounds.min().x, bounds.min().y),
        (bounds.max().x, bounds.min().y),
    ]
    .map(|(x, y)| lattice.position_of(Coord { x, y }));
    // The positions' range over the box's corners: for squares its top-left and bottom-right
    // cells; for hexagons' slanted axes a parallelogram that holds the box.
    let low = corners
        .iter()
        .fold((i32::MAX, i32::MAX), |m, p| (m.0.min(p.0), m.1.min(p.1)));
    let high = corners
        .iter()
        .fold((i32::MIN, i32::MIN), |m, p| (m.0.max(p.0), m.1.max(p.1)));
    // Wide enough to hold `count` free positions beyond the box even if none inside is free.
    let mut margin = (count as f64).sqrt().ceil() as i32 + 1;
    // The first margin whose square settled `count` positions, own side or not.
    let mut enough_at: Option<i32> = None;
    loop {
        let mut free: Vec<(bool, bool, f64, i32, i32)> = Vec::new();
        for row in low.1 - margin..=high.1 + margin {
            for col in low.0 - margin..=high.0 + margin {
                if !taken.contains_key(&(col, row)) {
                    let (own, elsewhere) = outlines.at(lattice, part, (col, row));
                    let touches = touches_another(lattice, taken, (col, row), part);
                    free.push((elsewhere, touches, own, row, col));
                }
            }
        }
        // A position farther than the margin could be beaten by one outside the searched
        // square: take only those the square settles.
        let settled = f64::from(margin) * lattice.tiling.pitch() * lattice.cell_size;
        free.retain(|f| f.2 <= settled);
        free.sort_by(|a, b| {
            (a.0.cmp(&b.0))
                .then(a.1.cmp(&b.1))
                .then(a.2.total_cmp(&b.2))
                .then(a.3.cmp(&b.3))
                .then(a.4.cmp(&b.4))
        });
        // Positions nearer another landmass are settled only once the square holds enough
        // positions that are not: otherwise a wider square may offer some. The square grows
        // at most two doublings past the first that held enough positions (and past 4(k + 1)
        // for a small landmass): a landmass ringed by islands has no own side farther out,
        // and a search to the lattice's ends would take minutes.
        let own_side = free.iter().filter(|f| !f.0).count();
        if free.len() >= count {
            enough_at.get_or_insert(margin);
        }
        let searched_enough =
            enough_at.is_some_and(|first| margin > (4 * (count as i32 + 1)).min(4 * first));
        if own_side >= count || searched_enough {
            return free[..count]
                .iter()
                .map(|&(_, _, _, row, col)| {
                    taken.insert((col, row), part);
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

/// Whether `at` shares an edge with a position handed out to another part than `part`, for the
/// tilings that keep landmasses apart ([`keeps_landmasses_apart`]).
fn touches_another(
    lattice: &Lattice,
    taken: &FxHashMap<Position, usize>,
    at: Position,
    part: usize,
) -> bool {
    keeps_landmasses_apart(lattice.tiling)
        && (lattice.tiling.edge_neighbours(at).iter())
            .any(|n| taken.get(n).is_some_and(|&p| p != part))
}

/// Whether cells and block shifts that would join two landmasses into one piece are avoided.
/// Hexagons share an edge with all six neighbours, so an island's nearest cell often joins the
/// mainland: on the generated islands layer (12 parts) hexagons made 8 pieces, and keep 12
/// with this, at better adjacency and direction. Squares touch most neighbours at a corner
/// only, which joins nothing; there it was measured to cost more than it gives (world_countries:
/// 17 → 23 pieces but location 1.38 → 1.55 cells), so squares place as before.
pub fn keeps_landmasses_apart(tiling: Tiling) -> bool {
    tiling != Tiling::Square
}

/// The most region placements [`settle`] weighs for one block's shifts before it searches them
/// on a coarser grid: nearly three times what any of 260 layers needed (37,125: the 27 regions
/// of Alaska in Highcharts' US counties, 25 cells from their place). Two concentric rings
/// thinner than a cell, whose first layouts put a 300-region block 33 cells off, needed a
/// million per round (BENCHMARKS.md, "A thin landmass that closes on itself").
const SHIFT_WORK: usize = 100_000;

/// Rounds of [`settle`]. Every shift lowers the blocks' cost, so the rounds end by themselves;
/// two or three do, and the cap only bounds the work.
const SETTLE_ROUNDS: usize = 8;

/// How many regions of the large landmasses place a region of a small one ([`Anchors`]).
const ANCHORS: usize = 3;

/// Per region on a landmass of one or two regions (method.md §8's wrong-landmass share counts
/// only landmasses of 3 regions or more), the regions whose cells place it: the [`ANCHORS`]
/// regions of large landmasses whose places lie nearest (ties by index); none for any other
/// region, or when no landmass is large.
///
/// The §8 fit is a scale and a shift for the whole map; where the layout must bend the map (a
/// crowded capital region spreading over a sparse coast), the coast's regions lie cells from
/// their fitted places, held there by their neighbours. An island of one region is held by
/// nothing: sent to its fitted place, it went there alone, out to sea (Cozumel 16 cells north
/// of its coast among Mexico's 2,458 municipalities, a tract of Albuquerque's 195 above the
/// whole layout). So an island whose fitted place lies more than `limit` cells
/// (`island_limit`) from where its anchors' cells put it (its place as seen from theirs) goes
/// where they put it, beside its coast as the source has it. One within the limit keeps its
/// fitted place: on a map the fit describes well (world_countries, where no island is more
/// than 4.3 cells from where its coast puts it), following the anchors at any distance only
/// added their errors to the island's (location 1.40 → 1.61 cells).
pub struct Anchors {
    of: Vec<Vec<usize>>,
    /// In cells.
    limit: f64,
}

impl Anchors {
    /// The anchors of the regions at `places`, `large(i)` telling whether region `i`'s landmass
    /// holds 3 regions or more; `limit` in cells.
    pub fn new(places: &[Coord<f64>], large: impl Fn(usize) -> bool, limit: f64) -> Anchors {
        use rstar::{primitives::GeomWithData, RTree};
        let on_large: Vec<GeomWithData<[f64; 2], usize>> = (0..places.len())
            .filter(|&i| large(i))
            .map(|i| GeomWithData::new([places[i].x, places[i].y], i))
            .collect();
        let tree = RTree::bulk_load(on_large);
        let of = (0..places.len())
            .map(|i| {
                if large(i) || tree.size() == 0 {
                    return Vec::new();
                }
                let squared = |j: usize| {
                    let d = places[j] - places[i];
                    d.x * d.x + d.y * d.y
                };
                // A few more than wanted, so that ties at the last distance go by index.
                let mut nearest: Vec<usize> = (tree
                    .nearest_neighbor_iter(&[places[i].x, places[i].y]))
                .take(ANCHORS + 2)
                .map(|found| found.data)
                .collect();
                nearest.sort_by(|&a, &b| squared(a).total_cmp(&squared(b)).then(a.cmp(&b)));
                nearest.truncate(ANCHORS);
                nearest
            })
            .collect();
        Anchors { of, limit }
    }

    /// Where region `i` belongs in the lattice's frame (cells of `cell_size`), given the §8 fit
    /// (`scale`, `offset`: a centre g lies at the place s·g + t), the regions' `places` and
    /// each region's cell centre `centre_of(j)`: its place under the fit, or where its anchors'
    /// cells put it (the mean over them), when that is beyond the limit. The flag tells which.
    pub fn target(
        &self,
        i: usize,
        places: &[Coord<f64>],
        centre_of: impl Fn(usize) -> Coord<f64>,
        (scale, offset): (f64, Coord<f64>),
        cell_size: f64,
    ) -> (Coord<f64>, bool) {
        let fitted = (places[i] - offset) / scale;
        let own = &self.of[i];
        if own.is_empty() {
            return (fitted, false);
        }
        let sum = (own.iter()).fold(Coord { x: 0.0, y: 0.0 }, |sum, &j| {
            sum + centre_of(j) + (places[i] - places[j]) / scale
        });
        let anchored = sum / own.len() as f64;
        let apart = fitted - anchored;
        let limit = self.limit * cell_size;
        if apart.x * apart.x + apart.y * apart.y > limit * limit {
            (anchored, true)
        } else {
            (fitted, false)
        }
    }
}

/// What [`settle`] places the landmass blocks by.
pub struct Homes<'a> {
    /// Per region, where §8 measures it from (its area centroid), in the lattice's frame before
    /// the fit; also the directions its adjacent pairs should keep.
    pub places: &'a [Coord<f64>],
    /// Where an island goes when its coast's cells lie far from its fitted place.
    pub anchors: &'a Anchors,
    /// Adjacent region pairs: a pair across two landmasses (a country on a continent and an
    /// island) pulls their blocks together.
    pub adjacency: &'a [(usize, usize)],
    /// Whether region `i` at a fitted position lies nearer another landmass than its own;
    /// `None` when no region can.
    pub misplaced: Option<&'a dyn Fn(usize, Coord<f64>) -> bool>,
}

/// Moves each part's block of cells (its assigned cells and its pool, which `part` tags) by
/// whole cells to where §8 will measure its regions from; `cells[i]` is region `i`'s index in
/// `lattice.cells`.
///
/// A block takes, among the shifts that keep it off every other part's cells and add no hole
/// to the layout, the one putting the fewest of its regions on another landmass, then the one of
/// least energy as method.md §6b writes it: the regions' squared distances from their places
/// under the §8 fit of the whole layout as the shift leaves it (in fitted cells; squared
/// throughout, unlike the refinement's beyond `refine_location_knee`, since the fit's sums
/// give the square's total for every shift in O(1)), plus the
/// block's pairs with other blocks; then the lowest row and column shift. It moves only if that
/// is better than staying. The part with the most regions stays (the lowest index among
/// equals); the others go largest first. A block's assignment stays optimal: translating all
/// its cells adds the same to every assignment's cost. With pins, the parts holding a pinned
/// cell (`anchored`) stay instead, and only the others move.
pub fn settle(
    lattice: &mut Lattice,
    cells: &[usize],
    homes: &Homes,
    params: &Params,
    anchored: &[usize],
) {
    let parts = lattice.cells.iter().map(|c| c.part + 1).max().unwrap_or(0);
    if parts < 2 {
        // One block: the fit's shift already puts it where it belongs.
        return;
    }
    let mut regions_of: Vec<Vec<usize>> = vec![Vec::new(); parts];
    for (i, &k) in cells.iter().enumerate() {
        regions_of[lattice.cells[k].part].push(i);
    }
    let mut order: Vec<usize> = (0..parts).filter(|&p| !regions_of[p].is_empty()).collect();
    order.sort_by_key(|&p| (std::cmp::Reverse(regions_of[p].len()), p));
    // The largest part stays where the Snake put it: the fit has no fixed origin, so moving it
    // would only do what moving all the others the other way does. Pins fix the origin.
    if anchored.is_empty() {
        order.remove(0);
    } else {
        order.retain(|p| !anchored.contains(p));
    }
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); cells.len()];
    for &(i, j) in homes.adjacency.iter().filter(|(i, j)| i != j) {
        neighbours[i].push(j);
        neighbours[j].push(i);
    }
    let block = Block {
        cells,
        homes,
        neighbours: &neighbours,
        pairs: PairWeights::of(params),
        w_location: params.refine_w_location,
    };
    let position = |cell: &LatticeCell| (cell.col, cell.row);
    // Every cell's part, and the assigned cells' parts: what a block may not land on, and what
    // it may touch.
    let mut taken: FxHashMap<Position, usize> = (lattice.cells.iter())
        .map(|c| (position(c), c.part))
        .collect();
    // Per part, its cells (assigned and pool), as indexes into `lattice.cells`.
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); parts];
    for (k, cell) in lattice.cells.iter().enumerate() {
        members[cell.part].push(k);
    }
    let mut assigned: FxHashMap<Position, usize> = (cells.iter())
        .map(|&k| (position(&lattice.cells[k]), lattice.cells[k].part))
        .collect();
    // The layout's holes, counted when a shift needs them and kept until a block moves: a
    // crowd of islands beside a mainland asked for them at every one (a thousand islands: nine
    // tenths of the run).
    let mut holes = OnceCell::new();
    for _ in 0..SETTLE_ROUNDS {
        let mut all = FitSums::of((0..cells.len()).map(|i| block.fit_term(lattice, i)));
        let mut moved = false;
        for &part in &order {
            let regions = &regions_of[part];
            let own = FitSums::of(regions.iter().map(|&i| block.fit_term(lattice, i)));
            let board = Board {
                members: &members[part],
                taken: &taken,
                assigned: &assigned,
                all: &all,
                own: &own,
                holes: &holes,
            };
            let Some((shift, holes_after)) = block.best_shift(lattice, part, regions, &board)
            else {
                continue;
            };
            holes = OnceCell::new();
            if let Some(count) = holes_after {
                let _ = holes.set(count);
            }
            let moving = &members[part];
            for &k in moving {
                taken.remove(&position(&lattice.cells[k]));
                assigned.remove(&position(&lattice.cells[k]));
            }
            let is_assigned: FxHashSet<usize> = regions.iter().map(|&i| cells[i]).collect();
            for &k in moving {
                let cell = &mut lattice.cells[k];
                cell.col += shift.0;
                cell.row += shift.1;
                // Off the moved outline's coverage now: the score no longer describes it.
                cell.score = 0.0;
                taken.insert(position(cell), part);
                if is_assigned.contains(&k) {
                    assigned.insert(position(cell), part);
                }
            }
            all = all.shifted(&own, block.offset(lattice, shift));
            moved = true;
        }
        if !moved {
            return;
        }
    }
}

/// Where the other blocks are, and the fit's sums, for one block's shift.
struct Board<'a> {
    /// The block's cells, as indexes into the lattice's.
    members: &'a [usize],
    /// Every lattice cell's position and part.
    taken: &'a FxHashMap<Position, usize>,
    /// The assigned cells' positions and parts.
    assigned: &'a FxHashMap<Position, usize>,
    /// The fit's sums over all regions, and over the block's.
    all: &'a FitSums,
    own: &'a FitSums,
    /// The layout's holes as it stands, once counted: they change only when a block moves.
    holes: &'a OnceCell<u32>,
}

/// What [`settle`] weighs a block's shift with.
struct Block<'a> {
    cells: &'a [usize],
    homes: &'a Homes<'a>,
    /// Per region, its adjacent regions.
    neighbours: &'a [Vec<usize>],
    pairs: PairWeights,
    /// `refine_w_location`, per squared cell.
    w_location: f64,
}

/// The sums the least-squares fit of cell centres g onto places c needs (`metrics::fit`), so that
/// the fit of a layout with one block shifted costs O(1).
#[derive(Clone, Copy)]
struct FitSums {
    n: f64,
    g: Coord<f64>,
    c: Coord<f64>,
    gg: f64,
    gc: f64,
    cc: f64,
}

impl FitSums {
    fn of(pairs: impl Iterator<Item = (Coord<f64>, Coord<f64>)>) -> FitSums {
        let zero = Coord { x: 0.0, y: 0.0 };
        pairs.fold(
            FitSums {
                n: 0.0,
                g: zero,
                c: zero,
                gg: 0.0,
                gc: 0.0,
                cc: 0.0,
            },
            |s, (g, c)| FitSums {
                n: s.n + 1.0,
                g: s.g + g,
                c: s.c + c,
                gg: s.gg + dot(g, g),
                gc: s.gc + dot(g, c),
                cc: s.cc + dot(c, c),
            },
        )
    }

    /// The sums with the centres of `block` (its own sums) moved by `d`.
    fn shifted(&self, block: &FitSums, d: Coord<f64>) -> FitSums {
        FitSums {
            g: self.g + d * block.n,
            gg: self.gg + 2.0 * dot(d, block.g) + block.n * dot(d, d),
            gc: self.gc + dot(d, block.c),
            ..*self
        }
    }

    /// The fit's scale and shift, as `metrics::fit` makes them, and its squared residual in fitted
    /// units (the sum of |c − (s·g + t)|² / s²).
    fn fit(&self) -> (f64, Coord<f64>, f64) {
        let n = self.n.max(1.0);
        let variance = self.gg - dot(self.g, self.g) / n;
        let covariance = self.gc - dot(self.g, self.c) / n;
        let spread = self.cc - dot(self.c, self.c) / n;
        let scale = if variance > 0.0 && covariance != 0.0 && self.n > 1.0 {
            covariance / variance
        } else {
            1.0
        };
        let residual = spread - 2.0 * scale * covariance + scale * scale * variance;
        let offset = (self.c - self.g * scale) / n;
        (scale, offset, residual.max(0.0) / (scale * scale))
    }
}

fn dot(a: Coord<f64>, b: Coord<f64>) -> f64 {
    a.x * b.x + a.y * b.y
}

impl Block<'_> {
    /// Region `i`'s cell centre and place: one term of the fit.
    fn fit_term(&self, lattice: &Lattice, i: usize) -> (Coord<f64>, Coord<f64>) {
        let cell = &lattice.cells[self.cells[i]];
        (lattice.centre(cell.col, cell.row), self.homes.places[i])
    }

    /// A shift by whole positions as a vector in the lattice's frame.
    fn offset(&self, lattice: &Lattice, shift: Position) -> Coord<f64> {
        lattice.tiling.centre_offset(shift) * lattice.cell_size
    }

    /// The shift [`settle`] gives the block of `part` (holding `regions`), or `None` to stay.
    /// The shift `part`'s block takes (see [`settle`]), and the layout's holes after it when
    /// they were counted.
    fn best_shift(
        &self,
        lattice: &Lattice,
        part: usize,
        regions: &[usize],
        board: &Board,
    ) -> Option<(Position, Option<u32>)> {
        let size = lattice.cell_size;
        let at = |region: usize| {
            let cell = &lattice.cells[self.cells[region]];
            (cell.col, cell.row)
        };
        let centre = |(col, row): Position| lattice.centre(col, row);
        let inside = |region: usize| lattice.cells[self.cells[region]].part == part;
        let places = self.homes.places;
        // Where the block's regions belong under the present fit. An island placed by the cells
        // of the regions nearest it ([`Anchors`]), which stay where they are whatever this block
        // does, is measured from there; any other block from its places under the fit as the
        // shift leaves it.
        let (scale, offset, _) = board.all.fit();
        let (targets, anchored): (Vec<Coord<f64>>, Vec<bool>) = (regions.iter())
            .map(|&i| {
                (self.homes.anchors).target(i, places, |j| centre(at(j)), (scale, offset), size)
            })
            .unzip();
        let anchored = anchored.contains(&true);
        let cost = |(du, dv): Position| {
            let moved = |i: usize| {
                let (col, row) = at(i);
                (col + du, row + dv)
            };
            let d = self.offset(lattice, (du, dv));
            let (scale, offset, residual) = board.all.shifted(board.own, d).fit();
            let residual = if anchored {
                (regions.iter().zip(&targets))
                    .map(|(&i, &t)| {
                        let e = centre(moved(i)) - t;
                        dot(e, e)
                    })
                    .sum()
            } else {
                residual
            };
            let wrong = self.homes.misplaced.map_or(0, |misplaced| {
                (regions.iter())
                    .filter(|&&i| misplaced(i, centre(moved(i)) * scale + offset))
                    .count()
            });
            let pairs: f64 = (regions.iter())
                .flat_map(|&i| self.neighbours[i].iter().map(move |&j| (i, j)))
                .filter(|&(_, j)| !inside(j))
                .map(|(i, j)| self.pairs.energy(places[j] - places[i], moved(i), at(j)))
                .sum();
            (wrong, self.w_location * residual / (size * size) + pairs)
        };
        // Where the block's regions lie from their cells, in cells (rows downwards). The fit
        // follows the block part of the way, so the search reaches twice as far, and a cell
        // beyond.
        let n = regions.len() as f64;
        let mean =
            (regions.iter().zip(&targets)).fold(Coord { x: 0.0, y: 0.0 }, |d, (&i, &target)| {
                let from = centre(at(i));
                Coord {
                    x: d.x + (target.x - from.x) / (size * n),
                    y: d.y + (target.y - from.y) / (size * n),
                }
            });
        let ideal = lattice.tiling.fractional(mean);
        let span = |ideal: f64| {
            let reach = (2.0 * ideal).round() as i32;
            reach.min(0) - 1..=reach.max(0) + 1
        };
        let staying = cost((0, 0));
        let better = |key: &(usize, f64)| {
            key.0 < staying.0 || (key.0 == staying.0 && key.1 < staying.1 - 1e-9)
        };
        let order = |a: &((usize, f64), Position), b: &((usize, f64), Position)| {
            (a.0 .0.cmp(&b.0 .0))
                .then(a.0 .1.total_cmp(&b.0 .1))
                .then(a.1 .1.cmp(&b.1 .1))
                .then(a.1 .0.cmp(&b.1 .0))
        };
        let (columns, rows) = (span(ideal.0), span(ideal.1));
        // Every shift of the square costs a pass over the block's regions. A block of many
        // regions far from its place is searched on a coarser grid first, then every shift
        // around the best of it.
        let work = regions.len() * columns.clone().count() * rows.clone().count();
        let stride = ((work as f64 / SHIFT_WORK as f64).sqrt().ceil() as usize).max(1);
        let mut shifts: Vec<((usize, f64), Position)> = Vec::new();
        let consider = |shift: Position, shifts: &mut Vec<_>| {
            let key = cost(shift);
            if better(&key) {
                shifts.push((key, shift));
            }
        };
        // The coarse grid's shifts: every `stride`-th of the square's, from its first.
        let on_grid = |(du, dv): Position| {
            let step = stride as i32;
            columns.contains(&du)
                && rows.contains(&dv)
                && (du - columns.start()) % step == 0
                && (dv - rows.start()) % step == 0
        };
        for dv in rows.clone().step_by(stride) {
            for du in columns.clone().step_by(stride) {
                consider((du, dv), &mut shifts);
            }
        }
        if let Some(&(_, (u, v))) = shifts
            .iter()
            .min_by(|a, b| order(a, b))
            .filter(|_| stride > 1)
        {
            let near = stride as i32 - 1;
            for dv in v - near..=v + near {
                for du in (u - near..=u + near).filter(|&du| !on_grid((du, dv))) {
                    consider((du, dv), &mut shifts);
                }
            }
        }
        shifts.sort_by(order);
        let block: Vec<Position> = (board.members.iter())
            .map(|&k| (lattice.cells[k].col, lattice.cells[k].row))
            .collect();
        let own_cells: Vec<Position> = regions.iter().map(|&i| at(i)).collect();
        // Whether the block's assigned cells, shifted, touch another block's: only then can the
        // shift change the layout's holes (a block apart from the rest neither closes nor
        // opens any).
        let touches = |(du, dv): Position| {
            (own_cells.iter()).any(|&(c, r)| {
                (-1..=1).any(|dr| {
                    (-1..=1).any(|dc| {
                        let near = (c + du + dc, r + dv + dr);
                        board.assigned.get(&near).is_some_and(|&p| p != part)
                    })
                })
            })
        };
        // Whether the shifted block shares an edge with another block: the two would become
        // one piece of the layout, where the source has two landmasses.
        let joins = |(du, dv): Position| {
            keeps_landmasses_apart(lattice.tiling)
                && (own_cells.iter()).any(|&(c, r)| {
                    (lattice.tiling.edge_neighbours((c + du, r + dv)).iter())
                        .any(|near| board.assigned.get(near).is_some_and(|&p| p != part))
                })
        };
        let layout = |(du, dv): Position| -> Vec<Position> {
            (0..self.cells.len())
                .map(|i| {
                    let (col, row) = at(i);
                    if inside(i) {
                        (col + du, row + dv)
                    } else {
                        (col, row)
                    }
                })
                .collect()
        };
        let holes_of = |shift: Position| LayoutShape::holes_of(&layout(shift), lattice.tiling);
        let mut after = None;
        let shift = shifts.into_iter().map(|(_, shift)| shift).find(|&shift| {
            after = None;
            let free = (block.iter()).all(|&(c, r)| {
                (board.taken.get(&(c + shift.0, r + shift.1))).is_none_or(|&p| p == part)
            });
            let apart = !joins(shift) || joins((0, 0));
            if !(free && apart) {
                return false;
            }
            if !(touches((0, 0)) || touches(shift)) {
                return true;
            }
            let holes = holes_of(shift);
            after = Some(holes);
            holes <= *board.holes.get_or_init(|| holes_of((0, 0)))
        })?;
        Some((shift, after))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::grid::frame;
    use crate::core::params::HexOrientation;
    use geo::{LineString, Polygon};
    use std::collections::HashSet;

    fn rectangle(x0: f64, y0: f64, x1: f64, y1: f64) -> MultiPolygon<f64> {
        MultiPolygon(vec![Polygon::new(
            LineString::from(vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]),
            vec![],
        )])
    }

    #[test]
    fn outline_distances_answer_as_a_search_of_every_part_would() {
        // A landmass with a lake, an island in the lake touching the shore at a corner, and an
        // island offshore: points inside another part, in the lake, and at ties between two.
        let lake = LineString::from(vec![
            (2.0, 2.0),
            (8.0, 2.0),
            (8.0, 8.0),
            (2.0, 8.0),
            (2.0, 2.0),
        ]);
        let ring = LineString::from(vec![
            (0.0, 0.0),
            (10.0, 0.0),
            (10.0, 10.0),
            (0.0, 10.0),
            (0.0, 0.0),
        ]);
        let parts = vec![
            MultiPolygon(vec![Polygon::new(ring, vec![lake])]),
            rectangle(2.0, 2.0, 4.0, 4.0),
            rectangle(13.0, 4.0, 14.0, 6.0),
        ];
        let outlines = Outlines::new(&parts);
        let indexes: Vec<RingIndex> = (parts.iter())
            .map(|p| RingIndex::new(&coords_of(&rings_of(p))))
            .collect();
        let all = RingIndex::new(&coords_of(&rings_of(&MultiPolygon(
            parts.iter().flat_map(|p| p.0.clone()).collect(),
        ))));
        for part in 0..parts.len() {
            for step in 0..=40 * 24 {
                let p = Coord {
                    x: -2.0 + f64::from(step % 41) * 0.5,
                    y: -1.0 + f64::from(step / 41) * 0.5,
                };
                let expected = if indexes[part].contains(p) {
                    (0.0, false)
                } else {
                    let own = indexes[part].distance(p);
                    let other = (0..parts.len())
                        .filter(|&q| q != part)
                        .map(|q| indexes[q].distance(p))
                        .fold(f64::INFINITY, f64::min);
                    (own, all.contains(p) || other < own)
                };
                assert_eq!(outlines.distance(part, p), expected, "part {part} at {p:?}");
            }
        }
    }

    #[test]
    fn each_part_gets_exactly_its_regions_cells_near_itself() {
        // A large empty part holding one region and a small crowded one holding nine: the
        // small one must not lose its cells to the large one.
        let big = rectangle(0.0, 0.0, 8.0, 8.0);
        let small = rectangle(20.0, 0.0, 22.0, 2.0);
        let all = MultiPolygon(big.0.iter().chain(&small.0).cloned().collect());
        let lattice = frame(&all, 10, [0.0, 0.0], Tiling::Square);
        let selection = select(&lattice, &[big.clone(), small.clone()], &[1, 9], 1.0, &[]);
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
    fn a_landmass_ringed_by_islands_takes_cells_beyond_the_ring() {
        // One square cell of land for 40 regions, ringed by 24 one-region islands 4 cells out:
        // its own side (nearer it than any island) has too few positions, so it takes the
        // nearest beyond. (How soon the search stops is the benchmark's: bench-quality's
        // archipelago layer took minutes per layout when it searched to the lattice's ends.)
        let land = rectangle(0.0, 0.0, 1.0, 1.0);
        let mut parts = vec![land.clone()];
        for k in 0..24 {
            let angle = f64::from(k) * std::f64::consts::TAU / 24.0;
            let (x, y) = (0.5 + 4.5 * angle.cos(), 0.5 + 4.5 * angle.sin());
            parts.push(rectangle(x - 0.1, y - 0.1, x + 0.1, y + 0.1));
        }
        let all = MultiPolygon(parts.iter().flat_map(|p| p.0.clone()).collect());
        let mut lattice = frame(&all, 64, [0.0, 0.0], Tiling::Square);
        lattice.cell_size = 1.0;
        let mut demands = vec![1; 25];
        demands[0] = 40;
        let selection = select(&lattice, &parts, &demands, 1.0, &[]);
        assert_eq!(selection.cells.len(), 64);
        let distinct: HashSet<(i32, i32)> =
            selection.cells.iter().map(|c| (c.col, c.row)).collect();
        assert_eq!(distinct.len(), 64);
        // 40 cells round a unit square fit within a 7 × 7 square: none farther than 4 cells
        // from it, even past the islands.
        for c in selection.cells.iter().filter(|c| c.part == 0) {
            let centre = lattice.centre(c.col, c.row);
            let far = (centre.x - 0.5).abs().max((centre.y - 0.5).abs());
            assert!(far < 5.0, "{c:?} at {centre:?}");
        }
    }

    #[test]
    fn the_pool_adds_free_cells_of_each_part() {
        let land = rectangle(0.0, 0.0, 4.0, 4.0);
        let lattice = frame(&land, 16, [0.0, 0.0], Tiling::Square);
        let selection = select(&lattice, &[land], &[10], 1.3, &[]);
        assert_eq!(selection.assigned, 10);
        assert_eq!(selection.cells.len(), 13);
        let distinct: HashSet<(i32, i32)> =
            selection.cells.iter().map(|c| (c.col, c.row)).collect();
        assert_eq!(distinct.len(), 13);
    }

    /// A unit lattice with a `side` × `side` block of part 0 at columns and rows 0..side (each
    /// region placed on its own cell) and, last, a lone cell of part 1 at `island`.
    fn mainland_and_island(side: i32, island: Position) -> (Lattice, Vec<usize>, Vec<Coord<f64>>) {
        let mut cells: Vec<LatticeCell> = (0..side * side)
            .map(|k| LatticeCell {
                col: k % side,
                row: k / side,
                score: 2.0,
                part: 0,
            })
            .collect();
        cells.push(LatticeCell {
            col: island.0,
            row: island.1,
            score: 2.0,
            part: 1,
        });
        let lattice = Lattice {
            tiling: Tiling::Square,
            cell_size: 1.0,
            origin: Coord { x: 0.0, y: 0.0 },
            cells,
        };
        let places = (lattice.cells.iter())
            .map(|c| lattice.centre(c.col, c.row))
            .collect();
        let count = lattice.cells.len();
        (lattice, (0..count).collect(), places)
    }

    fn island_at(lattice: &Lattice) -> Position {
        let island = lattice.cells[lattice.cells.len() - 1];
        (island.col, island.row)
    }

    /// The lattice of [`mainland_and_island`] after [`settle`], the island placed at the centre
    /// of cell `place`.
    fn settled(
        side: i32,
        island: Position,
        place: Position,
        adjacency: &[(usize, usize)],
        misplaced: Option<&dyn Fn(usize, Coord<f64>) -> bool>,
    ) -> Lattice {
        let (mut lattice, cells, mut places) = mainland_and_island(side, island);
        places[cells.len() - 1] = lattice.centre(place.0, place.1);
        let homes = Homes {
            places: &places,
            anchors: &Anchors::new(&places, |_| false, 5.0),
            adjacency,
            misplaced,
        };
        settle(&mut lattice, &cells, &homes, &Params::default(), &[]);
        lattice
    }

    #[test]
    fn an_island_far_from_its_fitted_place_goes_beside_its_coast() {
        // A 12 × 12 mainland whose east column's regions lie 60 cells east of their cells (the
        // layout bent the map there, the fit follows the other 132), and an island one cell
        // east of that coast's row 5.
        let side = 12;
        let (lattice, cells, mut places) = mainland_and_island(side, (20, 5));
        let island = cells.len() - 1;
        for place in places.iter_mut().skip(11).step_by(12).take(12) {
            place.x += 60.0;
        }
        places[island] = lattice.centre(72, 5);
        let settled_with = |limit: f64| {
            let mut lattice = lattice.clone();
            let homes = Homes {
                places: &places,
                anchors: &Anchors::new(&places, |i| i != island, limit),
                adjacency: &[],
                misplaced: None,
            };
            settle(&mut lattice, &cells, &homes, &Params::default(), &[]);
            island_at(&lattice)
        };
        // Its anchors are the coast's rows 5, 4 and 6 (nearest first, the tie by index); each
        // puts it one cell (over the fit's scale) east of its own cell, on row 5: beside the
        // coast.
        assert_eq!(settled_with(5.0), (12, 5));
        // Sent to its place under the fit instead, it lands out at sea, far from the coast.
        let (col, _) = settled_with(1000.0);
        assert!(col > 12 + 5, "{col}");
    }

    #[test]
    fn anchors_are_the_nearest_regions_of_large_landmasses() {
        let at = |x: f64, y: f64| Coord { x, y };
        // Regions 0-3 on a large landmass, 4 and 5 on islands.
        let places = [
            at(0.0, 0.0),
            at(1.0, 0.0),
            at(2.0, 0.0),
            at(3.0, 0.0),
            at(2.5, 1.0),
            at(9.0, 9.0),
        ];
        let anchors = Anchors::new(&places, |i| i < 4, 5.0);
        assert!((0..4).all(|i| anchors.of[i].is_empty()));
        // Region 4: 2 and 3 at √1.25, then 1 at √3.25; never the other island.
        assert_eq!(anchors.of[4], vec![2, 3, 1]);
        assert_eq!(anchors.of[5], vec![3, 2, 1]);
        // No large landmass: nothing places an island.
        let none = Anchors::new(&places, |_| false, 5.0);
        assert!(none.of.iter().all(Vec::is_empty));
    }

    #[test]
    fn the_fit_from_running_sums_is_the_metrics_fit_also_after_a_shift() {
        // Points on a skewed spiral, fitted onto a scaled, shifted and disturbed copy.
        let g: Vec<Coord<f64>> = (0..30)
            .map(|k| {
                let t = f64::from(k) * 0.7;
                Coord {
                    x: t * t.cos() + 40.0,
                    y: 0.5 * t * t.sin() - 7.0,
                }
            })
            .collect();
        let c: Vec<Coord<f64>> = (g.iter().enumerate())
            .map(|(k, &p)| {
                p * 1.7
                    + Coord { x: 3.0, y: -2.0 }
                    + Coord {
                        x: (k % 3) as f64,
                        y: (k % 5) as f64 * 0.3,
                    }
            })
            .collect();
        let check = |g: &[Coord<f64>], sums: FitSums| {
            let (scale, offset) = crate::core::metrics::fit(g, &c);
            let residual: f64 = (g.iter().zip(&c))
                .map(|(&p, &q)| {
                    let r = q - (p * scale + offset);
                    dot(r, r)
                })
                .sum::<f64>()
                / (scale * scale);
            let (s, t, r) = sums.fit();
            assert!(
                (s - scale).abs() < 1e-9 && (t - offset).x.abs() < 1e-9,
                "{s} {scale}"
            );
            assert!(
                (t - offset).y.abs() < 1e-9 && (r - residual).abs() < 1e-6,
                "{r} {residual}"
            );
        };
        let all = FitSums::of(g.iter().copied().zip(c.iter().copied()));
        check(&g, all);
        // The first ten points moved by (2, −3): the shifted sums give the moved points' fit.
        let d = Coord { x: 2.0, y: -3.0 };
        let block = FitSums::of(g[..10].iter().copied().zip(c[..10].iter().copied()));
        let moved: Vec<Coord<f64>> = (g.iter().enumerate())
            .map(|(k, &p)| if k < 10 { p + d } else { p })
            .collect();
        check(&moved, all.shifted(&block, d));
    }

    #[test]
    fn a_block_moves_to_where_its_regions_are_measured_from() {
        // The island's cell lies 4 cells east of its place, column 6: it moves there, and the
        // mainland, already on its places, stays.
        let lattice = settled(3, (10, 1), (6, 1), &[], None);
        assert_eq!(island_at(&lattice), (6, 1));
        for (k, cell) in lattice.cells[..9].iter().enumerate() {
            assert_eq!((cell.col, cell.row), (k as i32 % 3, k as i32 / 3));
        }
    }

    #[test]
    fn a_block_leaves_another_landmass_before_anything_else() {
        // A mainland of 100 regions holds the fit nearly still. The island's place is column
        // 12, but west of x = 13 counts as nearer the mainland (in the fitted frame): the island
        // takes column 13 (centre 13.5), the nearest position east of that.
        let misplaced = |region: usize, p: Coord<f64>| region == 100 && p.x < 13.0;
        let lattice = settled(10, (16, 1), (12, 1), &[], Some(&misplaced));
        assert_eq!(island_at(&lattice), (13, 1));
    }

    #[test]
    fn a_block_never_lands_on_another_nor_makes_a_hole() {
        // The island's place is the mainland's centre cell: it ends beside the block, on a free
        // position, leaving no hole.
        let lattice = settled(3, (10, 1), (1, 1), &[], None);
        let positions: Vec<Position> = lattice.cells.iter().map(|c| (c.col, c.row)).collect();
        let distinct: HashSet<Position> = positions.iter().copied().collect();
        assert_eq!(distinct.len(), 10);
        assert_eq!(LayoutShape::of(&positions, Tiling::Square).holes(), 0);
        let island = island_at(&lattice);
        let beside = lattice.cells[..9]
            .iter()
            .any(|c| Tiling::Square.sharing_an_edge((c.col, c.row), island));
        assert!(beside, "the island went to {island:?}");
    }

    #[test]
    fn a_pair_across_two_landmasses_holds_their_blocks_together() {
        // Without the pair the island would go 2 cells east to its place; its neighbour on the
        // mainland's east edge keeps it beside the block.
        let lattice = settled(3, (3, 1), (5, 1), &[(5, 9)], None);
        assert_eq!(island_at(&lattice), (3, 1));
    }

    #[test]
    fn with_hexagons_an_island_keeps_off_the_mainland() {
        // A one-region island a third of a cell off the coast: its nearest hexagons share an
        // edge with the mainland's, which would make the two one piece.
        let big = rectangle(0.0, 0.0, 8.0, 8.0);
        let small = rectangle(8.3, 3.9, 8.5, 4.1);
        let all = MultiPolygon(big.0.iter().chain(&small.0).cloned().collect());
        for orientation in [HexOrientation::Pointy, HexOrientation::Flat] {
            let tiling = Tiling::Hex(orientation);
            let lattice = frame(&all, 65, [0.0, 0.0], tiling);
            let selection = select(&lattice, &[big.clone(), small.clone()], &[64, 1], 1.0, &[]);
            let island: Vec<Position> = (selection.cells.iter())
                .filter(|c| c.part == 1)
                .map(|c| (c.col, c.row))
                .collect();
            assert_eq!(island.len(), 1);
            let joined = (selection.cells.iter())
                .filter(|c| c.part == 0)
                .any(|c| tiling.sharing_an_edge((c.col, c.row), island[0]));
            assert!(!joined, "{orientation:?}: the island joins the mainland");
        }
    }

    /// The number of edge-connected pieces the cells of `cells` make.
    fn pieces(tiling: Tiling, cells: &[LatticeCell]) -> usize {
        let mut left: Vec<Position> = cells.iter().map(|c| (c.col, c.row)).collect();
        let mut count = 0;
        while let Some(start) = left.pop() {
            count += 1;
            let mut stack = vec![start];
            while let Some(p) = stack.pop() {
                let (joined, rest): (Vec<Position>, Vec<Position>) =
                    left.iter().partition(|&&q| tiling.sharing_an_edge(p, q));
                left = rest;
                stack.extend(joined);
            }
        }
        count
    }

    #[test]
    fn a_strip_thinner_than_a_cell_takes_one_piece_of_cells() {
        // 30 regions in a north-south strip 0.55 cells wide (a long thin country): no cell lies
        // wholly inside, and the best-covered pointy hexagons alternate with worse ones row by
        // row, so the 30 best-scored alone make two pieces here (the generated strip layer
        // through the command line: 7, BENCHMARKS.md).
        let strip = rectangle(0.0, 0.0, 0.55, 16.5);
        for tiling in [
            Tiling::Square,
            Tiling::Hex(HexOrientation::Pointy),
            Tiling::Hex(HexOrientation::Flat),
        ] {
            let lattice = frame(&strip, 30, [0.0, 0.0], tiling);
            let selection = select(&lattice, std::slice::from_ref(&strip), &[30], 1.0, &[]);
            assert_eq!(selection.cells.len(), 30);
            assert_eq!(pieces(tiling, &selection.cells), 1, "{tiling:?}");
        }
    }
}
