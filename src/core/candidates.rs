//! The whole method (method.md §7): one noise-free and a few noisy Snake runs, a lattice with
//! every origin shift on each, assignment and refinement, metrics, TOPSIS ranking. Candidates are
//! independent and computed in parallel; the result does not depend on the order of the input
//! regions or their ids, because everything works on the regions in a geometric order.

use super::assign::Prices;
use super::frame::Frame;
use super::grid::{self, Lattice, LatticeCell};
use super::groups;
use super::landmass;
use super::metrics::{self, Scored};
use super::network::{self, Network};
use super::outline::{self, Prepared};
use super::params::HexOrientation;
use super::pins;
use super::snake::{self, SnakeRun};
use super::thin;
use super::tiling::{Position, Tiling};
use super::validity::{self, Problem};
use super::watch;
use super::{
    assign, forces, geometry, rank, refine, CandidateReport, Error, GridMap, LayoutMetrics, Params,
    Progress, Region, RegionCell, RegionMetrics,
};
use super::{derived_seed, first_error_in_order};
use geo::algorithm::bool_ops::FillRule;
use geo::{
    Area, BooleanOps, Centroid, Coord, CoordsIter, HasDimensions, LineString, MakeValid,
    MultiPolygon, Polygon,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::borrow::Cow;
use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// How far from the layer's centre, in mean region sizes (cells), a coordinate may lie. Real
/// layers span a few thousand cells at most; beyond this the method's arithmetic (squared
/// distances, areas, the triangulation) loses all precision or overflows, e.g. for a
/// needle-thin region 1e231 units long.
const MAX_SPAN: f64 = 1e6;
/// Vertices of a region above which its repair runs watched, so that a cancel is heard within
/// it: a repair of a few thousand vertices takes hundredths of a second, not worth a thread
/// pool of its own, while one crowded star of 20,000 took 0.44 s.
const WATCHED_REPAIR: usize = 5_000;

/// The largest coordinate taken: the squares of coordinates and the areas of rings stay far
/// from overflow (1e300 squared is infinite, and the layer would seem to have no area).
const LARGEST_COORDINATE: f64 = 1e100;

/// The most neighbouring regions a layer's regions may have on average. Regions side by side
/// form a planar map, whose regions have fewer than 6 neighbours on average (Euler's formula),
/// and borders that overlap sloppily or a layer copied into itself once or twice add a few more
/// (the US counties twice over: 12.2). Only features stacked many deep come near this, where
/// every copy neighbours every other (500 copies of one square: 499 each), and the layout's work
/// grows with the neighbours of each region: 25 s for those 500, over 5 minutes and 6 GB for
/// 3,000.
const MOST_MEAN_NEIGHBOURS: f64 = 24.0;

/// Draws of a noisy centroid before it is left where it was (a draw must land inside the outline).
const NOISE_DRAWS: usize = 16;

/// See [`crate::generate`]. With `params.threads` set, the work runs on a pool of that many
/// threads; the result is the same for any number, since every parallel step collects in order
/// and seeds from the candidate's index.
pub fn generate(regions: &[Region], params: &Params, progress: Progress) -> Result<GridMap, Error> {
    params.validate().map_err(Error::InvalidParameter)?;
    if params.threads == 0 {
        return generate_here(regions, params, progress);
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(params.threads)
        .build()
        .map_err(|e| Error::Internal(format!("cannot start {} threads: {e}", params.threads)))?;
    pool.install(|| generate_here(regions, params, progress))
}

/// The (Snake run, shift) pairs to lay out, `count` of the `runs` × `shifts`: the runs in turn,
/// each taking the shifts farthest from those already taken (on the torus of cell offsets) first,
/// so that a few layouts still spread over runs and positions. In run-major, shift-list order,
/// which is every pair in the order of the parameters when `count` allows all.
fn layout_jobs(runs: usize, shifts: &[[f64; 2]], count: usize) -> Vec<(usize, [f64; 2])> {
    let torus = |a: [f64; 2], b: [f64; 2]| {
        let d = |u: f64, v: f64| {
            let d = (u - v).rem_euclid(1.0);
            d.min(1.0 - d)
        };
        d(a[0], b[0]).hypot(d(a[1], b[1]))
    };
    let mut spread: Vec<usize> = Vec::with_capacity(shifts.len());
    while spread.len() < shifts.len() {
        let next = (0..shifts.len())
            .filter(|k| !spread.contains(k))
            .map(|k| {
                let nearest = (spread.iter())
                    .map(|&t| torus(shifts[k], shifts[t]))
                    .fold(f64::INFINITY, f64::min);
                (k, nearest)
            })
            // The farthest; the first in the list among equals.
            .fold(None, |best: Option<(usize, f64)>, (k, d)| match best {
                Some((_, b)) if b >= d => best,
                _ => Some((k, d)),
            });
        spread.extend(next.map(|(k, _)| k));
    }
    let used_runs = runs.min(count).max(1);
    let mut jobs: Vec<(usize, usize)> = (0..count.min(runs * shifts.len()))
        .map(|k| (k % used_runs, spread[k / used_runs]))
        .collect();
    jobs.sort_unstable();
    jobs.into_iter().map(|(r, s)| (r, shifts[s])).collect()
}

/// What a run on a layer does: the noise levels of its Snake runs (those some layout uses), its
/// (run, shift) layouts, how many of those are refined, and how many pairs there were to choose
/// from.
struct Plan {
    levels: Vec<f64>,
    jobs: Vec<(usize, [f64; 2])>,
    refined: usize,
    pairs: usize,
}

impl Plan {
    fn of(regions: usize, params: &Params) -> Plan {
        let mut levels = params.snake_noise_levels();
        let jobs = layout_jobs(levels.len(), &params.shifts, params.layout_count(regions));
        // Snake runs that no layout uses are not made.
        let pairs = levels.len() * params.shifts.len();
        levels.truncate(jobs.iter().map(|&(r, _)| r + 1).max().unwrap_or(1));
        let refined = if params.refine {
            params.refined_count(regions, jobs.len())
        } else {
            0
        };
        Plan {
            levels,
            jobs,
            refined,
            pairs,
        }
    }

    /// The layouts' work, in Snake steps ([`StageWeights`]).
    fn layout_work(&self, params: &Params) -> f64 {
        let weights = StageWeights::new(params);
        (self.levels.len() * params.max_steps) as f64
            + self.jobs.len() as f64 * weights.plain()
            + self.refined as f64 * weights.refinement()
    }
}

/// See [`crate::expected_seconds`].
pub fn expected_seconds(regions: &[Region], params: &Params) -> f64 {
    let plan = Plan::of(regions.len(), params);
    let steps =
        StageWeights::preparation(vertex_count(regions), regions.len()) + plan.layout_work(params);
    steps * StageWeights::step_seconds(regions.len())
}

/// The vertices of all `regions`, which the input's preparation follows.
fn vertex_count(regions: &[Region]) -> usize {
    regions.iter().map(|r| r.geometry.coords_count()).sum()
}

/// [`generate`] on the current thread pool.
fn generate_here(
    regions: &[Region],
    params: &Params,
    progress: Progress,
) -> Result<GridMap, Error> {
    let plan = Plan::of(regions.len(), params);
    let layout_work = plan.layout_work(params);
    let Plan {
        levels,
        mut jobs,
        refined,
        pairs,
    } = plan;
    let weights = StageWeights::new(params);
    // The bar's share of the input's preparation, which follows the vertices, not the regions.
    let preparation = StageWeights::preparation(vertex_count(regions), regions.len());
    let prepared_share = preparation / (preparation + layout_work);
    if !progress(0.0, "checking geometry") {
        return Err(Error::Cancelled);
    }
    let Input {
        order,
        frame,
        prepared,
        mut notes,
        repairs,
    } = Input::of(regions, params, &|fraction, message| {
        progress(prepared_share * fraction, message)
    })?;
    let grouped = regions.iter().any(|r| r.group.is_some());
    notes.extend(params.unused(grouped));
    let blocks = blocks_of(regions, &order, &prepared, grouped);
    let gap = grouped && params.group_gap > 0;
    let tiling = Tiling::of(params);
    let pins = pins::positions(regions, &order, tiling, grouped.then_some(&blocks), gap)?;
    let base = network::build(&prepared.centroids, &prepared.rings, &prepared.neighbours)?;

    if !pins.is_empty() {
        // Pins place the lattice: there is no origin to shift, and each shift's layout is
        // another start of the refinement (its own seed) instead.
        notes.push(format!(
            "{} pinned regions place the lattice; the candidate shifts are not used, each \
             stands for another start of the refinement",
            pins.len()
        ));
        for job in &mut jobs {
            job.1 = [0.0, 0.0];
        }
    }
    if jobs.len() < pairs {
        notes.push(format!(
            "{} of the {pairs} candidate layouts were made (max_layouts{})",
            jobs.len(),
            if params.max_layouts.is_some() {
                ""
            } else {
                " unset: fewer for more regions"
            }
        ));
    }
    if refined > 0 && refined < jobs.len() {
        notes.push(format!(
            "the best {refined} of the {} candidate layouts by the ranking before refinement \
             were refined (max_refined{})",
            jobs.len(),
            if params.max_refined.is_some() {
                ""
            } else {
                " unset: fewer for more regions"
            }
        ));
    }
    let tracker = Tracker::new(progress, layout_work, prepared_share);
    let reference = metrics::Reference::new(&prepared, frame);
    let anchors = landmass::Anchors::new(
        &prepared.area_centroids,
        |i| reference.landmasses.large(i),
        params.island_limit,
    );
    let context = Context {
        blocks,
        grouped,
        pins,
        prepared: &prepared,
        frame,
        reference,
        anchors,
        params,
    };
    let run_count = levels.len();
    let snake_run = |r: usize, md: f64| -> Result<(Network, SnakeRun), Error> {
        let network = if md == 0.0 {
            base.clone()
        } else {
            let centroids = noisy_centroids(&prepared, &base, md, derived_seed(params.seed, 1, r));
            network::build(&centroids, &prepared.rings, &prepared.neighbours)?
        };
        let neighbours = forces::neighbours(&network, &prepared.neighbours);
        let started = AtomicUsize::new(0);
        let run = snake::run(&network, &neighbours, params, &|| {
            let step = started.fetch_add(1, Ordering::Relaxed) + 1;
            let of_run = if run_count > 1 {
                format!(" (run {} of {run_count})", r + 1)
            } else {
                String::new()
            };
            let message = format!("Snake step {step} of {}{of_run}", params.max_steps);
            // Each step counts as it starts.
            tracker.advance(1.0, &message)
        })?;
        // A run that stops early hands its steps never started to the progress count.
        let unused = params.max_steps.saturating_sub(started.into_inner());
        tracker.advance(unused as f64, "Snake");
        Ok((network, run))
    };
    let lay_out = |ran: &(Network, SnakeRun), k: usize, start: Option<&RunStart>| {
        tracker.layout_work(&weights, k, jobs.len(), |report| {
            context.layout(&ran.0, &ran.1, jobs[k].1, start, report)
        })
    };
    // The Snake runs, then each run's layouts as it ends, all on the pool in the order they
    // become ready: a core that has finished a run lays out while the other runs go on, and no
    // run waits behind layouts (3 runs on 2 cores left a core idle for most of a run). A run's
    // other shifts assign the same moved centroids to a lattice shifted by part of a cell, so
    // they start from its first layout's prices (see assign::Prices) and take its choice of
    // figure for thin landmasses (see thin.rs). Each job leaves its
    // result in its own slot, collected in order after the scope: where and when a layout is
    // made changes nothing in it.
    type Slot<T> = Mutex<Option<Result<T, Error>>>;
    let ran_slots: Vec<Slot<Arc<(Network, SnakeRun)>>> =
        levels.iter().map(|_| Mutex::default()).collect();
    let layout_slots: Vec<Slot<Layout>> = jobs.iter().map(|_| Mutex::default()).collect();
    fn put<T>(slot: &Mutex<Option<T>>, value: T) {
        *slot.lock().expect("no job panics while holding a slot") = Some(value);
    }
    fn taken<T>(slot: Mutex<Option<T>>) -> Option<T> {
        slot.into_inner().ok().flatten()
    }
    // Run `r`'s first layout, made from scratch; the run's other layouts and what starts them,
    // unless it failed.
    let first_layout = |ran: &(Network, SnakeRun), r: usize| {
        let mut mine = (0..jobs.len()).filter(|&k| jobs[k].0 == r);
        let first = mine.next()?;
        let laid = lay_out(ran, first, None);
        let Ok((layout, start)) = laid else {
            put(&layout_slots[first], laid.map(|(layout, _)| layout));
            return None;
        };
        put(&layout_slots[first], Ok(layout));
        Some((mine.collect::<Vec<usize>>(), Arc::new(start)))
    };
    let (snake_run, lay_out, first_layout) = (&snake_run, &lay_out, &first_layout);
    let (ran_slots_ref, layout_slots_ref) = (&ran_slots, &layout_slots);
    rayon::scope_fifo(|scope| {
        for (r, &md) in levels.iter().enumerate() {
            scope.spawn_fifo(move |scope| {
                let ran = snake_run(r, md).map(Arc::new);
                if let Ok(ran) = &ran {
                    let ran = Arc::clone(ran);
                    scope.spawn_fifo(move |scope| {
                        let Some((rest, start)) = first_layout(&ran, r) else {
                            return;
                        };
                        for k in rest {
                            let (ran, start) = (Arc::clone(&ran), Arc::clone(&start));
                            scope.spawn_fifo(move |_| {
                                let laid = lay_out(&ran, k, Some(&start));
                                put(&layout_slots_ref[k], laid.map(|(layout, _)| layout));
                            });
                        }
                    });
                }
                put(&ran_slots_ref[r], ran);
            });
        }
    });
    let mut runs = Vec::with_capacity(levels.len());
    for (slot, &md) in ran_slots.into_iter().zip(&levels) {
        let ran =
            taken(slot).ok_or_else(|| Error::Internal("a Snake run was not made".into()))??;
        runs.push((md, ran.1.clone()));
    }
    // A layout is missing only when one before it in its run failed, whose error comes first.
    let layouts = (layout_slots.into_iter())
        .map(|slot| taken(slot).ok_or_else(|| Error::Internal("a layout was not made".into()))?)
        .collect::<Result<Vec<Layout>, Error>>()?;

    // The refinement moves every candidate about alike, so the best before it are the best
    // after (see REFINED_REGION_LAYOUTS): only those are refined, each with its own seed.
    let (layouts, kept): (Vec<Layout>, Vec<usize>) = if refined == 0 {
        let all = (0..layouts.len()).collect();
        (layouts, all)
    } else {
        let (before, _) = ranked(&layouts, params);
        let mut chosen = before[..refined].to_vec();
        chosen.sort_unstable();
        let mut layouts: Vec<Option<Layout>> = layouts.into_iter().map(Some).collect();
        let chosen_layouts: Vec<(usize, Layout)> = (chosen.iter())
            .map(|&k| (k, layouts[k].take().expect("each layout is chosen once")))
            .collect();
        let refined = first_error_in_order(chosen_layouts.into_par_iter().map(|(k, layout)| {
            tracker.layout_work(&weights, k, jobs.len(), |report| {
                context.refined(layout, derived_seed(params.seed, 2, k), report)
            })
        }))?;
        (refined, chosen)
    };

    // Whatever rounding left of the count: the layouts are done.
    if !progress(1.0, "ranking the layouts") {
        return Err(Error::Cancelled);
    }
    let (ranking, scores) = ranked(&layouts, params);
    let candidates = ranking
        .iter()
        .map(|&k| {
            let (md, run) = &runs[jobs[kept[k]].0];
            CandidateReport {
                noise: *md,
                shift: jobs[kept[k]].1,
                metrics: layouts[k].metrics,
                score: scores[k],
                snake: run.report.clone(),
            }
        })
        .collect();
    let best = &layouts[ranking[0]];
    let (_, run) = &runs[jobs[kept[ranking[0]]].0];
    let mut map = context.grid_map(regions, &order, best, run, candidates, notes);
    for (cell, repair) in map.cells.iter_mut().zip(repairs) {
        cell.repair = repair;
    }
    Ok(map)
}

/// The layouts' indices, best first, and their TOPSIS scores: the layout's defects first
/// (method.md §8 and the cartographer's priorities: each landmass in one piece, no holes but
/// the source's, no region nearer another landmass than its own), then TOPSIS over location,
/// adjacency, orientation and shape. A region on the wrong landmass counts as one defect, like a
/// break: across a river narrower than a cell (a city's districts either side of it), the block
/// boundary cannot follow every bend, and of the candidates some put a cell across it and others
/// not.
fn ranked(layouts: &[Layout], params: &Params) -> (Vec<usize>, Vec<f64>) {
    let scores = rank::topsis(
        &layouts.iter().map(|l| l.metrics).collect::<Vec<_>>(),
        params.topsis_weights,
    );
    let defects = |k: usize| layouts[k].breaks + layouts[k].stray_holes() + layouts[k].astray;
    let mut ranking: Vec<usize> = (0..layouts.len()).collect();
    ranking.sort_by(|&a, &b| {
        (defects(a).cmp(&defects(b)))
            .then(scores[b].total_cmp(&scores[a]))
            .then(a.cmp(&b))
    });
    (ranking, scores)
}

/// The regions made ready for the method: in their geometric order (`order[k]` is the input index of the
/// `k`-th), in the unit-cell frame, with centroids, adjacency and outline.
pub struct Input {
    pub order: Vec<usize>,
    pub frame: Frame,
    pub prepared: Prepared,
    /// What the user should know about the input, e.g. which polygons were repaired.
    pub notes: Vec<String>,
    /// Per region in input order, what was wrong with its polygon if it was repaired.
    pub repairs: Vec<Option<String>>,
}

impl Input {
    /// `progress` hears the share of the preparation done: 0 as the geometry is checked, the
    /// share expected for that ([`Preparation`]) as the outline is begun.
    pub fn of(regions: &[Region], params: &Params, progress: Progress) -> Result<Input, Error> {
        let checking_share = Preparation::of(vertex_count(regions), regions.len()).checking_share();
        let Checked {
            placed: Placed { order, frame, unit },
            valid_here,
            drawn,
            mut notes,
            repairs,
        } = check(regions, &|share| {
            progress(checking_share * share, "checking geometry")
        })?;
        let unit_refs: Vec<&MultiPolygon<f64>> = unit.iter().collect();
        let drawn_refs: Vec<&MultiPolygon<f64>> = (unit.iter().zip(&drawn))
            .map(|(repaired, drawn)| drawn.as_ref().unwrap_or(repaired))
            .collect();
        if !progress(checking_share, "outline") {
            return Err(Error::Cancelled);
        }
        let prepared = outline::prepare(
            &unit_refs,
            &drawn_refs,
            &valid_here,
            params,
            &|share, stage| progress(checking_share + (1.0 - checking_share) * share, stage),
        )
        .ok_or(Error::Cancelled)?;
        // The union and its outline are computed, not given: arithmetic at the edge of the
        // floating-point range (subnormal coordinates, found by fuzzing) can leave them empty
        // although every region has area, and every later step works on them.
        if prepared.regions_union.0.is_empty() || prepared.rings.is_empty() {
            return Err(Error::input(
                (regions.len() == 1).then(|| regions[0].id.as_str()),
                "the union of the regions has no area: the coordinates are degenerate \
                 (too close together to compute with)",
            ));
        }
        if let Some((share, pair)) = outline::overlaps(&unit_refs, prepared.overlap) {
            let example = pair.map_or(String::new(), |(i, j)| {
                let id = |k: usize| &regions[order[k]].id;
                format!(" ({:?} lies on {:?})", id(j), id(i))
            });
            notes.push(format!(
                "regions overlap: {:.1} % of their total area is covered more than once{example}; \
                 each region still gets its own cell, but a duplicated or stacked feature is \
                 likely a mistake in the layer",
                100.0 * share
            ));
        }
        stacked(&prepared.neighbours, regions, &order)?;
        let near = prepared.neighbours.len() - prepared.adjacency.len();
        if near > 0 {
            notes.push(format!(
                "borders not shared exactly: {near} pair(s) of regions share no border but run \
                 along each other, across a gap or an overlap under a hundredth of a cell; they \
                 are laid out as neighbours and measured so, where a judge reading exact borders \
                 counts none"
            ));
        }
        Ok(Input {
            order,
            frame,
            prepared,
            notes,
            repairs,
        })
    }
}

/// Refuses a layer whose regions have more than [`MOST_MEAN_NEIGHBOURS`] neighbours on average
/// (`neighbours`: the pairs, indexed as `order` places the regions), naming the region with the
/// most (the first in input order among equals).
fn stacked(
    neighbours: &[(usize, usize)],
    regions: &[Region],
    order: &[usize],
) -> Result<(), Error> {
    let mean = 2.0 * neighbours.len() as f64 / regions.len().max(1) as f64;
    if mean <= MOST_MEAN_NEIGHBOURS {
        return Ok(());
    }
    let mut counts = vec![0usize; order.len()];
    for &(i, j) in neighbours {
        counts[i] += 1;
        counts[j] += 1;
    }
    let Some((most, k)) = (counts.iter().zip(order))
        .map(|(&count, &k)| (count, k))
        .min_by_key(|&(count, k)| (std::cmp::Reverse(count), k))
    else {
        return Ok(());
    };
    Err(Error::input(
        Some(&regions[k].id),
        format!(
            "{most} regions lie on it or along its border, and the layer's regions have {mean:.0} \
             neighbours each on average, where regions side by side have fewer than 6: features \
             are stacked on one another (a layer copied into itself, a feature drawn many times); \
             remove the copies"
        ),
    ))
}

/// The regions' indices ordered by their geometry alone, so that renaming ids or reordering
/// features moves no cell: by area centroid (x, then y), then area, then smallest vertex; the id
/// decides only between identical geometries.
fn geometric_order(regions: &[Region], geometries: &[Cow<MultiPolygon<f64>>]) -> Vec<usize> {
    let keys: Vec<(Coord<f64>, f64, Coord<f64>)> = geometries
        .par_iter()
        .map(|g| {
            let centroid = g.centroid().map_or(Coord { x: 0.0, y: 0.0 }, |p| p.0);
            let smallest = g
                .coords_iter()
                .min_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)))
                .unwrap_or(centroid);
            (centroid, g.unsigned_area(), smallest)
        })
        .collect();
    let mut order: Vec<usize> = (0..regions.len()).collect();
    order.sort_by(|&a, &b| {
        let (ka, kb) = (&keys[a], &keys[b]);
        (ka.0.x.total_cmp(&kb.0.x))
            .then(ka.0.y.total_cmp(&kb.0.y))
            .then(ka.1.total_cmp(&kb.1))
            .then(ka.2.x.total_cmp(&kb.2.x))
            .then(ka.2.y.total_cmp(&kb.2.y))
            .then_with(|| regions[a].id.cmp(&regions[b].id))
    });
    order
}

/// The regions in their geometric order (`order[k]` is the input index of the `k`-th) and in
/// the unit-cell frame.
struct Placed {
    order: Vec<usize>,
    frame: Frame,
    unit: Vec<MultiPolygon<f64>>,
}

impl Placed {
    fn of(regions: &[Region], geometries: &[Cow<MultiPolygon<f64>>]) -> Result<Placed, Error> {
        let order = geometric_order(regions, geometries);
        let sorted: Vec<&MultiPolygon<f64>> = order.iter().map(|&i| &*geometries[i]).collect();
        let frame =
            Frame::of(&sorted).ok_or_else(|| Error::input(None, "the regions have no area"))?;
        let unit: Vec<MultiPolygon<f64>> = sorted
            .par_iter()
            .map(|g| frame.polygons_to_unit(g))
            .collect();
        if let Some(k) = unit.par_iter().position_first(|g| {
            g.coords_iter()
                .any(|c| !(c.x.abs() <= MAX_SPAN && c.y.abs() <= MAX_SPAN))
        }) {
            return Err(Error::input(
                Some(&regions[order[k]].id),
                format!(
                    "the geometry reaches more than {MAX_SPAN:e} times the mean region's size \
                     from the layer's centre: its coordinates are out of proportion"
                ),
            ));
        }
        Ok(Placed { order, frame, unit })
    }
}

/// The regions placed for the method, whether each (in geometric order) was found valid in the
/// unit-cell frame, each repaired one as drawn (in the unit-cell frame), and notes on the ones
/// repaired.
struct Checked {
    placed: Placed,
    valid_here: Vec<bool>,
    drawn: Vec<Option<MultiPolygon<f64>>>,
    notes: Vec<String>,
    /// Per region in input order, what was wrong with its polygon if it was repaired.
    repairs: Vec<Option<String>>,
}

/// Refuses what the method cannot work with, naming the feature. An invalid polygon (a ring that
/// crosses itself, a spike, overlapping parts) is repaired as GIS tools do (the even-odd rule of
/// geo's `MakeValid` and of GEOS's linework repair) and named in a note, because a digitising
/// slip should not stop a map; only one with no area left is refused. The geometries are
/// checked in parallel; the first error in input order is the one reported (the ids and
/// coordinates of all regions before any polygon's validity).
///
/// Validity, the costly check (O(n log n) in the vertices), is checked once per region, where
/// the method computes: in the unit-cell frame, the regions placed as if none needed a repair.
/// An isolated region found valid there is its own union, with no second check (on a region of
/// 200,000 vertices the check is a quarter of the run). Only a region found invalid there is
/// checked again in the layer's coordinates, which name the problem where the user can find it,
/// and repaired; a repair changes the areas and so the frame, and the regions are placed again
/// (the outline then checks an isolated region again in the new frame). `checking` hears the
/// share of the vertices checked, each hundredth of them; [`Error::Cancelled`] once it returns
/// false.
fn check(regions: &[Region], checking: &(dyn Fn(f64) -> bool + Sync)) -> Result<Checked, Error> {
    if regions.is_empty() {
        return Err(Error::input(None, "the layer has no regions"));
    }
    let mut seen = HashSet::new();
    for region in regions {
        let id = region.id.as_str();
        if id.is_empty() {
            return Err(Error::input(None, "a region has an empty id"));
        }
        if !seen.insert(id) {
            return Err(Error::input(
                Some(id),
                "the id is used by more than one region",
            ));
        }
    }
    first_error_in_order(regions.par_iter().map(admit))?;
    let given: Vec<Cow<MultiPolygon<f64>>> = (regions.iter())
        .map(|r| Cow::Borrowed(&r.geometry))
        .collect();
    // Per region in input order: valid in the unit-cell frame.
    let mut valid_here = vec![false; regions.len()];
    let placed = Placed::of(regions, &given).ok();
    if let Some(placed) = &placed {
        // Reported each hundredth of the vertices, since at 10⁷ vertices the check takes a
        // second; a cancel leaves the regions not yet begun unchecked.
        let total = placed
            .unit
            .iter()
            .map(|g| g.coords_count())
            .sum::<usize>()
            .max(1);
        let (done, stop) = (AtomicUsize::new(0), AtomicBool::new(false));
        let valid: Vec<bool> = (placed.unit.par_iter())
            .map(|g| {
                if stop.load(Ordering::Relaxed) {
                    return false;
                }
                let valid = validity::problem(g).is_none();
                let count = g.coords_count();
                let before = done.fetch_add(count, Ordering::Relaxed);
                if (before * 100 / total) != ((before + count) * 100 / total)
                    && !checking((before + count) as f64 / total as f64)
                {
                    stop.store(true, Ordering::Relaxed);
                }
                valid
            })
            .collect();
        if stop.into_inner() {
            return Err(Error::Cancelled);
        }
        for (&i, valid) in placed.order.iter().zip(valid) {
            valid_here[i] = valid;
        }
    }
    // A repair asks whether to go on as the checking's end (once told to stop, it does not
    // ask again).
    let stop = AtomicBool::new(false);
    let go_on = || {
        let go = !stop.load(Ordering::Relaxed) && checking(1.0);
        if !go {
            stop.store(true, Ordering::Relaxed);
        }
        go
    };
    let checked = first_error_in_order((regions.par_iter().zip(&valid_here)).map(
        |(region, &valid)| {
            if !valid {
                return repaired(region, &go_on);
            }
            if !has_area(&region.geometry) {
                return Err(Error::input(Some(&region.id), "the polygon has no area"));
            }
            Ok((Cow::Borrowed(&region.geometry), None))
        },
    ))?;
    let problems: Vec<Option<&Problem>> = checked.iter().map(|(_, p)| p.as_ref()).collect();
    let notes = repair_notes(regions, &problems);
    let repairs: Vec<Option<String>> = problems.iter().map(|p| p.map(Problem::to_string)).collect();
    if let Some(placed) = placed.filter(|_| notes.is_empty()) {
        let valid_here = placed.order.iter().map(|&i| valid_here[i]).collect();
        return Ok(Checked {
            drawn: vec![None; regions.len()],
            placed,
            valid_here,
            notes,
            repairs,
        });
    }
    let was_repaired: Vec<bool> = checked.iter().map(|(_, p)| p.is_some()).collect();
    let geometries: Vec<Cow<MultiPolygon<f64>>> = checked.into_iter().map(|(g, _)| g).collect();
    let placed = Placed::of(regions, &geometries)?;
    let drawn = (placed.order.iter())
        .map(|&i| was_repaired[i].then(|| placed.frame.polygons_to_unit(&regions[i].geometry)))
        .collect();
    Ok(Checked {
        valid_here: vec![false; regions.len()],
        drawn,
        placed,
        notes,
        repairs,
    })
}

/// How many repairs [`repair_notes`] lists one note each before it sums up the rest.
const REPAIRS_LISTED: usize = 10;

/// Notes on the repaired polygons (`problems` in input order): the first [`REPAIRS_LISTED`] one
/// by one, the rest in one note that counts them by kind, so that a layer of hundreds of invalid
/// polygons (a world of provinces drawn country by country) does not bury the other notes on
/// the console or in a QGIS log. Every region's own repair stays reported with its cell
/// ([`crate::RegionCell::repair`]).
fn repair_notes(regions: &[Region], problems: &[Option<&Problem>]) -> Vec<String> {
    let repaired: Vec<(&str, &Problem)> = (regions.iter().zip(problems))
        .filter_map(|(region, problem)| Some((region.id.as_str(), (*problem)?)))
        .collect();
    // One more is listed rather than summed up alone.
    let listed = if repaired.len() <= REPAIRS_LISTED + 1 {
        repaired.len()
    } else {
        REPAIRS_LISTED
    };
    let mut notes: Vec<String> = (repaired[..listed].iter())
        .map(|(id, problem)| format!("feature {id}: invalid polygon repaired ({problem})"))
        .collect();
    let rest = &repaired[listed..];
    if !rest.is_empty() {
        let mut kinds: Vec<(&str, usize)> = Vec::new();
        for (_, problem) in rest {
            match kinds.iter_mut().find(|(kind, _)| *kind == problem.kind()) {
                Some((_, count)) => *count += 1,
                None => kinds.push((problem.kind(), 1)),
            }
        }
        kinds.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(b.0)));
        let named: Vec<&str> = rest.iter().take(5).map(|(id, _)| *id).collect();
        let more = if rest.len() > named.len() {
            ", …"
        } else {
            ""
        };
        let counts: Vec<String> = (kinds.iter())
            .map(|(kind, count)| format!("{count} where {kind}"))
            .collect();
        notes.push(format!(
            "{} more invalid polygons repaired (features {}{more}): {}; each region's problem \
             comes with its cell (the JSON report's regions[].repair)",
            rest.len(),
            named.join(", "),
            counts.join(", ")
        ));
    }
    notes
}

/// Refuses a region with no coordinates, or with coordinates no area can be computed from.
fn admit(region: &Region) -> Result<(), Error> {
    let id = region.id.as_str();
    // Also a multipolygon of polygons without points (WKB allows one).
    if region.geometry.is_empty() {
        return Err(Error::input(Some(id), "the geometry is empty"));
    }
    if region
        .geometry
        .coords_iter()
        .any(|c| !c.x.is_finite() || !c.y.is_finite())
    {
        return Err(Error::input(
            Some(id),
            "the geometry has a NaN or infinite coordinate",
        ));
    }
    let farthest = (region.geometry.coords_iter())
        .map(|c| c.x.abs().max(c.y.abs()))
        .fold(0.0, f64::max);
    if farthest > LARGEST_COORDINATE {
        return Err(Error::input(
            Some(id),
            format!(
                "a coordinate ({farthest:.1e}) is beyond ±{LARGEST_COORDINATE:e}, too large for \
                 areas to be computed: rescale the layer or give it its real CRS"
            ),
        ));
    }
    Ok(())
}

/// An admitted region's geometry checked in the layer's coordinates, repaired if it is invalid
/// there (with what was wrong). A repair of more than [`WATCHED_REPAIR`] vertices runs watched
/// ([`watch::watched`]), asking `go_on`; [`Error::Cancelled`] once it has returned false.
fn repaired<'r>(
    region: &'r Region,
    go_on: &(dyn Fn() -> bool + Sync),
) -> Result<(Cow<'r, MultiPolygon<f64>>, Option<Problem>), Error> {
    let id = region.id.as_str();
    let examined = validity::examine(&region.geometry);
    let Some(problem) = examined.problem else {
        if !has_area(&region.geometry) {
            return Err(Error::input(Some(id), "the polygon has no area"));
        }
        return Ok((Cow::Borrowed(&region.geometry), None));
    };
    // The even-odd rule either way (a ring crossing itself keeps both loops, a spike or a
    // doubled edge cancels). geo's overlay, which also makes the outline's union, is O(n log n)
    // on boundaries as drawn: Greenland at 98,906 vertices in 0.03 s, where `MakeValid` took
    // 4–8 s, splitting its rings at pinch points in O(n²). Among crowded long segments (a star's
    // spikes) the overlay's sweep grows faster still, so those keep `MakeValid`.
    let crowded = examined.crowded;
    let repair = move |geometry: &MultiPolygon<f64>| {
        if crowded {
            geometry.make_valid().map_err(|e| e.to_string())
        } else {
            let none = MultiPolygon::new(Vec::new());
            Ok(geometry.union_with_fill_rule(&none, FillRule::EvenOdd))
        }
    };
    // Either is one call that cannot stop: seconds on a large region (35 s on a crowded star
    // of 200,000 vertices crossing itself).
    let repaired = if region.geometry.coords_count() > WATCHED_REPAIR {
        let geometry = region.geometry.clone();
        watch::watched(1, move || repair(&geometry), |_| go_on()).ok_or(Error::Cancelled)?
    } else {
        repair(&region.geometry)
    };
    let repaired = repaired.map_err(|e| {
        Error::input(
            Some(id),
            format!("the polygon is invalid ({problem}) and cannot be repaired: {e}"),
        )
    })?;
    let repaired = canonical(repaired);
    if !has_area(&repaired) {
        return Err(Error::input(
            Some(id),
            format!("the polygon has no area (it is invalid: {problem})"),
        ));
    }
    Ok((Cow::Owned(repaired), Some(problem)))
}

/// `polygons` in one order whatever the order they came in: each ring starting at its lowest
/// vertex (x, then y), holes and polygons in the order of their lowest vertices. geo's
/// `MakeValid` traces the repaired rings from a hash set, so their start and order change from
/// one call to the next, and the overlay's follow where the input's rings start; either would
/// change the layer's summed area in its last bits, the cell size and every coordinate written.
fn canonical(polygons: MultiPolygon<f64>) -> MultiPolygon<f64> {
    // The lowest vertex then comes first, and orders the rings.
    let rotated = |ring: &LineString<f64>| {
        let open = &ring.0[..ring.0.len().saturating_sub(1)];
        let Some(k) = geometry::lowest(open) else {
            return ring.clone();
        };
        LineString(open[k..].iter().chain(&open[..=k]).copied().collect())
    };
    let by_first = |a: &LineString<f64>, b: &LineString<f64>| match (a.0.first(), b.0.first()) {
        (Some(p), Some(q)) => p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y)),
        (p, q) => p.is_some().cmp(&q.is_some()),
    };
    let mut polygons: Vec<Polygon<f64>> = (polygons.0.iter())
        .map(|p| {
            let mut holes: Vec<LineString<f64>> = p.interiors().iter().map(rotated).collect();
            holes.sort_by(by_first);
            Polygon::new(rotated(p.exterior()), holes)
        })
        .collect();
    polygons.sort_by(|a, b| by_first(a.exterior(), b.exterior()));
    MultiPolygon(polygons)
}

/// Written so that a NaN area counts as none.
fn has_area(geometry: &MultiPolygon<f64>) -> bool {
    geometry.unsigned_area().partial_cmp(&0.0) == Some(std::cmp::Ordering::Greater)
}

/// Strategy 1 of §7: Gaussian noise on the centroids, σ_i = md × the mean distance from centroid
/// i to its neighbours, redrawn while it falls outside the outline.
fn noisy_centroids(prepared: &Prepared, base: &Network, md: f64, seed: u64) -> Vec<Coord<f64>> {
    let neighbours = forces::neighbours(base, &prepared.neighbours);
    let inside = super::geometry::RingIndex::new(&outline::coords_of(&prepared.rings));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    prepared
        .centroids
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            let distances: Vec<f64> = neighbours[i]
                .iter()
                .map(|&j| {
                    let d = c - prepared.centroids[j];
                    (d.x * d.x + d.y * d.y).sqrt()
                })
                .collect();
            let sigma = md * distances.iter().sum::<f64>() / distances.len().max(1) as f64;
            let Ok(normal) = Normal::new(0.0, sigma) else {
                return c;
            };
            (0..NOISE_DRAWS)
                .map(|_| {
                    c + Coord {
                        x: normal.sample(&mut rng),
                        y: normal.sample(&mut rng),
                    }
                })
                .find(|&p| inside.contains(p))
                .unwrap_or(c)
        })
        .collect()
}

/// Progress over the work units of a run (Snake steps and candidate layouts), shared by the
/// worker threads; remembers a cancellation.
struct Tracker<'a> {
    progress: Progress<'a>,
    /// The bar's share already filled when the tracking begins.
    start: f64,
    /// All the work, in units of one Snake step.
    total: f64,
    /// The work done, in millionths of a unit (an atomic float).
    done: AtomicU64,
    stopped: AtomicBool,
}

impl<'a> Tracker<'a> {
    fn new(progress: Progress<'a>, total: f64, start: f64) -> Self {
        Tracker {
            progress,
            start,
            total: total.max(1.0),
            done: AtomicU64::new(0),
            stopped: AtomicBool::new(false),
        }
    }

    /// Counts `units` more as done and reports them with `message`; false once the caller has
    /// cancelled.
    fn advance(&self, units: f64, message: &str) -> bool {
        if self.cancelled() {
            return false;
        }
        let millionths = (units.max(0.0) * 1e6).round() as u64;
        let done = self.done.fetch_add(millionths, Ordering::Relaxed) + millionths;
        let fraction = self.start + (1.0 - self.start) * (done as f64 / 1e6 / self.total).min(1.0);
        if !(self.progress)(fraction, message) {
            self.stopped.store(true, Ordering::Relaxed);
            return false;
        }
        true
    }

    /// Runs `work` on layout `k` of `count` with a report that names the layout and its stage,
    /// then counts the layout's scoring; [`Error::Cancelled`] once the run is cancelled.
    fn layout_work<T>(
        &self,
        weights: &StageWeights,
        k: usize,
        count: usize,
        work: impl FnOnce(&(dyn Fn(Stage, f64) -> bool + Sync)) -> Result<T, Error>,
    ) -> Result<T, Error> {
        if self.cancelled() {
            return Err(Error::Cancelled);
        }
        let name = format!("layout {} of {count}", k + 1);
        let report = |stage: Stage, share: f64| {
            self.advance(
                share * weights.of(stage),
                &format!("{name}: {}", stage.name()),
            )
        };
        let done = work(&report)?;
        if !report(Stage::Scoring, 1.0) {
            return Err(Error::Cancelled);
        }
        Ok(done)
    }

    fn cancelled(&self) -> bool {
        self.stopped.load(Ordering::Relaxed)
    }
}

/// The parts of one layout that report progress.
#[derive(Clone, Copy)]
enum Stage {
    Assigning,
    Refining,
    Scoring,
}

impl Stage {
    fn name(self) -> &'static str {
        match self {
            Stage::Assigning => "assigning",
            Stage::Refining => "refining",
            Stage::Scoring => "scoring",
        }
    }
}

/// The time of each stage of a layout, in Snake steps, so that the progress fraction follows
/// the clock. All three grow about linearly with the regions, as a Snake step does, so the
/// ratios hold for any layer; they were measured on the 3,107 US counties on one thread (a
/// Snake step about 22 ms; a layout's lattice, assignment and landmass settling 0.27 s, its
/// metrics about 0.02 s, the 800 refinement moves per region 1.1 s).
struct StageWeights {
    refining: f64,
}

impl StageWeights {
    const ASSIGNING: f64 = 12.0;
    const SCORING: f64 = 1.0;
    /// Per refinement move per region.
    const REFINING_PER_MOVE: f64 = 50.0 / 800.0;

    fn new(params: &Params) -> Self {
        StageWeights {
            refining: if params.refine {
                Self::REFINING_PER_MOVE * params.refine_moves_per_region as f64
            } else {
                0.0
            },
        }
    }

    fn of(&self, stage: Stage) -> f64 {
        match stage {
            Stage::Assigning => Self::ASSIGNING,
            Stage::Refining => self.refining,
            Stage::Scoring => Self::SCORING,
        }
    }

    /// A Snake step's wall time per region, in seconds, as the whole run's work divides among
    /// the cores (two): a layout stage of 1.33 s for 258 steps on the US counties, 0.13 s for
    /// 1,818 on the US states (2026-12-06, BENCHMARKS.md "Progress").
    const STEP_SECONDS_PER_REGION: f64 = 1.6e-6;

    /// A Snake step's wall time on `regions` regions, in seconds.
    fn step_seconds(regions: usize) -> f64 {
        Self::STEP_SECONDS_PER_REGION * regions.max(1) as f64
    }

    /// Checking and preparing an input of `vertices` vertices and `regions` regions (reading it
    /// is the host's share), in Snake steps ([`Preparation`]).
    fn preparation(vertices: usize, regions: usize) -> f64 {
        Preparation::of(vertices, regions).seconds() / Self::step_seconds(regions)
    }

    /// A layout before refinement: assigned and scored.
    fn plain(&self) -> f64 {
        Self::ASSIGNING + Self::SCORING
    }

    /// The refinement of a layout, and its scoring again.
    fn refinement(&self) -> f64 {
        self.refining + Self::SCORING
    }
}

/// The time the input's preparation is expected to take, in seconds: checking the geometry
/// (0.065 s of 0.38 s on the US states at 10⁶ vertices, 0.075 s of 0.33 s on the US counties:
/// 0.07 µs a vertex; 2026-12-06, BENCHMARKS.md "Progress"), then the outline's costly stages
/// ([`outline::expected_seconds`]) and the rest (13 µs a region, for the centroids and the
/// network, and 15 ms besides, fitted to the US counties and states as given).
struct Preparation {
    checking: f64,
    outline: f64,
}

impl Preparation {
    fn of(vertices: usize, regions: usize) -> Preparation {
        Preparation {
            checking: 0.07e-6 * vertices as f64,
            outline: 0.015 + outline::expected_seconds(vertices, regions) + 13e-6 * regions as f64,
        }
    }

    fn seconds(&self) -> f64 {
        self.checking + self.outline
    }

    /// The share of the preparation that checking the geometry takes.
    fn checking_share(&self) -> f64 {
        self.checking / self.seconds()
    }
}

/// What a Snake run's first layout hands on to the run's others.
struct RunStart {
    /// Its assignment's prices per landmass (none with groups).
    prices: Vec<Option<Prices>>,
    /// Its thin landmasses drawn again, when it kept them so (thin.rs).
    redrawn: Option<thin::Redrawn>,
}

/// One candidate layout, in the sorted region order.
struct Layout {
    lattice: Lattice,
    /// Per region, an index into `lattice.cells`.
    cells: Vec<usize>,
    metrics: LayoutMetrics,
    region_metrics: Vec<RegionMetrics>,
    moved_outline: MultiPolygon<f64>,
    /// The moved centroids the cells were assigned to (bent onto the pins, if any).
    moved: Vec<Coord<f64>>,
    /// How many times its landmasses' blocks break ([`metrics::landmass_breaks`]).
    breaks: usize,
    /// How many regions lie nearer another landmass than their own: the wrong-landmass share's
    /// count, from the share (the regions it counts are the same for every layout).
    astray: usize,
    /// How many of its holes are the source's (method.md §8: a lake, a missing region may
    /// stay): the area, in fitted cells, of the regions' holes that are not slivers between
    /// them ([`metrics::Reference::lake_share`]). Counted by area, not by place: a ring of
    /// regions round a lake encloses hundreds of thousands of positions (a ring of 3,000
    /// regions), and ranking every one a defect passed over layouts that keep the lake.
    lakes: u32,
}

impl Layout {
    /// The layout's holes beyond the source's own: its defects among them.
    fn stray_holes(&self) -> usize {
        self.metrics.holes.saturating_sub(self.lakes) as usize
    }
}

/// The regions' blocks (method.md §10): per landmass of the layout, each group's regions, in
/// the geometric order; without groups, the landmasses.
///
/// With groups, the landmasses are those of the regions' union, each laid on the part of the
/// simplified outline that most of its regions lie on: simplifying to a hundredth of a cell cuts
/// necks far narrower than a cell (Whidbey Island's 3 km of shore with the mainland, under
/// cells of 50 km), which would part an island county from its state's block although the two
/// share a border.
fn blocks_of(
    regions: &[Region],
    order: &[usize],
    prepared: &Prepared,
    grouped: bool,
) -> groups::Blocks {
    let part_of = if grouped {
        let landmasses = prepared
            .landmass_of
            .iter()
            .map(|&l| l + 1)
            .max()
            .unwrap_or(0);
        let mut counts: Vec<HashMap<usize, usize>> = vec![HashMap::new(); landmasses];
        for (&l, &p) in prepared.landmass_of.iter().zip(&prepared.part_of) {
            *counts[l].entry(p).or_default() += 1;
        }
        let main: Vec<usize> = (counts.iter())
            .map(|c| {
                (c.iter())
                    .max_by_key(|&(&p, &n)| (n, std::cmp::Reverse(p)))
                    .map_or(0, |(&p, _)| p)
            })
            .collect();
        prepared.landmass_of.iter().map(|&l| main[l]).collect()
    } else {
        prepared.part_of.clone()
    };
    let mut names: HashMap<&str, usize> = HashMap::new();
    let group_of: Vec<Option<usize>> = (order.iter())
        .map(|&i| {
            if !grouped {
                // One group: the blocks are the landmasses.
                return Some(0);
            }
            let next = names.len();
            // A blank name is no name: a group of its own, as a null is.
            let group = regions[i]
                .group
                .as_deref()
                .filter(|g| !g.trim().is_empty())?;
            Some(*names.entry(group).or_insert(next))
        })
        .collect();
    groups::Blocks::new(&part_of, &group_of)
}

/// What every candidate shares.
struct Context<'a> {
    /// Each region's block, and whether the layer has groups at all.
    blocks: groups::Blocks,
    grouped: bool,
    /// The pinned regions and their positions, by region.
    pins: Vec<(usize, Position)>,
    prepared: &'a Prepared,
    frame: Frame,
    /// What the layouts are scored against; its landmasses, in map units, also tell the
    /// landmass blocks and the refinement where a region would be nearer another landmass than
    /// its own, so that they answer as the metric does.
    reference: metrics::Reference,
    /// Where an island goes when its coast's cells lie far from its fitted place.
    anchors: landmass::Anchors,
    params: &'a Params,
}

impl Context<'_> {
    /// Lattice, assignment and metrics for one Snake run and one origin shift (§6), before
    /// refinement, with what starts the run's other layouts; `start` is what the run's first
    /// layout handed on (`None`: this is the first). [`Error::Cancelled`] once `report`
    /// returns false.
    fn layout(
        &self,
        network: &Network,
        run: &SnakeRun,
        shift: [f64; 2],
        start: Option<&RunStart>,
        report: &(dyn Fn(Stage, f64) -> bool + Sync),
    ) -> Result<(Layout, RunStart), Error> {
        let m = network.centroids;
        let mut moved: Cow<[Coord<f64>]> = Cow::Borrowed(&run.positions[..m]);
        let mut moved_outline = outline::polygons_of(&network.outline_rings(&run.positions));
        let mut demands = vec![0; moved_outline.0.len()];
        for &p in &self.blocks.of {
            let p = self.blocks.landmass[p];
            // A part the moved outline lost (a ring collapsed by the Snake) has no cells.
            *demands.get_mut(p).ok_or_else(|| {
                Error::Internal(format!("the moved outline lost landmass {p}"))
            })? += 1;
        }
        // Gaps between groups take cells of their own, which the lattice's cell size counts.
        let gap = self.grouped && self.params.group_gap > 0;
        if gap {
            demands = groups::cells_with_gaps(&self.blocks, demands.len());
        }
        let wanted: usize = demands.iter().sum();
        let tiling = Tiling::of(self.params);
        let lattice = if self.pins.is_empty() {
            grid::frame(&moved_outline, wanted, shift, tiling)
        } else {
            let pinned: Vec<(Position, Coord<f64>)> =
                self.pins.iter().map(|&(i, p)| (p, moved[i])).collect();
            // The rest follows the pins: the moved network bent so that each pinned region's
            // centroid lies on its cell.
            let (lattice, warp) = pins::place(&moved_outline, wanted, &pinned, tiling);
            moved = Cow::Owned(moved.iter().map(|&c| warp.at(c)).collect());
            moved_outline = geo::MapCoords::map_coords(&moved_outline, |c| warp.at(c));
            lattice
        };
        // One multipolygon per part of the outline: polygons_of keeps the parts' order.
        let parts: Vec<MultiPolygon<f64>> = (moved_outline.0.iter())
            .map(|p| MultiPolygon(vec![p.clone()]))
            .collect();
        // The pinned regions' cells come first, in the order of `self.pins`.
        let fixed: Vec<LatticeCell> = (self.pins.iter())
            .map(|&(i, (col, row))| LatticeCell {
                col,
                row,
                score: 0.0,
                part: self.blocks.landmass[self.blocks.of[i]],
            })
            .collect();
        let select = |parts: &[MultiPolygon<f64>]| {
            let selection = landmass::select(
                &lattice,
                parts,
                &demands,
                self.params.refine_cell_ratio,
                &fixed,
            );
            if selection.assigned != wanted {
                return Err(Error::Internal(format!(
                    "the lattice has {} cells for {wanted}",
                    selection.assigned
                )));
            }
            Ok(selection)
        };
        type Report<'r> = dyn Fn(Stage, f64) -> bool + Sync + 'r;
        let prices = start.map_or(&[][..], |start| &start.prices[..]);
        let lay = |selection, points: &[Coord<f64>], report: &Report| {
            self.laid_out(
                lattice.clone(),
                selection,
                points,
                &moved_outline,
                prices,
                report,
            )
        };
        let (layout, prices, redrawn) = match start {
            // A later layout takes the first's figure; its own hand-on is not read.
            Some(start) => {
                let (figure, points) = match &start.redrawn {
                    Some(redrawn) => (&redrawn.parts[..], &redrawn.points[..]),
                    None => (&parts[..], &moved[..]),
                };
                let (layout, prices) = lay(select(figure)?, points, report)?;
                (layout, prices, None)
            }
            None => {
                // The run's first layout decides for the run whether its thin landmasses are
                // drawn again: the figure depends on the moved outline and the cell size, which
                // the shifts share, and trying both at every shift doubled a thin layer's time.
                let selection = select(&parts)?;
                let assigned = &selection.cells[..selection.assigned];
                let redrawn =
                    thin::redrawn(&lattice, assigned, &parts, &moved, &self.prepared.part_of);
                let (plain, prices) = lay(selection, &moved, report)?;
                match redrawn {
                    // Its work is not in the progress shares, which the plain layout has taken.
                    Some(redrawn) => {
                        let silent = |stage: Stage, _: f64| report(stage, 0.0);
                        let (thick, thick_prices) =
                            lay(select(&redrawn.parts)?, &redrawn.points, &silent)?;
                        // Kept only where the plain cells failed the landmass: where they make
                        // a strip's shorter stretch, the fit puts its regions near home, and
                        // the thicker figure only turns their neighbours (thin.rs).
                        if thick.metrics.location < thin::GAIN * plain.metrics.location {
                            (thick, thick_prices, Some(redrawn))
                        } else {
                            (plain, prices, None)
                        }
                    }
                    None => (plain, prices, None),
                }
            }
        };
        Ok((layout, RunStart { prices, redrawn }))
    }

    /// The regions (moved centroids `moved`) assigned among the cells `selection` holds on
    /// `lattice` for the landmasses of `moved_outline`, each landmass's block settled where §8
    /// measures it from, and scored; with the assignment's prices per landmass (none with
    /// groups).
    fn laid_out(
        &self,
        mut lattice: Lattice,
        selection: landmass::Selection,
        moved: &[Coord<f64>],
        moved_outline: &MultiPolygon<f64>,
        start: &[Option<Prices>],
        report: &(dyn Fn(Stage, f64) -> bool + Sync),
    ) -> Result<(Layout, Vec<Option<Prices>>), Error> {
        let gap = self.grouped && self.params.group_gap > 0;
        lattice.cells = selection.cells;
        if !self.pins.is_empty() {
            let tiling = lattice.tiling;
            pins::bridge(
                &mut lattice.cells,
                self.pins.len(),
                selection.assigned,
                tiling,
            );
        }
        let (cells, prices) = if self.grouped {
            if !gap {
                // Without gaps the blocks share out exactly the landmasses' cells.
                lattice.cells.truncate(selection.assigned);
            }
            let pinned: FxHashMap<Position, usize> =
                self.pins.iter().map(|&(i, p)| (p, i)).collect();
            let cells = groups::assign(&mut lattice, &self.blocks, moved, gap, &pinned, &|done| {
                report(Stage::Assigning, done)
            })
            .ok_or(Error::Cancelled)?;
            (cells, Vec::new())
        } else {
            self.assign(&mut lattice, moved, moved_outline.0.len(), start, report)?
        };
        let area = &self.prepared.area_centroids;
        let home = &self.reference.landmasses;
        let misplaced = |region: usize, p: Coord<f64>| home.misplaced(region, self.frame.to_map(p));
        let homes = landmass::Homes {
            places: area,
            anchors: &self.anchors,
            adjacency: &self.prepared.neighbours,
            misplaced: home.any_counted().then_some(&misplaced),
        };
        let anchored = |of: &dyn Fn(usize) -> usize| {
            let mut anchored: Vec<usize> = self.pins.iter().map(|&(i, _)| of(i)).collect();
            anchored.sort_unstable();
            anchored.dedup();
            anchored
        };
        let parts_pinned = anchored(&|i| lattice.cells[cells[i]].part);
        landmass::settle(&mut lattice, &cells, &homes, self.params, &parts_pinned);
        if self.grouped {
            let blocks_pinned = anchored(&|i| self.blocks.of[i]);
            groups::dock(&mut lattice, &self.blocks, area, gap, &blocks_pinned);
        }
        let layout = self.scored(lattice, cells, moved_outline.clone(), moved.to_vec());
        Ok((layout, prices))
    }

    /// `layout` refined (§6b) with `seed`, and scored again.
    fn refined(
        &self,
        layout: Layout,
        seed: u64,
        report: &(dyn Fn(Stage, f64) -> bool + Sync),
    ) -> Result<Layout, Error> {
        let cells = self.refine(&layout.lattice, &layout.cells, layout.lakes, seed, report)?;
        Ok(self.scored(layout.lattice, cells, layout.moved_outline, layout.moved))
    }

    /// A layout with its metrics and its landmasses' breaks.
    fn scored(
        &self,
        lattice: Lattice,
        cells: Vec<usize>,
        moved_outline: MultiPolygon<f64>,
        moved: Vec<Coord<f64>>,
    ) -> Layout {
        let (metrics, region_metrics) = self.evaluate(&lattice, &cells, &moved);
        let (positions, landmasses): (Vec<(i32, i32)>, Vec<usize>) = (cells.iter())
            .map(|&k| {
                let cell = lattice.cells[k];
                ((cell.col, cell.row), cell.part)
            })
            .unzip();
        let mut breaks = metrics::landmass_breaks(&positions, &landmasses, lattice.tiling);
        if self.grouped {
            breaks += metrics::landmass_breaks(&positions, &self.blocks.of, lattice.tiling);
        }
        let counted = (0..cells.len())
            .filter(|&i| self.reference.landmasses.counts(i))
            .count();
        let astray = (metrics.wrong_landmass * counted as f64).round() as usize;
        Layout {
            breaks,
            astray,
            lakes: (metrics.source_holes * self.reference.lake_share).round() as u32,
            lattice,
            cells,
            metrics,
            region_metrics,
            moved_outline,
            moved,
        }
    }

    /// Each landmass's regions assigned among its own cells (method.md §6), the first `m` of
    /// `lattice.cells`: per region, an index into them, and per landmass the assignment's
    /// prices, started from `start`'s where it has them. The pinned regions take the first
    /// cells, one each, in the order of `self.pins`.
    fn assign(
        &self,
        lattice: &mut Lattice,
        moved: &[Coord<f64>],
        parts: usize,
        start: &[Option<Prices>],
        report: &(dyn Fn(Stage, f64) -> bool + Sync),
    ) -> Result<(Vec<usize>, Vec<Option<Prices>>), Error> {
        let m = moved.len();
        let part_of = &self.prepared.part_of;
        debug_assert!((0..m).all(|i| self.blocks.landmass[self.blocks.of[i]] == part_of[i]));
        let mut cells = vec![0; m];
        let mut prices = Vec::with_capacity(parts);
        let mut free = vec![true; m];
        for (k, &(i, _)) in self.pins.iter().enumerate() {
            cells[i] = k;
            free[i] = false;
        }
        let pinned = self.pins.len();
        for part in 0..parts {
            let regions: Vec<usize> = (0..m).filter(|&i| free[i] && part_of[i] == part).collect();
            let own: Vec<usize> = (pinned..m)
                .filter(|&k| lattice.cells[k].part == part)
                .collect();
            let points: Vec<Coord<f64>> = regions.iter().map(|&i| moved[i]).collect();
            let centres: Vec<Coord<f64>> = (own.iter())
                .map(|&k| lattice.centre(lattice.cells[k].col, lattice.cells[k].row))
                .collect();
            // Each landmass's share of the assignment is its share of the regions.
            let share = regions.len() as f64 / m as f64;
            let part_start = start.get(part).and_then(Option::as_ref);
            let (choices, part_prices) =
                assign::assign_from(&points, &centres, part_start, &|done| {
                    report(Stage::Assigning, done * share)
                })
                .ok_or(Error::Cancelled)?;
            for (&region, choice) in regions.iter().zip(choices) {
                cells[region] = own[choice];
            }
            prices.push(part_prices);
        }
        Ok((cells, prices))
    }

    /// The refinement (§6b) of `cells` on `lattice`, towards where §8 will measure each region
    /// from: its area centroid, taken into the lattice's frame by the scale-and-shift fit of
    /// `cells`; up to `lakes` holes are the source's.
    fn refine(
        &self,
        lattice: &Lattice,
        cells: &[usize],
        lakes: u32,
        seed: u64,
        report: &(dyn Fn(Stage, f64) -> bool + Sync),
    ) -> Result<Vec<usize>, Error> {
        let area = &self.prepared.area_centroids;
        let assigned: Vec<Coord<f64>> = (cells.iter())
            .map(|&k| lattice.centre(lattice.cells[k].col, lattice.cells[k].row))
            .collect();
        let (scale, offset) = metrics::fit(&assigned, area);
        let targets: Vec<Coord<f64>> = (0..area.len())
            .map(|i| {
                let centre_of = |j: usize| assigned[j];
                (self.anchors)
                    .target(i, area, centre_of, (scale, offset), lattice.cell_size)
                    .0
            })
            .collect();
        let home = &self.reference.landmasses;
        let nearer_another = |landmass: usize, (col, row): (i32, i32)| {
            let place = lattice.centre(col, row) * scale + offset;
            home.nearer_another(landmass, self.frame.to_map(place))
        };
        // With groups, a region only swaps cells within its block, so every block keeps its
        // patch: the refinement sees the blocks as its landmasses, and no free cells.
        let mut tagged = lattice.clone();
        let mut part_of = if self.grouped {
            for (cell, &block) in tagged.cells.iter_mut().zip(&self.blocks.of) {
                cell.part = block;
            }
            self.blocks.of.clone()
        } else {
            self.prepared.part_of.clone()
        };
        // A pinned region is a landmass of its own with one cell: nothing swaps with it and it
        // has no free cell to move to.
        let parts = part_of
            .iter()
            .chain(tagged.cells.iter().map(|c| &c.part))
            .max();
        let first_own = parts.map_or(0, |&p| p + 1);
        for (k, &(i, _)) in self.pins.iter().enumerate() {
            part_of[i] = first_own + k;
            tagged.cells[cells[i]].part = first_own + k;
        }
        let (lattice, part_of) = (&tagged, &part_of);
        let layout = refine::Layout {
            adjacency: &self.prepared.neighbours,
            centroids: area,
            targets: &targets,
            lattice,
            part_of,
            misplaced: home.any_counted().then_some(refine::Misplaced {
                landmass_of: home.of(),
                nearer_another: &nearer_another,
            }),
            lakes,
            // Pins bend the layout to the user's cells, and a region may have to sit far from
            // its place for them: the rule fights the pins (held in every search, with the
            // NYT's five pins, seeds 0-5: adjacency 0.886 → 0.874; BENCHMARKS.md "Left alone
            // far from home").
            keep_company: self.pins.is_empty(),
        };
        refine::refine(&layout, cells, self.params, seed, &|done| {
            report(Stage::Refining, done)
        })
        .ok_or(Error::Cancelled)
    }

    /// The §8 metrics, in map units.
    fn evaluate(
        &self,
        lattice: &Lattice,
        cells: &[usize],
        moved: &[Coord<f64>],
    ) -> (LayoutMetrics, Vec<RegionMetrics>) {
        let f = &self.frame;
        let moved: Vec<Coord<f64>> = moved.iter().map(|&c| f.to_map(c)).collect();
        let col_rows: Vec<(i32, i32)> = cells
            .iter()
            .map(|&k| (lattice.cells[k].col, lattice.cells[k].row))
            .collect();
        let centres: Vec<Coord<f64>> = col_rows
            .iter()
            .map(|&(c, r)| f.to_map(lattice.centre(c, r)))
            .collect();
        metrics::evaluate(&Scored {
            tiling: lattice.tiling,
            reference: &self.reference,
            moved: &moved,
            cells: &col_rows,
            centres: &centres,
            cell_size: lattice.cell_size * f.scale,
        })
    }

    /// The chosen layout in the input order and in map units, columns and rows counted from the
    /// top-left used cell, or with pins in the pins' frame (for hexagons, offset columns and
    /// rows: [`Tiling::offset_coordinates`]).
    fn grid_map(
        &self,
        regions: &[Region],
        order: &[usize],
        best: &Layout,
        run: &SnakeRun,
        candidates: Vec<CandidateReport>,
        notes: Vec<String>,
    ) -> GridMap {
        let f = &self.frame;
        let lattice = &best.lattice;
        let positions: Vec<(i32, i32)> = (best.cells.iter())
            .map(|&k| (lattice.cells[k].col, lattice.cells[k].row))
            .collect();
        let used: Vec<(i32, i32)> = (positions.iter())
            .map(|&p| lattice.tiling.offset_coordinates(p))
            .collect();
        // With pins, the pins' own frame; else from the top-left used cell.
        let from = |pick: fn(&(i32, i32)) -> i32| match self.pins.is_empty() {
            true => used.iter().map(pick).min().unwrap_or(0),
            false => 0,
        };
        let (col0, row0) = (from(|c| c.0), from(|c| c.1));
        // Axial positions from the one at offset column 0, row 0.
        let reference = lattice.tiling.from_offset_coordinates((col0, row0));
        // Blocks numbered by their top row, then their leftmost column in it.
        let mut corner = vec![(i32::MAX, i32::MAX); self.blocks.count()];
        for (k, &(col, row)) in used.iter().enumerate() {
            let c = &mut corner[self.blocks.of[k]];
            *c = (*c).min((row, col));
        }
        let mut by_corner: Vec<usize> = (0..corner.len()).collect();
        by_corner.sort_by_key(|&b| (corner[b], b));
        let mut number = vec![0u32; corner.len()];
        for (n, &b) in by_corner.iter().enumerate() {
            number[b] = n as u32 + 1;
        }
        let mut cells: Vec<Option<RegionCell>> = vec![None; regions.len()];
        for (k, &input) in order.iter().enumerate() {
            let (col, row) = used[k];
            let square = lattice.polygon(positions[k].0, positions[k].1);
            cells[input] = Some(RegionCell {
                id: regions[input].id.clone(),
                col: col - col0,
                row: row - row0,
                q: positions[k].0 - reference.0,
                r: positions[k].1 - reference.1,
                block: number[self.blocks.of[k]],
                cell: geo::MapCoords::map_coords(&square, |c| f.to_map(c)),
                centroid: f.to_map(self.prepared.centroids[k]),
                moved_centroid: f.to_map(run.positions[k]),
                metrics: best.region_metrics[k],
                repair: None,
            });
        }
        let mut adjacency: Vec<(usize, usize)> = self
            .prepared
            .adjacency
            .iter()
            .map(|&(i, j)| {
                let (a, b) = (order[i], order[j]);
                (a.min(b), a.max(b))
            })
            .collect();
        adjacency.sort_unstable();
        GridMap {
            tiling: lattice.tiling,
            shifted: match lattice.tiling {
                // Internally the odd rows (pointy) or columns (flat) sit half a cell further.
                Tiling::Square => None,
                Tiling::Hex(HexOrientation::Pointy) => Some((row0 + 1).rem_euclid(2)),
                Tiling::Hex(HexOrientation::Flat) => Some((col0 + 1).rem_euclid(2)),
            },
            cells: cells.into_iter().flatten().collect(),
            cell_size: lattice.cell_size * f.scale,
            metrics: best.metrics,
            groups: self.grouped.then(|| {
                let centres: Vec<Coord<f64>> = positions
                    .iter()
                    .map(|&(c, r)| lattice.centre(c, r))
                    .collect();
                groups::metrics(&groups::GroupLayout {
                    blocks: &self.blocks,
                    positions: &positions,
                    centres: &centres,
                    places: &self.prepared.area_centroids,
                    adjacency: &self.prepared.neighbours,
                    tiling: lattice.tiling,
                    gap: self.params.group_gap,
                })
            }),
            snake: run.report.clone(),
            candidates,
            moved_outline: f.polygons_to_map(&outline::drawable(&best.moved_outline)),
            adjacency,
            notes,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_repaired_region_keeps_the_neighbour_its_dropped_spike_ran_along() {
        // A's only border with B is a spike out along B's bottom edge and back: a repair drops
        // the spike (it has no area), which leaves A and B meeting at a corner. As drawn, they
        // share a border of length 1, and the judge counts them adjacent.
        let polygon = |ring: Vec<(f64, f64)>| {
            MultiPolygon(vec![Polygon::new(LineString::from(ring), vec![])])
        };
        let region = |id: &str, geometry| Region {
            id: id.into(),
            geometry,
            group: None,
            pin: None,
        };
        let spiked = polygon(vec![
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 0.5),
            (2.0, 0.5),
            (1.0, 0.5),
            (0.0, 0.5),
        ]);
        let beside = polygon(vec![(1.0, 0.5), (2.0, 0.5), (2.0, 1.5), (1.0, 1.5)]);
        let map = generate(
            &[region("a", spiked), region("b", beside)],
            &Params::default(),
            &|_, _| true,
        )
        .unwrap();
        assert!(map
            .notes
            .iter()
            .any(|n| n.contains("feature a: invalid polygon repaired")));
        assert_eq!(map.adjacency, vec![(0, 1)]);
        // Each region's own repair comes with its cell, as its note says it.
        let repair = map.cells[0].repair.as_deref().expect("a was repaired");
        assert!(repair.starts_with("a ring "), "{repair}");
        let note = format!("feature a: invalid polygon repaired ({repair})");
        assert!(map.notes.contains(&note), "{:?}", map.notes);
        assert_eq!(map.cells[1].repair, None);
    }

    #[test]
    fn many_repairs_are_listed_up_to_ten_and_then_counted_by_kind() {
        let regions: Vec<Region> = (0..16)
            .map(|k| Region {
                id: format!("r{k}"),
                geometry: MultiPolygon(vec![]),
                group: None,
                pin: None,
            })
            .collect();
        let crossing = Problem::SelfIntersection(Coord { x: 1.0, y: 2.0 });
        let outside = Problem::HoleOutside;
        // r1 is valid; of the 15 others, the last four are summed up.
        let mut problems: Vec<Option<&Problem>> = vec![Some(&crossing); 16];
        problems[1] = None;
        problems[14] = Some(&outside);
        let notes = repair_notes(&regions, &problems);
        assert_eq!(notes.len(), 11);
        assert_eq!(
            notes[0],
            "feature r0: invalid polygon repaired (a ring intersects itself at (1, 2))"
        );
        assert!(notes[9].starts_with("feature r10: "));
        assert_eq!(
            notes[10],
            "5 more invalid polygons repaired (features r11, r12, r13, r14, r15): 4 where a ring \
             intersects itself, 1 where a hole lies outside its polygon's shell; each region's \
             problem comes with its cell (the JSON report's regions[].repair)"
        );
        // Eleven are all listed: a summary of one would be no shorter.
        let notes = repair_notes(&regions[..12], &problems[..12]);
        assert_eq!(notes.len(), 11);
        assert!(notes
            .iter()
            .all(|n| n.contains("invalid polygon repaired (")));
        assert!(repair_notes(&regions[1..2], &problems[1..2]).is_empty());
    }

    #[test]
    fn checking_the_geometry_reports_as_it_goes_and_hears_a_cancel() {
        // 200 squares in a row: the check reports each hundredth of the vertices it has seen.
        let regions: Vec<Region> = (0..200)
            .map(|k| {
                let x = k as f64;
                Region {
                    id: format!("r{k}"),
                    geometry: MultiPolygon(vec![Polygon::new(
                        LineString::from(vec![(x, 0.0), (x + 1.0, 0.0), (x + 1.0, 1.0), (x, 1.0)]),
                        vec![],
                    )]),
                    group: None,
                    pin: None,
                }
            })
            .collect();
        let checking =
            |fraction: f64, message: &str| message == "checking geometry" && fraction > 0.0;
        let heard = AtomicUsize::new(0);
        generate(&regions, &Params::default(), &|fraction, message| {
            if checking(fraction, message) {
                heard.fetch_add(1, Ordering::Relaxed);
            }
            true
        })
        .unwrap();
        assert!(heard.into_inner() >= 50, "reports while checking");
        // Cancelled at the first of them: the run ends there, before the outline.
        let outline = AtomicBool::new(false);
        let result = generate(&regions, &Params::default(), &|fraction, message| {
            outline.fetch_or(message.starts_with("outline"), Ordering::Relaxed);
            !checking(fraction, message)
        });
        assert_eq!(result.err(), Some(Error::Cancelled));
        assert!(!outline.into_inner());
    }

    #[test]
    fn a_long_repair_hears_a_cancel() {
        // A star of 6,000 vertices (over `WATCHED_REPAIR`) whose ring crosses itself where two
        // of its tips are swapped.
        let mut tips: Vec<(f64, f64)> = (0..6000)
            .map(|k| {
                let (r, a) = (if k % 2 == 0 { 10.0 } else { 6.0 }, k as f64 / 6000.0);
                let a = a * std::f64::consts::TAU;
                (r * a.cos(), r * a.sin())
            })
            .collect();
        tips.swap(1000, 1003);
        let star = Region {
            id: "star".into(),
            geometry: MultiPolygon(vec![Polygon::new(LineString::from(tips), vec![])]),
            group: None,
            pin: None,
        };
        assert!(validity::problem(&star.geometry).is_some());
        // The check reports its end; the repair asks at the check's end again, and is told to
        // stop.
        let heard = Mutex::new(Vec::new());
        let result = generate(&[star], &Params::default(), &|fraction, message| {
            let mut heard = heard.lock().unwrap();
            let again = heard.last() == Some(&(fraction, message.to_owned()));
            heard.push((fraction, message.to_owned()));
            !(message == "checking geometry" && fraction > 0.0 && again)
        });
        assert_eq!(result.err(), Some(Error::Cancelled));
        let heard = heard.into_inner().unwrap();
        assert!(heard
            .iter()
            .all(|(_, message)| message == "checking geometry"));
    }

    #[test]
    fn of_two_bad_features_the_first_in_input_order_is_named_on_any_thread() {
        // 400 squares in a row, of which two are bad: a NaN corner, or flat (no area). A
        // sequential check meets feature 150 first; rayon's collect into a Result reported
        // whichever a worker met first, and the two halves of the layer start on different
        // workers.
        let ring = |k: usize, top: f64, corner: f64| {
            let x = k as f64;
            MultiPolygon(vec![Polygon::new(
                LineString::from(vec![(x, 0.0), (x + 1.0, 0.0), (x + 1.0, top), (x, corner)]),
                vec![],
            )])
        };
        let params = Params {
            threads: 4,
            ..Params::default()
        };
        let nan_corner = |k| ring(k, 1.0, f64::NAN);
        let flat = |k| ring(k, 0.0, 0.0);
        for (bad, message) in [
            (&nan_corner as &dyn Fn(usize) -> MultiPolygon<f64>, "NaN"),
            (&flat, "no area"),
        ] {
            let regions: Vec<Region> = (0..400)
                .map(|k| Region {
                    id: format!("r{k}"),
                    geometry: if k == 150 || k == 390 {
                        bad(k)
                    } else {
                        ring(k, 1.0, 1.0)
                    },
                    group: None,
                    pin: None,
                })
                .collect();
            for _ in 0..20 {
                match generate(&regions, &params, &|_, _| true) {
                    Err(Error::InvalidInput {
                        feature,
                        message: m,
                    }) => {
                        assert_eq!(feature.as_deref(), Some("r150"), "{m}");
                        assert!(m.contains(message), "{m}");
                    }
                    other => panic!("feature r150 was not refused: {:?}", other.err()),
                }
            }
        }
    }

    #[test]
    fn a_repair_keeps_what_make_valid_keeps() {
        // Even-odd, as geo's `MakeValid`: a ring crossing itself keeps both loops, a loop inside
        // its ring becomes a hole, a spike cancels; and on a ring of 10,000 vertices crossing
        // itself once (the overlay's case: short segments), the same two parts.
        let region = |ring: Vec<Coord<f64>>| Region {
            id: "r".into(),
            geometry: MultiPolygon(vec![Polygon::new(LineString(ring), vec![])]),
            group: None,
            pin: None,
        };
        let c = |x: f64, y: f64| Coord { x, y };
        let bowtie = vec![c(0.0, 0.0), c(2.0, 2.0), c(2.0, 0.0), c(0.0, 2.0)];
        // Round the square to (4, 4), then a loop back inside it, crossing the first side.
        let inner_loop = vec![
            c(0.0, 0.0),
            c(4.0, 0.0),
            c(4.0, 4.0),
            c(0.0, 4.0),
            c(0.0, 1.0),
            c(3.0, 1.0),
            c(3.0, 3.0),
            c(1.0, 3.0),
            c(1.0, -1.0),
        ];
        let spike = vec![
            c(0.0, 0.0),
            c(1.0, 0.0),
            c(1.0, 1.0),
            c(3.0, 1.0),
            c(1.0, 1.0),
            c(0.0, 1.0),
        ];
        let dense: Vec<Coord<f64>> = (0..10_000)
            .map(|k| {
                let t = k as f64 / 10_000.0 * std::f64::consts::TAU;
                // A circle whose last stretch cuts across its first: a crossing near (1, 0).
                let r = if k < 9_990 {
                    1.0
                } else {
                    1.0 + (k - 9_989) as f64 * 0.01
                };
                c(r * t.cos(), r * t.sin() - if k < 10 { 0.02 } else { 0.0 })
            })
            .collect();
        for (name, ring) in [
            ("bowtie", bowtie),
            ("inner loop", inner_loop),
            ("spike", spike),
            ("dense", dense),
        ] {
            let region = region(ring);
            assert!(!validity::examine(&region.geometry).crowded, "{name}");
            let (ours, problem) = repaired(&region, &|| true).unwrap();
            assert!(problem.is_some(), "{name}");
            let theirs = region.geometry.make_valid().unwrap();
            let shape = |m: &MultiPolygon<f64>| {
                let mut holes: Vec<usize> = m.0.iter().map(|p| p.interiors().len()).collect();
                holes.sort_unstable();
                holes
            };
            assert_eq!(
                shape(&ours),
                shape(&theirs),
                "{name}: {ours:?} against {theirs:?}"
            );
            let (a, b) = (ours.unsigned_area(), theirs.unsigned_area());
            // The overlay snaps to a grid of about 1e-9 of the extent: the dense ring's area
            // moves by its perimeter times that (6e-9 of it).
            assert!((a - b).abs() <= 1e-7 * b, "{name}: area {a} against {b}");
        }
    }

    #[test]
    fn a_repair_comes_out_the_same_every_time() {
        // A ring that crosses itself twice: repaired into three triangles, each traced from
        // where the overlay's sweep meets it.
        let ring: Vec<(f64, f64)> = vec![
            (0.0, 0.0),
            (2.0, 1.0),
            (4.0, 0.0),
            (6.0, 1.0),
            (6.0, 0.0),
            (4.0, 1.0),
            (2.0, 0.0),
            (0.0, 1.0),
        ];
        let region = Region {
            id: "zigzag".into(),
            geometry: MultiPolygon(vec![Polygon::new(LineString::from(ring), vec![])]),
            group: None,
            pin: None,
        };
        let (first, problem) = repaired(&region, &|| true).unwrap();
        assert!(problem.is_some());
        assert!(first.0.len() > 1, "{first:?}");
        for _ in 0..20 {
            assert_eq!(repaired(&region, &|| true).unwrap().0, first);
        }
    }

    #[test]
    fn all_layouts_keep_the_order_of_the_parameters() {
        let shifts = Params::default().shifts;
        let jobs = layout_jobs(3, &shifts, 27);
        let expected: Vec<(usize, [f64; 2])> = (0..3)
            .flat_map(|r| shifts.iter().map(move |&s| (r, s)))
            .collect();
        assert_eq!(jobs, expected);
    }

    #[test]
    fn fewer_layouts_spread_over_runs_and_the_cell() {
        let shifts = Params::default().shifts;
        // By hand: from 0:0 the farthest shifts on the torus are the four diagonal ones, at
        // 0.33·√2; the first of them in the list is 0.33:0.33, and 0.67:0.67 is as far from
        // both.
        let diagonal = [[0.0, 0.0], [0.33, 0.33], [0.67, 0.67]];
        let jobs = layout_jobs(3, &shifts, 9);
        let expected: Vec<(usize, [f64; 2])> = (0..3)
            .flat_map(|r| diagonal.iter().map(move |&s| (r, s)))
            .collect();
        assert_eq!(jobs, expected);
        // One layout: the noise-free run at the first shift; two: two runs.
        assert_eq!(layout_jobs(3, &shifts, 1), vec![(0, [0.0, 0.0])]);
        assert_eq!(
            layout_jobs(3, &shifts, 2),
            vec![(0, [0.0, 0.0]), (1, [0.0, 0.0])]
        );
    }

    #[test]
    fn the_layout_budget_follows_the_regions_unless_given() {
        let mut params = Params::default();
        // 3 runs × 9 shifts.
        assert_eq!(params.layout_count(51), 27);
        assert_eq!(params.layout_count(1000), 27);
        assert_eq!(params.layout_count(3107), 9);
        assert_eq!(params.layout_count(33_000), 1);
        params.max_layouts = Some(5);
        assert_eq!(params.layout_count(33_000), 5);
        params.max_layouts = Some(1000);
        assert_eq!(params.layout_count(10), 27);
        params.noise_levels.clear();
        params.shifts.truncate(2);
        assert_eq!(params.layout_count(10), 2);
    }

    #[test]
    fn the_refined_budget_follows_the_regions_unless_given() {
        let mut params = Params::default();
        // Every candidate of the shared layers but the counties (at most 177 regions).
        assert_eq!(params.refined_count(177, 27), 27);
        assert_eq!(params.refined_count(222, 27), 27);
        assert_eq!(params.refined_count(1000, 27), 6);
        assert_eq!(params.refined_count(2999, 9), 3);
        // One, in stripes, from 3,000 regions on.
        assert_eq!(params.refined_count(3000, 9), 1);
        assert_eq!(params.refined_count(3107, 9), 1);
        assert_eq!(params.refined_count(33_000, 1), 1);
        // Never more than the candidates.
        assert_eq!(params.refined_count(10, 5), 5);
        params.max_refined = Some(4);
        assert_eq!(params.refined_count(33_000, 27), 4);
        assert_eq!(params.refined_count(10, 3), 3);
    }
}
