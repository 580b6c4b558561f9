//! Step 4a″ (method.md §10, groups kept together): the regions of one group on one landmass —
//! a *block* — take one edge-connected patch of cells, and the patches lie like the groups.
//!
//! A landmass's cells are split among its blocks by an exact transport: block b takes k_b
//! cells (as many as it has regions) and the split minimises the summed costs of the cells to
//! their blocks ([`transport`]). Without a gap the cost is the squared distance from the
//! block's territory in the plain assignment of the landmass's regions (method.md §6), so a
//! patch has its group's shape; each round re-draws the territories as the patches' main
//! pieces and bans the stray cells, and a split the rounds cannot mend falls back to the cost
//! of the squared distance from the block's centre (the mean of its moved centroids), whose
//! optimum is a power diagram of convex, hence whole, patches. Then each block's regions are
//! assigned among its own cells, and the refinement only swaps cells within a block.
//!
//! With `group_gap` 1 no cell of one group may touch a cell of another: on convex patches, a
//! patch gives up every cell touching the patch of a block with fewer regions (the larger block
//! yields, so a small group keeps its shape), and the split is made again with each patch's
//! size corrected by what it gave up, until each keeps its k_b cells.

use super::assign;
use super::grid::{Lattice, LatticeCell};
use super::tiling::{Position, Tiling};
use super::{GroupMetrics, Tick};
use geo::Coord;
use rustc_hash::{FxHashMap, FxHashSet};
use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

/// Which block each region belongs to.
#[derive(Clone, Debug, PartialEq)]
pub struct Blocks {
    /// Per region, its block.
    pub of: Vec<usize>,
    /// Per block, its landmass (a part of the moved outline).
    pub landmass: Vec<usize>,
    /// Per block, its group: an index into the layer's groups, the regions without a group
    /// each a group of their own.
    pub group: Vec<usize>,
}

impl Blocks {
    /// The blocks of regions on landmasses `landmass_of` in groups `group_of` (`None`: a group
    /// of its own). Groups and blocks are numbered by their first region, so that neither the
    /// groups' names nor the regions' order (already geometric) can change a layout.
    pub fn new(landmass_of: &[usize], group_of: &[Option<usize>]) -> Blocks {
        let mut groups: FxHashMap<Option<usize>, usize> = FxHashMap::default();
        let mut keys: FxHashMap<(usize, usize), usize> = FxHashMap::default();
        let mut blocks = Blocks {
            of: Vec::with_capacity(group_of.len()),
            landmass: Vec::new(),
            group: Vec::new(),
        };
        let mut own_groups = 0;
        for (&landmass, &group) in landmass_of.iter().zip(group_of) {
            let next = groups.len() + own_groups;
            let group = match group {
                Some(g) => *groups.entry(Some(g)).or_insert(next),
                None => {
                    own_groups += 1;
                    next
                }
            };
            let next_block = blocks.landmass.len();
            let block = *keys.entry((landmass, group)).or_insert(next_block);
            if block == next_block {
                blocks.landmass.push(landmass);
                blocks.group.push(group);
            }
            blocks.of.push(block);
        }
        blocks
    }

    pub fn count(&self) -> usize {
        self.landmass.len()
    }

    /// Per block, its regions.
    fn members(&self) -> Vec<Vec<usize>> {
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); self.count()];
        for (i, &b) in self.of.iter().enumerate() {
            members[b].push(i);
        }
        members
    }
}

/// The cells each of `landmasses` landmasses needs for its blocks a cell apart: per block its
/// regions, and for a landmass of several blocks, a first guess at its moats (half the ring
/// round a compact patch, 2√k + 2 cells; [`assign`] corrects it within the pool's spare cells).
pub fn cells_with_gaps(blocks: &Blocks, landmasses: usize) -> Vec<usize> {
    let regions: Vec<usize> = blocks.members().iter().map(Vec::len).collect();
    let mut per_landmass = vec![0usize; landmasses];
    let mut several = vec![0usize; landmasses];
    for (b, &p) in blocks.landmass.iter().enumerate() {
        several[p] += 1;
        per_landmass[p] += regions[b];
    }
    for (b, &p) in blocks.landmass.iter().enumerate() {
        if several[p] > 1 {
            per_landmass[p] += moat_guess(regions[b]);
        }
    }
    per_landmass
}

/// How far, in cells, [`dock`] looks around an island block's place for room.
const DOCK_REACH: i32 = 8;

/// Puts each island block of a group — a block alone on its landmass, whose group has a larger
/// block elsewhere (Nantucket beside Massachusetts) — where it lies from that larger block,
/// measured on the map: the offset of their regions' area centroids (`places`), scaled by the
/// layout's §8 fit. The global fit alone can leave an island many cells out to sea where the
/// Snake moved the coast; its own state's block is the nearer reference. The block moves whole,
/// to the nearest shift (within [`DOCK_REACH`] cells of that place) whose cells are free, touch
/// no other group's cells with `gap`, and, for hexagons, share no edge with another landmass
/// (see `landmass::keeps_landmasses_apart`); it stays if none is nearer than where it is and
/// its cells there fit. A group's largest block alone on its landmass moves only where its
/// cells break the gap beside a larger block, to the nearest place that keeps it.
/// `lattice.cells[i]` is region i's cell. A block holding a pinned cell (`anchored`) stays.
pub fn dock(
    lattice: &mut Lattice,
    blocks: &Blocks,
    places: &[Coord<f64>],
    gap: bool,
    anchored: &[usize],
) {
    let count = blocks.count();
    let members = blocks.members();
    let landmasses = blocks.landmass.iter().map(|&p| p + 1).max().unwrap_or(0);
    let mut on_landmass = vec![0usize; landmasses];
    for &p in &blocks.landmass {
        on_landmass[p] += 1;
    }
    let groups = blocks.group.iter().map(|&g| g + 1).max().unwrap_or(0);
    let mut largest: Vec<Option<usize>> = vec![None; groups];
    for b in 0..count {
        let g = &mut largest[blocks.group[b]];
        if g.is_none_or(|l| members[b].len() > members[l].len()) {
            *g = Some(b);
        }
    }
    let centre = |i: usize, lattice: &Lattice| {
        let c = lattice.cells[i];
        lattice.centre(c.col, c.row)
    };
    let centres: Vec<Coord<f64>> = (0..places.len()).map(|i| centre(i, lattice)).collect();
    let (scale, _) = super::metrics::fit(&centres, places);
    let tiling = lattice.tiling;
    let apart = super::landmass::keeps_landmasses_apart(tiling);
    for b in (0..count).filter(|b| !anchored.contains(b)) {
        // Only a block alone on its landmass moves: it takes its landmass along whole.
        if on_landmass[blocks.landmass[b]] != 1 {
            continue;
        }
        let owner: FxHashMap<Position, usize> = (lattice.cells.iter().enumerate())
            .filter(|&(i, _)| blocks.of[i] != b)
            .map(|(i, c)| ((c.col, c.row), i))
            .collect();
        let fits = |(dc, dr): Position| {
            members[b].iter().all(|&i| {
                let p = (lattice.cells[i].col + dc, lattice.cells[i].row + dr);
                let clash = |n: Position, edge: bool| {
                    owner.get(&n).is_some_and(|&j| {
                        (gap && blocks.group[blocks.of[j]] != blocks.group[b])
                            || (edge
                                && apart
                                && blocks.landmass[blocks.of[j]] != blocks.landmass[b])
                    })
                };
                !owner.contains_key(&p)
                    && !tiling
                        .touching_positions(p)
                        .any(|n| clash(n, tiling.sharing_an_edge(p, n)))
            })
        };
        // Whether a block of another group touches block `b` and is larger (or as large and
        // earlier).
        let gives_way = || {
            (members[b].iter()).any(|&i| {
                let c = lattice.cells[i];
                tiling.touching_positions((c.col, c.row)).any(|n| {
                    owner.get(&n).is_some_and(|&j| {
                        let other = blocks.of[j];
                        blocks.group[other] != blocks.group[b]
                            && (members[other].len(), std::cmp::Reverse(other))
                                > (members[b].len(), std::cmp::Reverse(b))
                    })
                })
            })
        };
        let mean_of = |f: &dyn Fn(usize) -> Coord<f64>, block: usize| {
            mean(members[block].iter().map(|&i| f(i)))
        };
        let here = mean_of(&|i| centre(i, lattice), b);
        let main = largest[blocks.group[b]].filter(|&l| l != b);
        let wanted = match main {
            Some(main) => {
                mean_of(&|i| centre(i, lattice), main)
                    + (mean_of(&|i| places[i], b) - mean_of(&|i| places[i], main)) / scale
            }
            // A group's largest block alone on its landmass (an island province beside the
            // mainland) stays, unless its cells touch a larger block of another group across
            // the gap (`landmass::settle` places landmasses knowing nothing of groups): then
            // it goes to the nearest place that keeps the gap. Of two alike, the later gives
            // way.
            None if gap && gives_way() => here,
            None => continue,
        };
        let first = (
            lattice.cells[members[b][0]].col,
            lattice.cells[members[b][0]].row,
        );
        let aim = lattice.position_of(lattice.centre(first.0, first.1) + (wanted - here));
        let aim = (aim.0 - first.0, aim.1 - first.1);
        let off = |shift: Position| {
            let p = lattice.centre(first.0 + shift.0, first.1 + shift.1);
            let q = lattice.centre(first.0, first.1);
            let d = (p - q) - (wanted - here);
            d.x * d.x + d.y * d.y
        };
        let mut shifts: Vec<Position> = (-DOCK_REACH..=DOCK_REACH)
            .flat_map(|dr| (-DOCK_REACH..=DOCK_REACH).map(move |dc| (aim.0 + dc, aim.1 + dr)))
            .collect();
        shifts.sort_by(|&a, &b| off(a).total_cmp(&off(b)).then((a.1, a.0).cmp(&(b.1, b.0))));
        // Where it is, unless a cell there touches another group's across the gap (an island
        // `landmass::settle` put beside its coast): then the nearest place that fits.
        let stay = if fits((0, 0)) {
            off((0, 0))
        } else {
            f64::INFINITY
        };
        if let Some(&(dc, dr)) = shifts
            .iter()
            .take_while(|&&s| off(s) < stay)
            .find(|&&s| fits(s))
        {
            for &i in &members[b] {
                lattice.cells[i].col += dc;
                lattice.cells[i].row += dr;
            }
        }
    }
}

/// A first guess at the moat of a patch of `k` cells: half the ring round a compact patch.
fn moat_guess(k: usize) -> usize {
    2 * (k as f64).sqrt().ceil() as usize + 2
}

/// Assigns the regions to cells so that each block's regions take one patch: `lattice.cells`
/// holds each landmass's cells (tagged with its part), `points` are the moved centroids. With
/// `gap`, patches of different groups keep a cell apart, which needs more cells than regions:
/// `lattice.cells` then holds spare cells too. On return `lattice.cells` holds exactly the
/// regions' cells, in region order; the result gives each region's index into them (the
/// identity). A pinned region (`pinned`: position → region, each position among
/// `lattice.cells`) keeps its position, which its block's patch always holds. `None` when
/// `tick` stops it.
pub fn assign(
    lattice: &mut Lattice,
    blocks: &Blocks,
    points: &[Coord<f64>],
    gap: bool,
    pinned: &FxHashMap<Position, usize>,
    tick: Tick,
) -> Option<Vec<usize>> {
    let m = points.len();
    let count = blocks.count();
    let members = blocks.members();
    let landmasses = blocks.landmass.iter().map(|&p| p + 1).max().unwrap_or(0);
    // The shares of the work: the plain assignment that outlines the territories (without a
    // gap), then the assignment within the patches.
    let share = |regions: usize| regions as f64 / m.max(1) as f64 / 2.0;
    let mut patches: Vec<Vec<Position>> = vec![Vec::new(); count];
    for landmass in 0..landmasses {
        let own: Vec<usize> = (0..count)
            .filter(|&b| blocks.landmass[b] == landmass)
            .collect();
        let cells: Vec<Position> = (lattice.cells.iter())
            .filter(|c| c.part == landmass)
            .map(|c| (c.col, c.row))
            .collect();
        let demand: Vec<usize> = own.iter().map(|&b| members[b].len()).collect();
        let centres: Vec<Coord<f64>> = (own.iter())
            .map(|&b| mean(members[b].iter().map(|&i| points[i])))
            .collect();
        let local: FxHashMap<usize, usize> = own.iter().enumerate().map(|(k, &b)| (b, k)).collect();
        let fixed: FxHashMap<Position, usize> = (pinned.iter())
            .filter_map(|(&p, &i)| Some((p, *local.get(&blocks.of[i])?)))
            .collect();
        let split = Split {
            lattice,
            cells: &cells,
            centres: &centres,
            demand: &demand,
            gap: gap && own.len() > 1,
            fixed: &fixed,
        };
        // Shaped territories pulled a cell apart lose their way (us_counties: 0.81 of the
        // neighbouring states within 2 cells, against 0.84 with convex patches): the spare
        // cells between them lie out of every territory's reach. A gap takes convex patches.
        let found = if own.len() == 1 || split.gap {
            split.patches(&Cost::Power)
        } else {
            // The plain assignment of the landmass's regions outlines each block's territory:
            // shaped like its group, as the regions lie after the Snake.
            let regions: Vec<usize> = own.iter().flat_map(|&b| members[b].clone()).collect();
            let at: Vec<Coord<f64>> = (cells.iter()).map(|&(c, r)| lattice.centre(c, r)).collect();
            let moved: Vec<Coord<f64>> = regions.iter().map(|&i| points[i]).collect();
            let work = share(regions.len());
            let choice = assign::assign(&moved, &at, &|done| tick(done * work))?;
            let territory: FxHashMap<Position, usize> = (regions.iter().zip(choice))
                .map(|(&i, k)| (cells[k], local[&blocks.of[i]]))
                .collect();
            // A territory in pieces that the rounds cannot mend falls back to convex patches.
            let (shaped, strays) = split.rounds(&Cost::Territory(territory));
            if strays == 0 {
                shaped
            } else {
                let (convex, fewer) = split.rounds(&Cost::Power);
                if fewer < strays {
                    convex
                } else {
                    shaped
                }
            }
        };
        for (k, patch) in found.into_iter().enumerate() {
            patches[own[k]] = patch;
        }
    }
    // Each block's pinned regions on their pins, the others among its patch's other cells.
    let mut placed: Vec<Position> = vec![(0, 0); m];
    for (&p, &i) in pinned {
        placed[i] = p;
    }
    let pinned_regions: FxHashSet<usize> = pinned.values().copied().collect();
    for (b, members) in members.iter().enumerate() {
        let regions: Vec<usize> = (members.iter().copied())
            .filter(|i| !pinned_regions.contains(i))
            .collect();
        let mut patch: Vec<Position> = (patches[b].iter().copied())
            .filter(|p| !pinned.contains_key(p))
            .collect();
        if patch.len() != regions.len() {
            // A patch that could not keep a pin (a moat took it) has a cell too many or too
            // few for its free regions: the farthest from their centre go, the nearest free
            // positions come.
            let centre = mean(regions.iter().map(|&i| points[i]));
            let far = |p: &Position| {
                let c = lattice.centre(p.0, p.1) - centre;
                c.x * c.x + c.y * c.y
            };
            patch.sort_by(|a, b| far(a).total_cmp(&far(b)).then(a.cmp(b)));
            patch.truncate(regions.len());
            while patch.len() < regions.len() {
                let taken = |p: Position| {
                    pinned.contains_key(&p)
                        || patch.contains(&p)
                        || patches.iter().any(|other| other.contains(&p))
                };
                patch.push(nearest_free(lattice, centre, |p| !taken(p)));
            }
        }
        let at: Vec<Coord<f64>> = patch.iter().map(|&(c, r)| lattice.centre(c, r)).collect();
        let own: Vec<Coord<f64>> = regions.iter().map(|&i| points[i]).collect();
        let work = share(regions.len());
        let choices = assign::assign(&own, &at, &|done| tick(done * work))?;
        for (&i, k) in regions.iter().zip(choices) {
            placed[i] = patch[k];
        }
    }
    lattice.cells = (placed.iter().zip(&blocks.of))
        .map(|(&(col, row), &b)| LatticeCell {
            col,
            row,
            score: 0.0,
            part: blocks.landmass[b],
        })
        .collect();
    Some((0..m).collect())
}

fn mean(points: impl Iterator<Item = Coord<f64>>) -> Coord<f64> {
    let (sum, n) = points.fold((Coord { x: 0.0, y: 0.0 }, 0.0), |(s, n), p| {
        (s + p, n + 1.0)
    });
    if n > 0.0 {
        sum / n
    } else {
        sum
    }
}

/// Rounds of splitting again: a patch in pieces bans its stray cells and the split is made
/// again; with a gap, each round also corrects the patches' sizes by what their moats took.
/// Both settle in two or three rounds on real layers.
const SPLIT_ROUNDS: usize = 12;

/// What a cell costs a block.
enum Cost {
    /// The squared distance from the block's centre: convex patches (a power diagram), which
    /// hold together, but round where a group is long (Tennessee's patch misses North
    /// Carolina and Virginia). With a gap, a cell far beyond a block's reach costs it more
    /// ([`Split::power_costs`]).
    Power,
    /// The squared distance, in cells, from the block's territory (position → block), which
    /// each round re-draws as the main pieces of the patches: patches shaped like the groups.
    /// On us_counties 0.95 of the neighbouring states touch against 0.86 with `Power`.
    Territory(FxHashMap<Position, usize>),
}

/// How far beyond the radius of a round patch of its size, in cells, a block reaches before a
/// cell costs it more ([`Split::power_costs`]).
const REACH_MARGIN: f64 = 2.0;

/// The weight of the square of how far beyond its reach a cell lies from a block, against the
/// squared distance ([`Split::power_costs`]).
const BEYOND_REACH: f64 = 0.5;

/// How far, in cells, a territory reaches: a block farther from a cell than this does not
/// compete for it.
const TERRITORY_REACH: i32 = 4;

/// One landmass's cells (best scored first) and its blocks' cell counts.
struct Split<'a> {
    lattice: &'a Lattice,
    cells: &'a [Position],
    /// The blocks' centres: the means of their moved centroids.
    centres: &'a [Coord<f64>],
    demand: &'a [usize],
    /// Whether patches of different blocks keep a cell apart.
    gap: bool,
    /// The pinned positions, each with its block: always its block's, never a moat.
    fixed: &'a FxHashMap<Position, usize>,
}

impl Split<'_> {
    /// The [`Cost::Power`] of cell centre `p` to the blocks among its nearest
    /// ([`nearest_centres`]). With a gap, a cell beyond a block's reach — the radius of a round
    /// patch of its `sizes` cells, plus [`REACH_MARGIN`] — costs it [`BEYOND_REACH`] times the
    /// square of the excess more: the rounds' bans and moats press hardest on small blocks,
    /// which the plain squared distance lets the split send far away (one far cell costs less
    /// than a chain of larger patches each giving up a cell). Adjacent states within two cells,
    /// us_counties, seeds 0 and 1: squares 0.850 / 0.850 → 0.850 / 0.860, hexagons 0.841 /
    /// 0.841 → 0.860 / 0.850; 2,500 Voronoi regions in 90 groups 0.848 → 0.866 (squares),
    /// 0.853 → 0.866 (hexagons); adjacency, location and whole blocks unchanged. A larger factor
    /// (2, 10) did worse.
    fn power_costs(&self, p: Coord<f64>, sizes: &[usize]) -> Vec<(usize, f64)> {
        let mut costs = nearest_centres(self.centres, p);
        if self.gap {
            for (b, cost) in costs.iter_mut() {
                let radius = (sizes[*b] as f64 / std::f64::consts::PI).sqrt();
                let reach = (radius + REACH_MARGIN) * self.lattice.cell_size;
                let beyond = (cost.sqrt() - reach).max(0.0);
                *cost += BEYOND_REACH * beyond * beyond;
            }
        }
        costs
    }

    /// The rounds' best patches and, without a gap, how many cells stray from their patch's
    /// main piece; with a gap, patches trimmed or grown to their sizes.
    fn patches(&self, cost: &Cost) -> Vec<Vec<Position>> {
        let (mut kept, amiss) = self.rounds(cost);
        let settled = (kept.iter().zip(self.demand)).all(|(patch, &k)| patch.len() == k);
        if self.gap && (amiss > 0 || !settled) {
            // A patch drops its strays, but not its pins (which the patches around them keep
            // a moat from), and is trimmed or grown to its size.
            for (b, patch) in kept.iter_mut().enumerate() {
                let mut main = pieces_of(self.lattice.tiling, patch).swap_remove(0);
                let pins: Vec<Position> = (patch.iter().copied())
                    .filter(|p| self.fixed.get(p) == Some(&b) && !main.contains(p))
                    .collect();
                main.extend(pins);
                *patch = main;
            }
            settle_sizes(
                self.lattice,
                &mut kept,
                self.centres,
                self.demand,
                self.fixed,
            );
        }
        kept
    }

    /// The splitting rounds: the best round's patches, and how many of their cells are astray
    /// (outside their patch's main piece) or amiss (a patch's size off its demand).
    fn rounds(&self, cost: &Cost) -> (Vec<Vec<Position>>, usize) {
        let tiling = self.lattice.tiling;
        let cells = self.cells;
        let demand = self.demand;
        let blocks = demand.len();
        let at: Vec<Coord<f64>> = (cells.iter())
            .map(|&(c, r)| self.lattice.centre(c, r))
            .collect();
        let index: FxHashMap<Position, usize> =
            cells.iter().enumerate().map(|(k, &p)| (p, k)).collect();
        // The block that yields a moat to the other: the one with more regions (then the later).
        let yields = |a: usize, b: usize| (demand[a], a) > (demand[b], b);
        // With a gap, each patch starts with a guess at its moat ([`cells_with_gaps`]).
        let mut sizes: Vec<usize> = (demand.iter())
            .map(|&k| if self.gap { k + moat_guess(k) } else { k })
            .collect();
        let mut banned: FxHashSet<(usize, usize)> = FxHashSet::default();
        let mut territory = match cost {
            Cost::Territory(t) => Some(t.clone()),
            Cost::Power => None,
        };
        let mut best: Option<(usize, Vec<Vec<Position>>)> = None;
        // Each round's transport starts from the last one's block potentials.
        let mut potential = vec![0.0; blocks];
        for _ in 0..SPLIT_ROUNDS {
            let total: usize = sizes.iter().sum();
            if total > cells.len() {
                shrink_to_fit(&mut sizes, demand, total - cells.len());
            }
            // The best-scored cells, as many as the patches take: the landmass's shape,
            // without free cells inside it to keep apart patches that should meet.
            let used = total.min(cells.len());
            let options: Vec<Vec<(usize, f64)>> = (0..used)
                .map(|x| {
                    if let Some(&b) = self.fixed.get(&cells[x]) {
                        return vec![(b, 0.0)];
                    }
                    let all = match &territory {
                        Some(t) => {
                            near_territories(t, cells[x], || nearest_centres(self.centres, at[x]))
                        }
                        None => self.power_costs(at[x], &sizes),
                    };
                    let allowed: Vec<(usize, f64)> = (all.iter().copied())
                        .filter(|&(b, _)| !banned.contains(&(x, b)))
                        .collect();
                    // A cell every block near it has banned stays open to them all.
                    if allowed.is_empty() {
                        all
                    } else {
                        allowed
                    }
                })
                .collect();
            let holder = transport(&options, &sizes, &mut potential);
            let mut claimed: Vec<Vec<Position>> = vec![Vec::new(); blocks];
            let mut kept: Vec<Vec<Position>> = vec![Vec::new(); blocks];
            for (k, &h) in holder.iter().enumerate() {
                claimed[h].push(cells[k]);
                // A pinned cell cannot yield: the cell of another block beside it does.
                let moat = self.gap
                    && !self.fixed.contains_key(&cells[k])
                    && (tiling.touching_positions(cells[k])).any(|n| {
                        (index.get(&n)).is_some_and(|&j| {
                            holder.get(j).is_some_and(|&o| {
                                o != h && (yields(h, o) || self.fixed.contains_key(&n))
                            })
                        })
                    });
                if !moat {
                    kept[h].push(cells[k]);
                }
            }
            let mut amiss = 0;
            for (b, patch) in kept.iter().enumerate() {
                for stray in pieces_of(tiling, patch).drain(1..).flatten() {
                    banned.insert((index[&stray], b));
                    amiss += 1;
                }
                amiss += patch.len().abs_diff(demand[b]);
            }
            let kept_sizes: Vec<usize> = kept.iter().map(Vec::len).collect();
            if best.as_ref().is_none_or(|(fewest, _)| amiss < *fewest) {
                best = Some((amiss, kept));
            }
            if amiss == 0 {
                break;
            }
            if let Some(t) = territory.as_mut() {
                t.clear();
                for (b, patch) in claimed.iter().enumerate() {
                    t.extend(
                        pieces_of(tiling, patch)
                            .swap_remove(0)
                            .into_iter()
                            .map(|p| (p, b)),
                    );
                }
            }
            if self.gap {
                // Half the difference each round, so that the sizes settle rather than swing:
                // a moat's size jumps with its patch's. Rounded up both ways: rounded down, a
                // patch one cell over its size never shrank, and its extra cell strayed and was
                // banned round after round (us_counties, with the gap: 0.841 of the adjacent
                // states within 2 cells, 0.850 rounded up; 40 Voronoi groups 0.898 → 0.949).
                for (b, size) in sizes.iter_mut().enumerate() {
                    let (k, now) = (demand[b], kept_sizes[b]);
                    if now < k {
                        *size += (k - now).div_ceil(2);
                    } else {
                        *size = (*size - (now - k).div_ceil(2)).max(k);
                    }
                }
            }
        }
        let (amiss, kept) = best.unwrap_or_default();
        (kept, amiss)
    }
}

/// The blocks whose centres are among the [`CANDIDATE_BLOCKS`] nearest to `p`, with the
/// squared distances.
fn nearest_centres(centres: &[Coord<f64>], p: Coord<f64>) -> Vec<(usize, f64)> {
    let mut all: Vec<(usize, f64)> = (centres.iter().enumerate())
        .map(|(b, c)| (b, (p.x - c.x).powi(2) + (p.y - c.y).powi(2)))
        .collect();
    if all.len() > CANDIDATE_BLOCKS {
        all.select_nth_unstable_by(CANDIDATE_BLOCKS - 1, |a, b| {
            a.1.total_cmp(&b.1).then(a.0.cmp(&b.0))
        });
        all.truncate(CANDIDATE_BLOCKS);
        all.sort_unstable_by_key(|&(b, _)| b);
    }
    all
}

/// The blocks whose territory comes within [`TERRITORY_REACH`] of `p`, with the squared
/// distance in cells to its nearest position (0 on it); for a cell out of every territory's
/// reach, the `nearest` blocks by centre, each costing more than any territory in reach.
fn near_territories(
    territory: &FxHashMap<Position, usize>,
    p: Position,
    nearest: impl Fn() -> Vec<(usize, f64)>,
) -> Vec<(usize, f64)> {
    let mut found: Vec<(usize, f64)> = Vec::new();
    for dr in -TERRITORY_REACH..=TERRITORY_REACH {
        for dc in -TERRITORY_REACH..=TERRITORY_REACH {
            if let Some(&b) = territory.get(&(p.0 + dc, p.1 + dr)) {
                let d = f64::from(dc * dc + dr * dr);
                match found.iter_mut().find(|(o, _)| *o == b) {
                    Some(entry) => entry.1 = entry.1.min(d),
                    None => found.push((b, d)),
                }
            }
        }
    }
    if found.is_empty() {
        let beyond = f64::from(2 * TERRITORY_REACH * TERRITORY_REACH + 1);
        return (nearest().into_iter())
            .map(|(b, d)| (b, beyond + d))
            .collect();
    }
    found.sort_unstable_by_key(|&(b, _)| b);
    found
}

/// Lowers the patch sizes above their demand by `over` in total, largest excess first.
fn shrink_to_fit(sizes: &mut [usize], demand: &[usize], mut over: usize) {
    while over > 0 {
        let Some(b) = (0..sizes.len())
            .filter(|&b| sizes[b] > demand[b])
            .max_by_key(|&b| (sizes[b] - demand[b], Reverse(b)))
        else {
            return;
        };
        sizes[b] -= 1;
        over -= 1;
    }
}

/// Trims patches with too many cells (farthest from their centre first, never splitting the
/// patch, never a `fixed` one) and grows those with too few into the free positions nearest their centre that touch
/// no other patch and extend it, else that touch no other patch, so that each has exactly its
/// demand.
fn settle_sizes(
    lattice: &Lattice,
    kept: &mut [Vec<Position>],
    centres: &[Coord<f64>],
    demand: &[usize],
    fixed: &FxHashMap<Position, usize>,
) {
    let tiling = lattice.tiling;
    let distance = |b: usize, p: Position| {
        let c = lattice.centre(p.0, p.1);
        (c.x - centres[b].x).powi(2) + (c.y - centres[b].y).powi(2)
    };
    for b in 0..kept.len() {
        while kept[b].len() > demand[b] {
            let patch = &kept[b];
            let mut order: Vec<usize> = (0..patch.len())
                .filter(|&k| !fixed.contains_key(&patch[k]))
                .collect();
            if order.is_empty() {
                break;
            }
            order.sort_by(|&x, &y| distance(b, patch[y]).total_cmp(&distance(b, patch[x])));
            let drop = (order.iter().copied())
                .find(|&k| {
                    let rest: Vec<Position> = (patch.iter().enumerate())
                        .filter(|&(j, _)| j != k)
                        .map(|(_, &p)| p)
                        .collect();
                    pieces_of(tiling, &rest).len() == 1
                })
                .unwrap_or(order[0]);
            kept[b].swap_remove(drop);
        }
    }
    let mut owner: FxHashMap<Position, usize> = FxHashMap::default();
    for (b, patch) in kept.iter().enumerate() {
        for &p in patch {
            owner.insert(p, b);
        }
    }
    for b in 0..kept.len() {
        while kept[b].len() < demand[b] {
            let apart = |p: Position| {
                (tiling.touching_positions(p)).all(|n| owner.get(&n).is_none_or(|&o| o == b))
            };
            let free = |p: &Position| !owner.contains_key(p);
            let edge: Vec<Position> = (kept[b].iter())
                .flat_map(|&p| tiling.edge_neighbours(p).to_vec())
                .filter(free)
                .collect();
            let nearest = |set: &mut dyn Iterator<Item = Position>| {
                set.min_by(|&p, &q| distance(b, p).total_cmp(&distance(b, q)).then(p.cmp(&q)))
            };
            // The gap the user asked for comes before the patch's holding together: boxed in,
            // a patch takes the free position apart from the others nearest its centre.
            let p = nearest(&mut edge.iter().copied().filter(|&p| apart(p)))
                .unwrap_or_else(|| nearest_free(lattice, centres[b], |p| free(&p) && apart(p)));
            owner.insert(p, b);
            kept[b].push(p);
        }
    }
}

/// The position nearest to `centre` (by lattice steps, then row and column) that is `free`,
/// searched in rings of growing distance: the lattice is unbounded and the occupied positions
/// finite, so one is found.
fn nearest_free(
    lattice: &Lattice,
    centre: Coord<f64>,
    free: impl Fn(Position) -> bool,
) -> Position {
    let start = lattice.position_of(centre);
    let tiling = lattice.tiling;
    let mut reach = 0;
    loop {
        let ring = (-reach..=reach)
            .flat_map(|dr| (-reach..=reach).map(move |dc| (start.0 + dc, start.1 + dr)))
            .filter(|&p| tiling.distance(p, start) == reach && free(p));
        if let Some(p) = ring.min_by_key(|&(c, r)| (r, c)) {
            return p;
        }
        reach += 1;
    }
}

/// The edge-connected pieces of `cells`, largest first (then by their first cell's place in
/// `cells`); at least one, empty for no cells.
pub(crate) fn pieces_of(tiling: Tiling, cells: &[Position]) -> Vec<Vec<Position>> {
    let all: FxHashSet<Position> = cells.iter().copied().collect();
    let mut seen: FxHashSet<Position> = FxHashSet::default();
    let mut pieces: Vec<Vec<Position>> = Vec::new();
    for &start in cells {
        if !seen.insert(start) {
            continue;
        }
        let mut piece = vec![start];
        let mut next = 0;
        while next < piece.len() {
            for n in tiling.edge_neighbours(piece[next]).iter() {
                if all.contains(n) && seen.insert(*n) {
                    piece.push(*n);
                }
            }
            next += 1;
        }
        pieces.push(piece);
    }
    if pieces.is_empty() {
        pieces.push(Vec::new());
    }
    // Stable: equal sizes keep their order.
    pieces.sort_by_key(|p| Reverse(p.len()));
    pieces
}

/// Blocks whose centres are among a cell's this many nearest may take it, when there are more
/// blocks: a power diagram gives a cell to a far block only if its weight is large, and a
/// block's patch is never much larger than the spacing of the blocks around it.
const CANDIDATE_BLOCKS: usize = 24;

/// The exact transport of cells to blocks, block b taking `demand[b]` cells (Σ demand =
/// cells), minimising the summed costs; `options[x]` lists the blocks cell x may go to with
/// their costs, by block. Per cell, its block.
///
/// Successive shortest paths over the blocks: each cell starts at its cheapest block (optimal
/// for the counts that gives), and each step moves one cell's worth of surplus from a block
/// with too many to one with too few along the cheapest chain of hand-overs (a cell passes from
/// each block in the chain to the one before), found by Dijkstra on reduced costs under block
/// potentials. Per pair of blocks a heap holds the hand-over costs of the cells, so each step
/// costs about the number of blocks times its chain's length. Deterministic: ties go to the
/// lower index.
///
/// `potential` holds the blocks' potentials (all 0 for a cold start) and is left with the
/// final ones. Each cell starts at the block of least cost less potential, which is optimal
/// for the counts it gives, so the result is the same optimum from any potentials; those of a
/// like problem (the previous splitting round) start near the demands and leave few steps
/// (us_counties with a gap: a third of the run was these steps, from cold starts).
fn transport(options: &[Vec<(usize, f64)>], demand: &[usize], potential: &mut [f64]) -> Vec<usize> {
    let blocks = demand.len();
    let cost = |x: usize, b: usize| {
        let list = &options[x];
        list.binary_search_by_key(&b, |&(o, _)| o)
            .map_or(f64::INFINITY, |k| list[k].1)
    };
    let mut holder: Vec<usize> = (options.iter())
        .map(|list| {
            (list.iter())
                .map(|&(b, c)| (b, c - potential[b]))
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
                .map_or(0, |(b, _)| b)
        })
        .collect();
    let mut count = vec![0usize; blocks];
    for &h in &holder {
        count[h] += 1;
    }
    // hand_over[taker][giver]: the cells `giver` holds that `taker` may take, by the cost
    // difference (taker's cost − giver's), lazily dropped once they change hands.
    let mut hand_over: Vec<FxHashMap<usize, BinaryHeap<Reverse<Offer>>>> =
        vec![FxHashMap::default(); blocks];
    let offer = |hand_over: &mut Vec<FxHashMap<usize, BinaryHeap<Reverse<Offer>>>>,
                 x: usize,
                 giver: usize| {
        for &(taker, taker_cost) in &options[x] {
            if taker != giver {
                let key = taker_cost - cost(x, giver);
                (hand_over[taker].entry(giver).or_default()).push(Reverse((Key(key), x)));
            }
        }
    };
    for (x, &h) in holder.iter().enumerate() {
        offer(&mut hand_over, x, h);
    }
    loop {
        let short: Vec<usize> = (0..blocks).filter(|&b| count[b] < demand[b]).collect();
        if short.is_empty() {
            break;
        }
        // Dijkstra from every block that is short, to the nearest that has too many.
        let mut distance = vec![f64::INFINITY; blocks];
        let mut via: Vec<Option<(usize, usize)>> = vec![None; blocks];
        let mut done = vec![false; blocks];
        let mut queue: BinaryHeap<Reverse<(Key, usize)>> = BinaryHeap::new();
        for &s in &short {
            distance[s] = 0.0;
            queue.push(Reverse((Key(0.0), s)));
        }
        let mut reached = None;
        while let Some(Reverse((Key(d), taker))) = queue.pop() {
            if done[taker] || d > distance[taker] {
                continue;
            }
            done[taker] = true;
            if count[taker] > demand[taker] {
                reached = Some(taker);
                break;
            }
            for (&giver, heap) in hand_over[taker].iter_mut() {
                while heap
                    .peek()
                    .is_some_and(|&Reverse((_, cell))| holder[cell] != giver)
                {
                    heap.pop();
                }
                let Some(&Reverse((Key(key), cell))) = heap.peek() else {
                    continue;
                };
                let reduced = (key - potential[taker] + potential[giver]).max(0.0);
                let through = d + reduced;
                if through < distance[giver] {
                    distance[giver] = through;
                    via[giver] = Some((taker, cell));
                    queue.push(Reverse((Key(through), giver)));
                }
            }
        }
        let Some(end) = reached else {
            // No block with a surplus can be reached (candidate lists too short to connect
            // them): the counts stay as they are rather than loop.
            break;
        };
        let limit = distance[end];
        for b in 0..blocks {
            potential[b] -= distance[b].min(limit);
        }
        count[end] -= 1;
        let mut giver = end;
        while let Some((taker, x)) = via[giver] {
            holder[x] = taker;
            offer(&mut hand_over, x, taker);
            giver = taker;
        }
        count[giver] += 1;
    }
    holder
}

/// A cell one block may take from another (its index, second) and how much more it costs the
/// taker than its holder (first): heaps order by the cost, then the cell.
type Offer = (Key, usize);

/// A cost or distance, totally ordered.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Key(f64);
impl Eq for Key {}
impl PartialOrd for Key {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Key {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// What [`metrics`] measures a layout's groups with, all per region in the unit-cell frame.
pub struct GroupLayout<'a> {
    pub blocks: &'a Blocks,
    /// Lattice positions.
    pub positions: &'a [Position],
    /// Cell centres, and the regions' area centroids.
    pub centres: &'a [Coord<f64>],
    pub places: &'a [Coord<f64>],
    /// Adjacent region pairs, as the layout's metrics count them (with regions drawn a hairline
    /// apart, those facing each other across the gaps).
    pub adjacency: &'a [(usize, usize)],
    pub tiling: Tiling,
    /// `group_gap`: how many empty cells may lie between adjacent groups' cells.
    pub gap: usize,
}

/// The group metrics of method.md §10 (see [`GroupMetrics`]).
pub fn metrics(layout: &GroupLayout) -> GroupMetrics {
    let GroupLayout {
        blocks,
        positions,
        tiling,
        ..
    } = *layout;
    let group_of = |i: usize| blocks.group[blocks.of[i]];
    let groups = blocks.group.iter().map(|&g| g + 1).max().unwrap_or(0);
    let mut cells_of_block: Vec<Vec<Position>> = vec![Vec::new(); blocks.count()];
    for (i, &p) in positions.iter().enumerate() {
        cells_of_block[blocks.of[i]].push(p);
    }
    let whole = (cells_of_block.iter())
        .filter(|cells| pieces_of(tiling, cells).len() == 1)
        .count();
    let owner: FxHashMap<Position, usize> = (positions.iter().enumerate())
        .map(|(i, &p)| (p, group_of(i)))
        .collect();
    let owner = &owner;
    let contacts = (positions.iter().enumerate())
        .flat_map(|(i, &(c, r))| {
            (tiling.half_neighbourhood().iter())
                .filter_map(move |&(dc, dr)| Some((i, *owner.get(&(c + dc, r + dr))?)))
        })
        .filter(|&(i, g)| g != group_of(i))
        .count();
    // The groups whose cells come within reach of each group's.
    let reach = 1 + layout.gap as i32;
    let mut near: FxHashSet<(usize, usize)> = FxHashSet::default();
    for (i, &(c, r)) in positions.iter().enumerate() {
        for dr in -reach..=reach {
            for dc in -reach..=reach {
                let q = (c + dc, r + dr);
                if tiling.distance((c, r), q) <= reach {
                    if let Some(&g) = owner.get(&q) {
                        near.insert((group_of(i), g));
                    }
                }
            }
        }
    }
    let mut pairs: Vec<(usize, usize)> = (layout.adjacency.iter())
        .map(|&(i, j)| (group_of(i), group_of(j)))
        .filter(|(a, b)| a != b)
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    let kept = pairs.iter().filter(|p| near.contains(p)).count();
    let mean_of = |points: &[Coord<f64>]| {
        let mut sums = vec![(Coord { x: 0.0, y: 0.0 }, 0.0); groups];
        for (i, &p) in points.iter().enumerate() {
            let s = &mut sums[group_of(i)];
            s.0 = s.0 + p;
            s.1 += 1.0;
        }
        (sums.into_iter())
            .map(|(sum, n)| sum / f64::max(n, 1.0))
            .collect::<Vec<_>>()
    };
    let (places, centres) = (mean_of(layout.places), mean_of(layout.centres));
    let angles: f64 = (pairs.iter())
        .map(|&(a, b)| {
            let (u, v) = (places[b] - places[a], centres[b] - centres[a]);
            let cross = u.x * v.y - u.y * v.x;
            let dot = u.x * v.x + u.y * v.y;
            cross.abs().atan2(dot).to_degrees()
        })
        .sum();
    let share = |k: usize, n: usize| if n > 0 { k as f64 / n as f64 } else { 1.0 };
    GroupMetrics {
        whole: share(whole, blocks.count()),
        adjacency: share(kept, pairs.len()),
        orientation: if pairs.is_empty() {
            0.0
        } else {
            angles / pairs.len() as f64
        },
        groups: groups as u32,
        blocks: blocks.count() as u32,
        contacts: contacts as u32,
        group_pairs: pairs.len() as u32,
        reach: reach as u32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn squared(a: Coord<f64>, b: Coord<f64>) -> f64 {
        (a.x - b.x).powi(2) + (a.y - b.y).powi(2)
    }

    #[test]
    fn an_island_group_touching_another_across_the_gap_is_docked_clear_of_it() {
        // Group 0: four regions on landmass 0 at (0..2, 0..2); group 1: one region alone on
        // landmass 1 at (2, 2), touching (1, 1) at a corner, as `landmass::settle` may leave
        // it (it knows nothing of groups).
        let at = [(0, 0), (1, 0), (0, 1), (1, 1), (2, 2)];
        let mut lattice = Lattice {
            tiling: Tiling::Square,
            cell_size: 1.0,
            origin: Coord { x: 0.0, y: 0.0 },
            cells: (at.iter())
                .enumerate()
                .map(|(i, &(col, row))| LatticeCell {
                    col,
                    row,
                    score: 2.0,
                    part: usize::from(i == 4),
                })
                .collect(),
        };
        let places: Vec<Coord<f64>> = at.iter().map(|&(c, r)| lattice.centre(c, r)).collect();
        let blocks = Blocks::new(
            &[0, 0, 0, 0, 1],
            &[Some(0), Some(0), Some(0), Some(0), Some(1)],
        );
        let island = |lattice: &Lattice| (lattice.cells[4].col, lattice.cells[4].row);
        // Without a gap the contact is allowed: it stays.
        let mut packed = lattice.clone();
        dock(&mut packed, &blocks, &places, false, &[]);
        assert_eq!(island(&packed), (2, 2));
        // With a gap it moves one cell, to where it touches nothing of group 0.
        dock(&mut lattice, &blocks, &places, true, &[]);
        let (col, row) = island(&lattice);
        assert_eq!((col - 2).abs() + (row - 2).abs(), 1, "{col} {row}");
        assert!((0..4).all(|i| {
            let c = lattice.cells[i];
            (c.col - col).abs().max((c.row - row).abs()) > 1
        }));
    }

    #[test]
    fn the_transport_is_optimal_and_meets_every_demand() {
        // Against the exact one-to-one assignment of one slot per demanded cell (each slot at
        // its block's centre): the same optimum, by a different method.
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for blocks in [2, 5, 30] {
            let demand: Vec<usize> = (0..blocks).map(|_| rng.random_range(1..12)).collect();
            let n: usize = demand.iter().sum();
            let cells: Vec<Coord<f64>> = (0..n)
                .map(|_| Coord {
                    x: rng.random_range(0.0..20.0),
                    y: rng.random_range(0.0..20.0),
                })
                .collect();
            let centres: Vec<Coord<f64>> = (0..blocks)
                .map(|_| Coord {
                    x: rng.random_range(0.0..20.0),
                    y: rng.random_range(0.0..20.0),
                })
                .collect();
            let options: Vec<Vec<(usize, f64)>> = (cells.iter())
                .map(|&c| nearest_centres(&centres, c))
                .collect();
            // The cost of a transport that meets every demand.
            let cost_of = |holder: &[usize]| {
                let mut count = vec![0; blocks];
                for &h in holder {
                    count[h] += 1;
                }
                assert_eq!(count, demand);
                (holder.iter().zip(&cells))
                    .map(|(&h, &c)| squared(c, centres[h]))
                    .sum::<f64>()
            };
            let cost = cost_of(&transport(&options, &demand, &mut vec![0.0; blocks]));
            let slots: Vec<Coord<f64>> = (demand.iter().enumerate())
                .flat_map(|(b, &k)| std::iter::repeat_n(centres[b], k))
                .collect();
            let exact = assign::assign(&slots, &cells, &|_| true).unwrap();
            let best: f64 = (exact.iter().enumerate())
                .map(|(s, &c)| squared(cells[c], slots[s]))
                .sum();
            if blocks <= CANDIDATE_BLOCKS {
                assert!(
                    (cost - best).abs() < 1e-9 * best.max(1.0),
                    "{cost} against {best}"
                );
            }
            // From any potentials (a warm start), the same demands met at the same cost.
            let mut warm: Vec<f64> = (0..blocks).map(|_| rng.random_range(-50.0..50.0)).collect();
            let warm_cost = cost_of(&transport(&options, &demand, &mut warm));
            assert!(
                (warm_cost - cost).abs() < 1e-9 * cost.max(1.0),
                "{warm_cost} against {cost}"
            );
        }
    }

    #[test]
    fn blocks_are_numbered_by_their_first_region_whatever_the_group_names() {
        // Regions 0..6 on landmasses 0, 0, 1, 0, 1, 0 in groups b, a, b, None, a, a.
        let landmass = [0, 0, 1, 0, 1, 0];
        let named = [Some(7), Some(3), Some(7), None, Some(3), Some(3)];
        let renamed = [Some(0), Some(9), Some(0), None, Some(9), Some(9)];
        let a = Blocks::new(&landmass, &named);
        assert_eq!(a, Blocks::new(&landmass, &renamed));
        // b on 0, a on 0, b on 1, the loner, a on 1.
        assert_eq!(a.of, vec![0, 1, 2, 3, 4, 1]);
        assert_eq!(a.landmass, vec![0, 0, 1, 0, 1]);
        assert_eq!(a.group, vec![0, 1, 0, 2, 1]);
    }

    #[test]
    fn with_a_gap_a_cell_beyond_a_blocks_reach_costs_it_more() {
        // Cells of side 2; a block of 12 cells (radius √(12/π) ≈ 1.95 cells, reach 3.95 cells
        // = 7.91 units) and one of 1 cell (radius 0.56, reach 2.56 cells = 5.13 units).
        let lattice = Lattice {
            tiling: Tiling::Square,
            cell_size: 2.0,
            origin: Coord { x: 0.0, y: 0.0 },
            cells: Vec::new(),
        };
        let centres = [Coord { x: 0.0, y: 0.0 }, Coord { x: 0.0, y: 20.0 }];
        let none = FxHashMap::default();
        let split = |gap: bool| Split {
            lattice: &lattice,
            cells: &[],
            centres: &centres,
            demand: &[12, 1],
            gap,
            fixed: &none,
        };
        let sizes = [12, 1];
        // 6 units from the large block (within its reach), 14 from the small one (beyond).
        let p = Coord { x: 0.0, y: 6.0 };
        assert_eq!(
            split(false).power_costs(p, &sizes),
            vec![(0, 36.0), (1, 196.0)]
        );
        let costs = split(true).power_costs(p, &sizes);
        assert_eq!(costs[0], (0, 36.0));
        let reach = ((1.0 / std::f64::consts::PI).sqrt() + REACH_MARGIN) * 2.0;
        let expected = 196.0 + BEYOND_REACH * (14.0 - reach).powi(2);
        assert_eq!(costs[1].0, 1);
        assert!((costs[1].1 - expected).abs() < 1e-9, "{costs:?}");
    }

    #[test]
    fn pieces_are_edge_connected() {
        // Two squares touching at a corner are two pieces; two hexagons side by side are one.
        let diagonal = [(0, 0), (1, 1), (0, 1)];
        assert_eq!(pieces_of(Tiling::Square, &diagonal).len(), 1);
        assert_eq!(pieces_of(Tiling::Square, &diagonal[..2]).len(), 2);
        let hex = Tiling::Hex(crate::core::HexOrientation::Pointy);
        assert_eq!(pieces_of(hex, &[(0, 0), (1, -1)]).len(), 1);
        assert_eq!(pieces_of(hex, &[(0, 0), (1, 1)]).len(), 2);
    }
}
