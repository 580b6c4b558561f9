//! Step 2 (method.md §3): the forces that pull every centroid towards one cell's distance from
//! its neighbours, capped so no step is too large.

use super::network::Network;
use geo::Coord;

/// N(i) for every centroid: its centroid neighbours in the network together with its adjacent
/// regions, sorted and without repeats. Outline nodes do not count.
pub fn neighbours(network: &Network, adjacency: &[(usize, usize)]) -> Vec<Vec<usize>> {
    let m = network.centroids;
    let mut lists = vec![Vec::new(); m];
    let centroid_edges = network
        .edges
        .iter()
        .filter(|[a, b]| *a < m && *b < m)
        .map(|&[a, b]| (a, b));
    for (a, b) in centroid_edges.chain(adjacency.iter().copied()) {
        lists[a].push(b);
        lists[b].push(a);
    }
    for list in &mut lists {
        list.sort_unstable();
        list.dedup();
    }
    lists
}

/// The forces on the centroids at one step.
#[derive(Clone, Debug)]
pub struct Forces {
    /// Capped force per centroid.
    pub vectors: Vec<Coord<f64>>,
    /// The largest force before the cap: the worst centroid's distance from its target.
    pub largest: f64,
    /// The centroid with the largest force.
    pub worst: usize,
}

/// Forces at `positions` (centroids first) with unit spacing as the goal: each neighbour j
/// proposes the point one cell from j towards i; the force moves i to the mean proposal. When
/// the largest force exceeds `cap`, all are scaled so it equals `cap` (Eq. 7).
pub fn compute(positions: &[Coord<f64>], neighbours: &[Vec<usize>], cap: f64) -> Forces {
    let mut vectors: Vec<Coord<f64>> = neighbours
        .iter()
        .enumerate()
        .map(|(i, list)| {
            let p = positions[i];
            let proposals = list.iter().filter_map(|&j| {
                let d = p - positions[j];
                let len = (d.x * d.x + d.y * d.y).sqrt();
                (len > 0.0).then(|| positions[j] + d / len)
            });
            let (sum, count) = proposals.fold((Coord { x: 0.0, y: 0.0 }, 0usize), |(s, n), q| {
                (s + q, n + 1)
            });
            if count == 0 {
                Coord { x: 0.0, y: 0.0 }
            } else {
                sum / count as f64 - p
            }
        })
        .collect();
    let (worst, largest) = vectors
        .iter()
        .map(|f| (f.x * f.x + f.y * f.y).sqrt())
        .enumerate()
        .fold(
            (0, 0.0),
            |best, (i, len)| if len > best.1 { (i, len) } else { best },
        );
    if largest > cap {
        let k = cap / largest;
        for f in &mut vectors {
            *f = *f * k;
        }
    }
    Forces {
        vectors,
        largest,
        worst,
    }
}

/// Coefficient of variation of the distances between neighbouring centroids (each pair once):
/// the unevenness the Snake exists to reduce (§5).
pub fn spread(positions: &[Coord<f64>], neighbours: &[Vec<usize>]) -> f64 {
    let lengths: Vec<f64> = neighbours
        .iter()
        .enumerate()
        .flat_map(|(i, list)| list.iter().filter(move |&&j| j > i).map(move |&j| (i, j)))
        .map(|(i, j)| {
            let d = positions[i] - positions[j];
            (d.x * d.x + d.y * d.y).sqrt()
        })
        .collect();
    if lengths.is_empty() {
        return 0.0;
    }
    let n = lengths.len() as f64;
    let mean = lengths.iter().sum::<f64>() / n;
    let variance = lengths.iter().map(|l| (l - mean) * (l - mean)).sum::<f64>() / n;
    if mean > 0.0 {
        variance.sqrt() / mean
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pair_too_close_is_pushed_apart_to_one_cell() {
        let positions = [Coord { x: 0.0, y: 0.0 }, Coord { x: 0.4, y: 0.0 }];
        let neighbours = vec![vec![1], vec![0]];
        let f = compute(&positions, &neighbours, 10.0);
        assert!((f.vectors[0].x + 0.6).abs() < 1e-12);
        assert!((f.vectors[1].x - 0.6).abs() < 1e-12);
        assert!((f.largest - 0.6).abs() < 1e-12);
        let capped = compute(&positions, &neighbours, 0.1);
        assert!((capped.vectors[1].x - 0.1).abs() < 1e-12);
        assert!(
            (capped.largest - 0.6).abs() < 1e-12,
            "largest is reported uncapped"
        );
    }

    #[test]
    fn spread_is_zero_for_even_spacing() {
        let positions: Vec<Coord<f64>> = (0..4)
            .map(|i| Coord {
                x: i as f64,
                y: 0.0,
            })
            .collect();
        let neighbours = vec![vec![1], vec![0, 2], vec![1, 3], vec![2]];
        assert!(spread(&positions, &neighbours).abs() < 1e-12);
        let uneven = [
            positions[0],
            positions[1],
            Coord { x: 3.0, y: 0.0 },
            Coord { x: 3.5, y: 0.0 },
        ];
        assert!(spread(&uneven, &neighbours) > 0.3);
    }
}
