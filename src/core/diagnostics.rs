//! The Snake's network of one layer, step by step: what the benchmarks time and what a picture
//! of the method shows. Making a grid map needs none of it ([`crate::generate`] does it all).

use super::candidates::Input;
use super::frame::Frame;
use super::network::{self, Network};
use super::{forces, outline, snake, Error, Params, Region, SnakeReport};
use geo::{Coord, MultiPolygon};

/// The noise-free network that [`crate::generate`] builds for a layer (method.md §1–2): the
/// regions' centroids and the simplified outline's vertices, joined by the pruned triangulation
/// and the adjacencies.
pub struct SnakeNetwork {
    network: Network,
    neighbours: Vec<Vec<usize>>,
    frame: Frame,
    /// `order[k]`: the input index of the network's `k`-th centroid.
    order: Vec<usize>,
}

/// The network after a Snake run, in map units.
pub struct MovedNetwork {
    /// How the run went: steps, why it stopped, the spread of neighbour distances.
    pub report: SnakeReport,
    /// The moved outline.
    pub outline: MultiPolygon<f64>,
    /// The moved centroids, in the order of the input regions.
    pub centroids: Vec<Coord<f64>>,
}

impl SnakeNetwork {
    /// The network of `regions` with `params`' outline settings.
    pub fn of(regions: &[Region], params: &Params) -> Result<SnakeNetwork, Error> {
        params.validate().map_err(Error::InvalidParameter)?;
        let input = Input::of(regions, params, &|_, _| true)?;
        let prepared = &input.prepared;
        let network = network::build(&prepared.centroids, &prepared.rings, &prepared.neighbours)?;
        let neighbours = forces::neighbours(&network, &prepared.neighbours);
        Ok(SnakeNetwork {
            network,
            neighbours,
            frame: input.frame,
            order: input.order,
        })
    }

    /// Nodes of the network: centroids and outline vertices.
    pub fn nodes(&self) -> usize {
        self.network.nodes.len()
    }

    /// Edges (beams) of the network.
    pub fn edges(&self) -> usize {
        self.network.edges.len()
    }

    /// Runs the Snake (method.md §3–5) with `params` — at most `params.max_steps` steps.
    pub fn run(&self, params: &Params) -> Result<MovedNetwork, Error> {
        params.validate().map_err(Error::InvalidParameter)?;
        let run = snake::run(&self.network, &self.neighbours, params, &|| true)?;
        let moved = outline::polygons_of(&self.network.outline_rings(&run.positions));
        let mut centroids = vec![Coord::default(); self.order.len()];
        for (k, &input) in self.order.iter().enumerate() {
            centroids[input] = self.frame.to_map(run.positions[k]);
        }
        Ok(MovedNetwork {
            report: run.report,
            outline: self.frame.polygons_to_map(&moved),
            centroids,
        })
    }
}
