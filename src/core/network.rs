//! Step 1 (method.md §2): the network the Snake deforms. Its nodes are the region centroids and
//! the outline's vertices; its edges come from a constrained Delaunay triangulation pruned to a
//! relative-neighbourhood graph, plus every adjacent pair, plus links that keep islands and
//! lonely centroids attached.

use super::geometry::RingIndex;
use super::outline::{coords_of, Ring};
use super::Error;
use geo::Coord;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};
use std::collections::{BTreeSet, HashMap};

/// The network: nodes `0..centroids` are the region centroids (in region order), the rest the
/// outline vertices, ring after ring.
#[derive(Clone, Debug)]
pub struct Network {
    pub nodes: Vec<Coord<f64>>,
    pub centroids: usize,
    /// Undirected edges (a < b), sorted: oriented from the lower to the higher node index so the
    /// beam matrices do not depend on the triangulator (§4).
    pub edges: Vec<[usize; 2]>,
    /// The outline's rings as chains of node indices (closed implicitly).
    pub rings: Vec<NetRing>,
}

#[derive(Clone, Debug)]
pub struct NetRing {
    pub nodes: Vec<usize>,
    pub part: usize,
    pub hole: bool,
}

impl Network {
    /// The rings' coordinates at `positions` (one per node).
    pub fn ring_coords(&self, positions: &[Coord<f64>]) -> Vec<Vec<Coord<f64>>> {
        self.rings
            .iter()
            .map(|r| r.nodes.iter().map(|&n| positions[n]).collect())
            .collect()
    }

    /// The rings as outline rings (for rebuilding polygons at moved positions).
    pub fn outline_rings(&self, positions: &[Coord<f64>]) -> Vec<Ring> {
        self.rings
            .iter()
            .zip(self.ring_coords(positions))
            .map(|(r, coords)| Ring {
                coords,
                part: r.part,
                hole: r.hole,
            })
            .collect()
    }
}

/// Builds the network of `centroids` (one per region) inside the outline `rings`;
/// `adjacency` holds the adjacent region pairs.
pub fn build(
    centroids: &[Coord<f64>],
    rings: &[Ring],
    adjacency: &[(usize, usize)],
) -> Result<Network, Error> {
    let m = centroids.len();
    let mut nodes = centroids.to_vec();
    let mut net_rings = Vec::with_capacity(rings.len());
    let mut ring_edges = Vec::new();
    for ring in rings {
        let first = nodes.len();
        nodes.extend_from_slice(&ring.coords);
        let ids: Vec<usize> = (first..nodes.len()).collect();
        for (k, &a) in ids.iter().enumerate() {
            let b = ids[(k + 1) % ids.len()];
            ring_edges.push(ordered(a, b));
        }
        net_rings.push(NetRing {
            nodes: ids,
            part: ring.part,
            hole: ring.hole,
        });
    }

    // The triangulator merges coincident points (a centroid on an outline vertex, rings that
    // touch at a vertex): triangulate the distinct positions and map back to the first node at
    // each position.
    let mut vertex_of_position: HashMap<(u64, u64), usize> = HashMap::new();
    let mut node_vertex = Vec::with_capacity(nodes.len());
    let mut vertex_node = Vec::new();
    for (n, p) in nodes.iter().enumerate() {
        let key = (p.x.to_bits(), p.y.to_bits());
        let v = *vertex_of_position.entry(key).or_insert_with(|| {
            vertex_node.push(n);
            vertex_node.len() - 1
        });
        node_vertex.push(v);
    }
    let vertices: Vec<Point2<f64>> = vertex_node
        .iter()
        .map(|&n| Point2::new(nodes[n].x, nodes[n].y))
        .collect();
    let constraints: Vec<[usize; 2]> = ring_edges
        .iter()
        .map(|&[a, b]| [node_vertex[a], node_vertex[b]])
        .filter(|[a, b]| a != b)
        .collect();
    // Crossing constraints cannot occur on a valid outline; if rounding makes one, the edge is
    // still kept below as a ring edge, it just does not constrain the triangulation.
    let cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::try_bulk_load_cdt(
        vertices,
        constraints,
        |_| {},
    )
    .map_err(|e| Error::Internal(format!("triangulation failed: {e:?}")))?;
    if cdt.num_vertices() != vertex_node.len() {
        return Err(Error::Internal("the triangulation dropped vertices".into()));
    }
    let node = |v: spade::handles::FixedVertexHandle| vertex_node[v.index()];

    let adjacent: BTreeSet<[usize; 2]> = adjacency.iter().map(|&(i, j)| ordered(i, j)).collect();
    let ring_edge_set: BTreeSet<[usize; 2]> = ring_edges.iter().copied().collect();
    let index = RingIndex::new(&coords_of(rings));
    let mut inside_edges = BTreeSet::new();
    let mut pruned = BTreeSet::new();
    for face in cdt.inner_faces() {
        let [a, b, c] = face.vertices().map(|v| node(v.fix()));
        let centre = (nodes[a] + nodes[b] + nodes[c]) / 3.0;
        if !index.contains(centre) {
            continue;
        }
        let sides = [ordered(a, b), ordered(b, c), ordered(c, a)];
        let length = |[p, q]: [usize; 2]| {
            let d = nodes[p] - nodes[q];
            (d.x * d.x + d.y * d.y).sqrt()
        };
        let longest = sides.iter().map(|&s| length(s)).fold(0.0, f64::max);
        for side in sides {
            inside_edges.insert(side);
            // Relative-neighbourhood pruning: drop the longest side (ties included).
            if length(side) >= longest * (1.0 - 1e-12) {
                pruned.insert(side);
            }
        }
    }
    let mut edges: BTreeSet<[usize; 2]> = inside_edges
        .into_iter()
        .filter(|e| !pruned.contains(e) || adjacent.contains(e))
        .collect();
    edges.extend(ring_edge_set.iter().copied());
    edges.extend(adjacent.iter().copied());
    edges.retain(|[a, b]| a != b);

    // Join parts left apart (islands) by the shortest triangulation edges between them: Kruskal
    // over the full triangulation, starting from the components the network already has.
    let mut components = DisjointSets::new(nodes.len());
    for &[a, b] in &edges {
        components.union(a, b);
    }
    // Coincident nodes are one point of the triangulation: count them as joined.
    for n in 0..nodes.len() {
        components.union(n, vertex_node[node_vertex[n]]);
    }
    let mut all: Vec<(f64, [usize; 2])> = cdt
        .undirected_edges()
        .map(|e| {
            let [a, b] = e.vertices().map(|v| node(v.fix()));
            let d = nodes[a] - nodes[b];
            (d.x * d.x + d.y * d.y, ordered(a, b))
        })
        .collect();
    all.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    for (_, [a, b]) in all {
        if components.union(a, b) {
            edges.insert([a, b]);
        }
    }

    // Every centroid needs a centroid neighbour for its force (§2.5).
    let mut has_centroid_neighbour = vec![false; m];
    for &[a, b] in &edges {
        if a < m && b < m {
            has_centroid_neighbour[a] = true;
            has_centroid_neighbour[b] = true;
        }
    }
    for i in (0..m).filter(|&i| !has_centroid_neighbour[i]) {
        let nearest = (0..m).filter(|&j| j != i).min_by(|&j, &k| {
            let dj = nodes[j] - nodes[i];
            let dk = nodes[k] - nodes[i];
            (dj.x * dj.x + dj.y * dj.y)
                .total_cmp(&(dk.x * dk.x + dk.y * dk.y))
                .then(j.cmp(&k))
        });
        if let Some(j) = nearest {
            edges.insert(ordered(i, j));
        }
    }

    Ok(Network {
        nodes,
        centroids: m,
        edges: edges.into_iter().collect(),
        rings: net_rings,
    })
}

fn ordered(a: usize, b: usize) -> [usize; 2] {
    [a.min(b), a.max(b)]
}

/// Union-find: the component joining here, the outline's clusters and near parts.
pub(super) struct DisjointSets {
    parent: Vec<usize>,
}

impl DisjointSets {
    pub(super) fn new(n: usize) -> Self {
        DisjointSets {
            parent: (0..n).collect(),
        }
    }

    pub(super) fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] != x {
            self.parent[x] = self.parent[self.parent[x]];
            x = self.parent[x];
        }
        x
    }

    /// Joins the sets of `a` and `b`; true when they were apart.
    pub(super) fn union(&mut self, a: usize, b: usize) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        self.parent[ra.max(rb)] = ra.min(rb);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(coords: &[(f64, f64)], part: usize, hole: bool) -> Ring {
        Ring {
            coords: coords.iter().map(|&(x, y)| Coord { x, y }).collect(),
            part,
            hole,
        }
    }

    #[test]
    fn islands_are_joined_and_ring_edges_kept() {
        let rings = vec![
            ring(&[(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)], 0, false),
            ring(&[(5.0, 0.0), (6.0, 0.0), (6.0, 1.0), (5.0, 1.0)], 1, false),
        ];
        let centroids = [Coord { x: 1.0, y: 1.0 }, Coord { x: 5.5, y: 0.5 }];
        let net = build(&centroids, &rings, &[]).unwrap();
        assert_eq!(net.nodes.len(), 10);
        for r in &net.rings {
            for k in 0..r.nodes.len() {
                let e = ordered(r.nodes[k], r.nodes[(k + 1) % r.nodes.len()]);
                assert!(net.edges.contains(&e), "ring edge {e:?} kept");
            }
        }
        // One component.
        let mut sets = DisjointSets::new(net.nodes.len());
        for &[a, b] in &net.edges {
            sets.union(a, b);
        }
        assert!((0..net.nodes.len()).all(|n| sets.find(n) == sets.find(0)));
        // The two lonely centroids are joined to each other.
        assert!(net.edges.contains(&[0, 1]));
    }

    #[test]
    fn adjacent_pairs_become_beams() {
        let rings = vec![ring(
            &[(0.0, 0.0), (4.0, 0.0), (4.0, 1.0), (0.0, 1.0)],
            0,
            false,
        )];
        let centroids = [
            Coord { x: 0.5, y: 0.5 },
            Coord { x: 1.5, y: 0.5 },
            Coord { x: 2.5, y: 0.5 },
            Coord { x: 3.5, y: 0.5 },
        ];
        let net = build(&centroids, &rings, &[(0, 3)]).unwrap();
        assert!(net.edges.contains(&[0, 3]));
        assert!(net.edges.iter().all(|[a, b]| a < b));
    }
}
