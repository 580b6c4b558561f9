//! Step 3 (method.md §4–5): the Snake. Every network edge is a beam with elasticity α and
//! rigidity β; the centroid forces load the beams; one sparse Cholesky factorisation per step
//! gives the displacements of all nodes, which are scaled by the step-size rule, limited so the
//! outline cannot fold, checked, and applied.

use super::forces::{self, Forces};
use super::geometry::{point_segment_distance2, RingIndex, Segment};
use super::network::Network;
use super::{Error, LoadModel, Params, SnakeReport, StopReason};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::{Conj, Mat, Par, Side};
use geo::Coord;
use rstar::primitives::GeomWithData;
use rstar::{RTree, AABB};

/// Halvings of a step that stays invalid before the Snake gives up (§4).
const HALVINGS: usize = 4;
/// Steps over which the largest force must fall, for the no-progress stop (§5).
const PROGRESS_WINDOW: usize = 3;
/// Shortest beam length used in the stiffness, in cells: coincident nodes would make the
/// bending terms (1/h³) blow up.
const SHORTEST_BEAM: f64 = 1e-6;
/// Clearance from the outline, in cells, under which rounding could carry a centroid across it
/// despite the step limit: coordinates of a hundred cells round at 1e-14.
const ROUNDING_CLEARANCE: f64 = 1e-9;
/// How far, in multiples of its step, a node's clearance is searched: above the 3 at which a
/// clearance starts to limit the step, with room for rounding.
const REACH: f64 = 4.0;

/// The network after the Snake.
#[derive(Clone, Debug)]
pub struct SnakeRun {
    /// Every node's position (centroids first, as in the network).
    pub positions: Vec<Coord<f64>>,
    pub report: SnakeReport,
}

/// Runs the Snake on `network` with the neighbour lists N(i) of the forces; `keep_going` is asked
/// before every step and cancels the run when it returns false.
pub fn run(
    network: &Network,
    neighbours: &[Vec<usize>],
    params: &Params,
    keep_going: &dyn Fn() -> bool,
) -> Result<SnakeRun, Error> {
    let m = network.centroids;
    let mut positions = network.nodes.clone();
    let spread_before = forces::spread(&positions[..m], neighbours);
    let mut report = SnakeReport {
        steps: 0,
        stop_reason: StopReason::NotRun,
        spread_before,
        spread_after: spread_before,
        nodes: network.nodes.len(),
        edges: network.edges.len(),
    };
    if params.max_steps == 0 || m < 2 {
        return Ok(SnakeRun { positions, report });
    }
    let mut solver = BeamSolver::new(network, params);
    let mut largest_forces = Vec::new();
    // The outline at `positions`: each step's check builds it for the next step's limits.
    let mut outline = RingIndex::new(&network.ring_coords(&positions));
    report.stop_reason = StopReason::MaxSteps;
    while report.steps < params.max_steps {
        if !keep_going() {
            return Err(Error::Cancelled);
        }
        let forces = forces::compute(&positions[..m], neighbours, params.force_cap);
        largest_forces.push(forces.largest);
        if no_progress(&largest_forces) && params.stop_on_no_progress {
            report.stop_reason = StopReason::NoProgress;
            break;
        }
        let displacement = solver.solve(&positions, &forces)?;
        let step = scale_step(displacement, &forces, params.step_ratio);
        let Some((applied, applied_outline)) =
            apply_valid_step(network, &positions, &outline, step)
        else {
            report.stop_reason = StopReason::InvalidStep;
            break;
        };
        report.steps += 1;
        let largest_move = applied
            .iter()
            .zip(&positions)
            .map(|(a, b)| length(*a - *b))
            .fold(0.0, f64::max);
        positions = applied;
        outline = applied_outline;
        if largest_move < params.epsilon {
            report.stop_reason = StopReason::Converged;
            break;
        }
    }
    report.spread_after = forces::spread(&positions[..m], neighbours);
    Ok(SnakeRun { positions, report })
}

fn length(c: Coord<f64>) -> f64 {
    (c.x * c.x + c.y * c.y).sqrt()
}

/// True when the latest `PROGRESS_WINDOW` largest forces are none below the one before them.
fn no_progress(history: &[f64]) -> bool {
    history.len() > PROGRESS_WINDOW && {
        let (before, recent) = history.split_at(history.len() - PROGRESS_WINDOW);
        let reference = before[before.len() - 1];
        recent.iter().all(|&f| f >= reference)
    }
}

/// The beam-element stiffness system of the network, with its sparsity pattern and symbolic
/// factorisation kept across steps (the pattern never changes, only the values): sorting the
/// entries into the pattern anew each step was a fifth of a Snake run on 10,000 regions.
struct BeamSolver<'a> {
    network: &'a Network,
    alpha: f64,
    beta: f64,
    spring: f64,
    load_model: LoadModel,
    pattern: Option<Pattern>,
}

/// Where each entry of the assembly goes in the stiffness matrix, its factorisation's symbolic
/// part, and the factor's values and the work space, kept across steps. Sequential: the Snake
/// runs and layouts already share the cores.
struct Pattern {
    matrix: SymbolicSparseColMat<usize>,
    order: Argsort<usize>,
    llt: SymbolicCholesky<usize>,
    factor: Vec<f64>,
    scratch: MemBuffer,
}

impl<'a> BeamSolver<'a> {
    fn new(network: &'a Network, params: &Params) -> Self {
        BeamSolver {
            network,
            alpha: params.alpha,
            beta: params.beta,
            spring: params.spring,
            load_model: params.load_model,
            pattern: None,
        }
    }

    /// The matrix entries' rows and columns, in the order [`BeamSolver::solve`] assembles
    /// their values: each edge's 4 × 4 block, then each node's two spring terms.
    fn entry_positions(&self, n: usize) -> Vec<Pair<usize, usize>> {
        let mut at = Vec::with_capacity(16 * self.network.edges.len() + 2 * n);
        for &[a, b] in &self.network.edges {
            let dof = [2 * a, 2 * a + 1, 2 * b, 2 * b + 1];
            for row in dof {
                at.extend(dof.map(|col| Pair { row, col }));
            }
        }
        for i in 0..n {
            at.push(Pair {
                row: 2 * i,
                col: 2 * i,
            });
            at.push(Pair {
                row: 2 * i + 1,
                col: 2 * i + 1,
            });
        }
        at
    }

    /// Solves K·D = F for both axes at once and returns each node's displacement.
    fn solve(
        &mut self,
        positions: &[Coord<f64>],
        forces: &Forces,
    ) -> Result<Vec<Coord<f64>>, Error> {
        let n = positions.len();
        let dofs = 2 * n;
        let mut values: Vec<f64> = Vec::with_capacity(16 * self.network.edges.len() + 2 * n);
        let mut load = Mat::<f64>::zeros(dofs, 2);
        let mut diagonal_sum = 0.0;
        let force = |i: usize| forces.vectors.get(i).copied().unwrap_or_default();
        for &[a, b] in &self.network.edges {
            let h = length(positions[b] - positions[a]).max(SHORTEST_BEAM);
            let k = beam_matrix(h, self.alpha, self.beta);
            let dof = [2 * a, 2 * a + 1, 2 * b, 2 * b + 1];
            values.extend(k.iter().flatten());
            diagonal_sum += k[0][0] + k[2][2];
            if self.load_model == LoadModel::Element {
                // Eq. 3 with the slope load of the far end on d'(x_1).
                let (fa, fb) = (force(a), force(b));
                let weights = [h / 2.0, h * h / 12.0, h / 2.0, -h * h / 12.0];
                for (axis, (ua, ub)) in [(fa.x, fb.x), (fa.y, fb.y)].into_iter().enumerate() {
                    for (slot, value) in [ua, ua, ub, ub].into_iter().enumerate() {
                        load[(dof[slot], axis)] += weights[slot] * value;
                    }
                }
            }
        }
        if self.load_model == LoadModel::Nodal {
            for (i, f) in forces.vectors.iter().enumerate() {
                load[(2 * i, 0)] += f.x;
                load[(2 * i, 1)] += f.y;
            }
        }
        // The weak spring to every node's current position makes K definite without pinning an
        // arbitrary node (§4 [differs]).
        let kappa = self.spring * diagonal_sum / n as f64;
        for _ in 0..n {
            // A slope of a node without edges would be a zero row.
            values.extend([kappa, kappa * 1e-6]);
        }
        if self.pattern.is_none() {
            let (matrix, order) =
                SymbolicSparseColMat::try_new_from_indices(dofs, dofs, &self.entry_positions(n))
                    .map_err(|e| Error::Internal(format!("stiffness matrix: {e:?}")))?;
            // Supernodal: faer's own threshold picks the simplicial factorisation for these
            // networks, which took 13 % of a us_counties run against 3 % (the same layouts).
            let llt = factorize_symbolic_cholesky(
                matrix.as_ref(),
                Side::Lower,
                SymmetricOrdering::Amd,
                CholeskySymbolicParams {
                    supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                    ..Default::default()
                },
            )
            .map_err(|e| Error::Internal(format!("symbolic factorisation: {e:?}")))?;
            // Work space for the factorisation and for the solve of both axes' loads.
            let scratch = MemBuffer::try_new(
                llt.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
                    .or(llt.solve_in_place_scratch::<f64>(2, Par::Seq)),
            )
            .map_err(|e| Error::Internal(format!("factorisation work space: {e:?}")))?;
            let factor = vec![0.0; llt.len_val()];
            self.pattern = Some(Pattern {
                matrix,
                order,
                llt,
                factor,
                scratch,
            });
        }
        let pattern = self.pattern.as_mut().expect("made above");
        let matrix =
            SparseColMat::new_from_argsort(pattern.matrix.clone(), &pattern.order, &values)
                .map_err(|e| Error::Internal(format!("stiffness matrix: {e:?}")))?;
        // The ranges of α, β and κ keep K definite on real layers; if rounding still defeats the
        // factorisation, the parameters are what the user can change.
        let llt = pattern
            .llt
            .factorize_numeric_llt(
                &mut pattern.factor,
                matrix.as_ref(),
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut pattern.scratch),
                Default::default(),
            )
            .map_err(|_| {
                Error::InvalidParameter(format!(
                    "parameters alpha {}, beta {} and spring {} make the Snake's stiffness \
                     matrix singular on this layer: choose alpha and beta nearer 1 or a larger \
                     spring",
                    self.alpha, self.beta, self.spring
                ))
            })?;
        let mut solution = load;
        llt.solve_in_place_with_conj(
            Conj::No,
            solution.as_mut(),
            Par::Seq,
            MemStack::new(&mut pattern.scratch),
        );
        Ok((0..n)
            .map(|i| Coord {
                x: solution[(2 * i, 0)],
                y: solution[(2 * i, 1)],
            })
            .collect())
    }
}

/// K_e = α·T(h) + β·B(h) over (d_a, d'_a, d_b, d'_b): the Hermite tension matrix and the
/// Euler-Bernoulli bending matrix of method.md §4 (the paper's Eq. 2 corrected).
fn beam_matrix(h: f64, alpha: f64, beta: f64) -> [[f64; 4]; 4] {
    let t = [
        [6.0 / (5.0 * h), 0.1, -6.0 / (5.0 * h), 0.1],
        [0.1, 2.0 * h / 15.0, -0.1, -h / 30.0],
        [-6.0 / (5.0 * h), -0.1, 6.0 / (5.0 * h), -0.1],
        [0.1, -h / 30.0, -0.1, 2.0 * h / 15.0],
    ];
    let (h2, h3) = (h * h, h * h * h);
    let b = [
        [12.0 / h3, 6.0 / h2, -12.0 / h3, 6.0 / h2],
        [6.0 / h2, 4.0 / h, -6.0 / h2, 2.0 / h],
        [-12.0 / h3, -6.0 / h2, 12.0 / h3, -6.0 / h2],
        [6.0 / h2, 2.0 / h, -6.0 / h2, 4.0 / h],
    ];
    let mut k = [[0.0; 4]; 4];
    for r in 0..4 {
        for c in 0..4 {
            k[r][c] = alpha * t[r][c] + beta * b[r][c];
        }
    }
    k
}

/// The step-size rule (§4): scale all displacements so the centroid with the largest force moves
/// as far as its (capped) force, then shrink so no node moves more than R times that.
fn scale_step(mut d: Vec<Coord<f64>>, forces: &Forces, ratio: f64) -> Vec<Coord<f64>> {
    let goal = length(forces.vectors[forces.worst]);
    let largest = d.iter().map(|&v| length(v)).fold(0.0, f64::max);
    if goal == 0.0 || largest == 0.0 {
        return vec![Coord::default(); d.len()];
    }
    let at_worst = length(d[forces.worst]);
    let mut k = if at_worst > largest * 1e-9 {
        goal / at_worst
    } else {
        goal / largest
    };
    if largest * k > ratio * goal {
        k = ratio * goal / largest;
    }
    for v in &mut d {
        *v = *v * k;
    }
    d
}

/// Applies `step` so that the outline cannot fold and no centroid can leave it. Before the step,
/// each node is limited to a third of its clearance: a centroid's distance to the outline; an
/// outline vertex's distance to the segments it is not part of and its own segments' distance to
/// the nearest other node (so a long segment cannot sweep over a centroid or a vertex). Two
/// things that are `d` apart then close by at most 2d/3. Where rounding could still matter the
/// result is checked, and the step halved up to `HALVINGS` times while it is invalid. `index` is
/// the outline at `positions`; the result is the new positions with the outline there, or `None`
/// when no valid step was found.
fn apply_valid_step(
    network: &Network,
    positions: &[Coord<f64>],
    index: &RingIndex,
    mut step: Vec<Coord<f64>>,
) -> Option<(Vec<Coord<f64>>, RingIndex)> {
    let m = network.centroids;
    // Every node as a point tagged with its node index.
    let points = RTree::bulk_load(
        positions
            .iter()
            .enumerate()
            .map(|(n, c)| GeomWithData::new([c.x, c.y], n))
            .collect(),
    );
    // A node is limited only when its clearance is under three times its step, so clearances
    // are searched no farther than `REACH` steps: the same limits, found by box queries.
    let reach = |v: Coord<f64>| REACH * length(v);
    // Two nodes, or a node and a segment, close by at most two thirds of the clearance between
    // them, so the step can only make the outline cross itself or leave a centroid outside it
    // by rounding, where a clearance is under ROUNDING_CLEARANCE: only those segments and
    // centroids are tested (testing them all was a seventh of the run on us_counties).
    let (mut segments_at_risk, mut centroids_at_risk) = (Vec::new(), Vec::new());
    for (r, ring) in network.rings.iter().enumerate() {
        let len = ring.nodes.len();
        // Each segment's distance to the nearest node that is not one of its ends.
        let segment_clearance: Vec<f64> = (0..len)
            .map(|k| {
                let ends = [ring.nodes[k], ring.nodes[(k + 1) % len]];
                let most = reach(step[ends[0]]).max(reach(step[ends[1]]));
                segment_to_points(positions[ends[0]], positions[ends[1]], most, &points, |n| {
                    ends.contains(&n)
                })
            })
            .collect();
        for (k, &node) in ring.nodes.iter().enumerate() {
            let own = |s: &super::geometry::Segment| {
                s.ring == r && (s.index == k || (s.index + 1) % len == k)
            };
            let clearance = index
                .distance_within(positions[node], reach(step[node]), own)
                .min(segment_clearance[k])
                .min(segment_clearance[(k + len - 1) % len]);
            limit(&mut step[node], clearance / 3.0);
            if clearance < ROUNDING_CLEARANCE {
                segments_at_risk.extend([(r, (k + len - 1) % len), (r, k)]);
            }
        }
    }
    for (c, v) in step[..m].iter_mut().enumerate() {
        let clearance = index.distance_within(positions[c], reach(*v), |_| false);
        limit(v, clearance / 3.0);
        if clearance < ROUNDING_CLEARANCE {
            centroids_at_risk.push(c);
        }
    }
    for _ in 0..=HALVINGS {
        let moved: Vec<Coord<f64>> = positions.iter().zip(&step).map(|(p, v)| *p + *v).collect();
        let rings = network.ring_coords(&moved);
        let outline = RingIndex::new(&rings);
        let crossed = segments_at_risk.iter().any(|&(ring, index)| {
            let coords = &rings[ring];
            outline.meets_another(&Segment {
                a: coords[index],
                b: coords[(index + 1) % coords.len()],
                ring,
                index,
            })
        });
        if !crossed
            && centroids_at_risk
                .iter()
                .all(|&c| outline.contains(moved[c]))
        {
            return Some((moved, outline));
        }
        for v in &mut step {
            *v = *v * 0.5;
        }
    }
    None
}

fn limit(v: &mut Coord<f64>, most: f64) {
    let len = length(*v);
    if len > most {
        *v = *v * (most / len);
    }
}

/// Distance from the segment `a`–`b` to the nearest of `points` that `skip` does not reject,
/// or `reach` when none is nearer (see [`RingIndex::distance_within`]).
fn segment_to_points(
    a: Coord<f64>,
    b: Coord<f64>,
    reach: f64,
    points: &RTree<GeomWithData<[f64; 2], usize>>,
    skip: impl Fn(usize) -> bool,
) -> f64 {
    let around = AABB::from_corners(
        [a.x.min(b.x) - reach, a.y.min(b.y) - reach],
        [a.x.max(b.x) + reach, a.y.max(b.y) + reach],
    );
    (points.locate_in_envelope(&around))
        .filter(|p| !skip(p.data))
        .map(|p| {
            point_segment_distance2(
                Coord {
                    x: p.geom()[0],
                    y: p.geom()[1],
                },
                a,
                b,
            )
            .sqrt()
        })
        .fold(reach, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn beam_matrix_is_symmetric_and_a_rigid_shift_costs_nothing() {
        let k = beam_matrix(0.7, 1.3, 0.4);
        for (r, row) in k.iter().enumerate() {
            for (c, value) in row.iter().enumerate() {
                assert!((value - k[c][r]).abs() < 1e-12);
            }
        }
        // A rigid translation (d_a = d_b = 1, slopes 0) produces no force.
        for row in &k {
            assert!((row[0] + row[2]).abs() < 1e-12);
        }
    }

    #[test]
    fn the_step_rule_moves_the_worst_centroid_by_its_force_and_caps_the_rest() {
        let forces = Forces {
            vectors: vec![Coord { x: 0.1, y: 0.0 }, Coord { x: 0.0, y: 0.0 }],
            largest: 0.1,
            worst: 0,
        };
        let d = vec![Coord { x: 0.02, y: 0.0 }, Coord { x: 0.0, y: 0.5 }];
        let s = scale_step(d, &forces, 5.0);
        // Scaled by 5 to move the worst by 0.1 would move node 1 by 2.5 > 5·0.1: capped to 0.5.
        assert!((length(s[1]) - 0.5).abs() < 1e-12);
        assert!((length(s[0]) - 0.02).abs() < 1e-12);
    }

    #[test]
    fn a_step_never_folds_the_outline_or_carries_a_centroid_out() {
        // A unit square with one centroid; node 0 is the centroid, 1–4 the corners.
        let c = |x: f64, y: f64| Coord { x, y };
        let network = Network {
            nodes: vec![
                c(0.5, 0.5),
                c(0.0, 0.0),
                c(1.0, 0.0),
                c(1.0, 1.0),
                c(0.0, 1.0),
            ],
            centroids: 1,
            edges: vec![
                [0, 1],
                [0, 2],
                [0, 3],
                [0, 4],
                [1, 2],
                [1, 4],
                [2, 3],
                [3, 4],
            ],
            rings: vec![super::super::network::NetRing {
                nodes: vec![1, 2, 3, 4],
                part: 0,
                hole: false,
            }],
        };
        let positions = network.nodes.clone();
        let index = RingIndex::new(&network.ring_coords(&positions));
        // Asked to throw the centroid out through the right side and a corner across the
        // square: the limits keep both a third of their clearance short.
        for (centroid, corner) in [(c(2.0, 0.0), c(0.0, 0.0)), (c(0.0, 0.0), c(-3.0, 3.0))] {
            let step = vec![centroid, corner, c(0.0, 0.0), c(0.0, 0.0), c(0.0, 0.0)];
            let (moved, outline) =
                apply_valid_step(&network, &positions, &index, step).expect("a valid step");
            assert!(!outline.self_intersects(), "{moved:?}");
            assert!(outline.contains(moved[0]), "{moved:?}");
            // The centroid stood half a cell from every side.
            assert!(length(moved[0] - positions[0]) <= 0.5 / 3.0 + 1e-12);
        }
    }

    #[test]
    fn no_progress_needs_three_steps_without_a_fall() {
        assert!(!no_progress(&[1.0, 0.9, 0.8, 0.7]));
        assert!(no_progress(&[1.0, 0.5, 0.6, 0.55, 0.5]));
        assert!(!no_progress(&[0.5, 0.6, 0.7]));
    }
}
