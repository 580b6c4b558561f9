//! The method of method.md, one module per step, in the order the data flows:
//!
//! regions → [`frame`] (unit-cell frame) → [`outline`] (centroids, adjacency, outline) →
//! [`network`] (pruned constrained Delaunay network) → [`forces`] + [`snake`] (moved network) →
//! [`grid`] (lattice fitted to the moved outline) → [`assign`] (one-to-one assignment) →
//! [`refine`] (adjacency-aware local search) → [`metrics`] → [`candidates`] (several runs,
//! ranked by TOPSIS) → [`GridMap`].
//!
//! Everything here is planar and knows nothing of GDAL, the C API or QGIS.

#![forbid(unsafe_code)]

mod assign;
mod candidates;
pub mod crs;
pub mod diagnostics;
pub mod fields;
mod forces;
mod frame;
pub(crate) mod geometry;
mod grid;
mod groups;
pub mod hexjson;
pub mod input;
mod landmass;
mod metrics;
mod network;
mod outline;
mod overlay;
pub mod params;
pub mod pins;
mod rank;
mod refine;
mod score;
mod snake;
mod thin;
pub mod tiling;
mod validity;
mod watch;

use geo::{Coord, MultiPolygon, Polygon};
use serde::Serialize;
use std::fmt;

pub use params::{HexOrientation, LoadModel, Params, PARAMETERS};
pub use score::score;

/// One input region: a unique id, its (multi)polygon in a planar CRS and, optionally, the
/// group whose regions keep together (method.md §10).
#[derive(Clone, Debug)]
pub struct Region {
    pub id: String,
    pub geometry: MultiPolygon<f64>,
    /// Its group's name; `None` or a blank name: a group of its own. A layer where no region
    /// has a group (not even a blank one) is laid out without groups.
    pub group: Option<String>,
    /// The cell it must take (method.md §10, pinned cells): its offset column and row, as the
    /// grid layer numbers them (rows from the top; [`tiling::Tiling::offset_coordinates`]).
    /// The other cells are numbered in the same frame.
    pub pin: Option<(i32, i32)>,
}

/// Why a run failed. `InvalidInput` names the offending feature when there is one.
#[derive(Clone, Debug, PartialEq)]
pub enum Error {
    InvalidInput {
        feature: Option<String>,
        message: String,
    },
    InvalidParameter(String),
    /// Reading or writing a dataset failed (only the I/O layer makes these).
    Io(String),
    Cancelled,
    Internal(String),
}

impl Error {
    pub fn input(feature: Option<&str>, message: impl Into<String>) -> Self {
        Error::InvalidInput {
            feature: feature.map(str::to_owned),
            message: message.into(),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::InvalidInput {
                feature: Some(id),
                message,
            } => write!(f, "feature {id}: {message}"),
            Error::InvalidInput {
                feature: None,
                message,
            } => write!(f, "{message}"),
            Error::InvalidParameter(message) => write!(f, "{message}"),
            Error::Io(message) => write!(f, "{message}"),
            Error::Cancelled => write!(f, "cancelled"),
            Error::Internal(message) => write!(f, "internal error: {message}"),
        }
    }
}

impl std::error::Error for Error {}

/// A seed for the `k`-th draw of purpose `purpose`, so every random choice is reproducible and
/// independent of the thread that makes it.
fn derived_seed(base: u64, purpose: u64, k: usize) -> u64 {
    base ^ purpose.wrapping_mul(0xD1B5_4A32_D192_ED03)
        ^ (k as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

/// The items of a parallel check in input order, or the first error in input order, as a
/// sequential check would report it. rayon's own collect into a `Result` returns whichever error
/// a thread met first, so a layer with two bad features could name either from run to run.
pub(crate) fn first_error_in_order<T: Send>(
    results: impl rayon::iter::IndexedParallelIterator<Item = Result<T, Error>>,
) -> Result<Vec<T>, Error> {
    let results: Vec<Result<T, Error>> = results.collect();
    results.into_iter().collect()
}

/// Progress reporting: called with the fraction done (0..=1) and a short message; returning
/// `false` cancels the run, which then ends with [`Error::Cancelled`]. Called from worker
/// threads, hence `Sync`.
pub type Progress<'a> = &'a (dyn Fn(f64, &str) -> bool + Sync);

/// What a long step inside one layout (the assignment, the refinement) reports as it goes: the
/// share of its work done since the last call; returning `false` stops the step.
type Tick<'a> = &'a (dyn Fn(f64) -> bool + Sync);

/// Why the Snake stopped (method.md §5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// No node moved more than ε in the last step: the centroids are grid-like.
    Converged,
    /// The largest uncapped force did not fall for 3 steps (only when asked for).
    NoProgress,
    /// T_s steps were made.
    MaxSteps,
    /// A step stayed invalid after halving it 4 times; the last valid state was kept.
    InvalidStep,
    /// The Snake was switched off (T_s = 0) or had nothing to move.
    NotRun,
}

impl StopReason {
    pub fn as_str(self) -> &'static str {
        match self {
            StopReason::Converged => "converged",
            StopReason::NoProgress => "no_progress",
            StopReason::MaxSteps => "max_steps",
            StopReason::InvalidStep => "invalid_step",
            StopReason::NotRun => "not_run",
        }
    }
}

/// What the Snake did in one run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SnakeReport {
    pub steps: usize,
    pub stop_reason: StopReason,
    /// Coefficient of variation of the distances between neighbouring centroids, before.
    pub spread_before: f64,
    /// The same after the last step: the Snake exists to make it smaller.
    pub spread_after: f64,
    /// Network size, for the record.
    pub nodes: usize,
    pub edges: usize,
}

/// The layout metrics of method.md §8, as the shared judge computes them. `repr(C)`: the C API
/// hands it out as it is (snakegrid_layout_metrics).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct LayoutMetrics {
    /// C_location: mean distance from each region's area centroid to its cell's centre after
    /// the least-squares scale-and-translation fit, in fitted cells. Lower is better.
    pub location: f64,
    /// The 90th percentile of those distances, and the largest: the regions far from home.
    pub location_p90: f64,
    pub location_max: f64,
    /// The mean distance without the fit, in map units.
    pub location_raw: f64,
    /// The paper's variant: from the moved centroids, in cells of the map, without fit.
    pub location_moved: f64,
    /// C_adjacent: share of adjacent pairs whose cells are 8-neighbours. Higher is better.
    pub adjacent: f64,
    /// Share of adjacent pairs whose cells share an edge (4-neighbours).
    pub adjacent_rook: f64,
    /// Of the pairs of 8-neighbour cells, the share whose regions are not adjacent. Lower is
    /// better.
    pub false_neighbours: f64,
    /// C_orientation: mean directed angle error over adjacent pairs, degrees. Lower is better.
    pub orientation: f64,
    /// Share of adjacent pairs whose direction is off by more than 45°.
    pub misdirected: f64,
    /// C_shape: Fourier-descriptor similarity of the outlines. Higher is better.
    pub shape: f64,
    /// The area of the regions' own holes (lakes, missing regions), in fitted cells: holes of
    /// the layout up to this many are the source's.
    pub source_holes: f64,
    /// Among the regions of landmasses of 3+ regions, the share whose cell lies nearer another
    /// such landmass than its own.
    pub wrong_landmass: f64,
    /// Edge-connected pieces of the layout, and connected parts of the regions' union. (The
    /// counts come last, four 32-bit numbers, so that the C struct has no padding.)
    pub pieces: u32,
    pub source_pieces: u32,
    /// Empty cells enclosed by the layout (the area of its inner rings, in cells).
    pub holes: u32,
    /// Empty positions next to the layout with at most one free side (holes included).
    pub notches: u32,
}

impl LayoutMetrics {
    /// The regions' own holes in whole cells, slivers between regions included, as the judge
    /// counts them: what the summary reports beside the layout's holes.
    pub fn source_hole_cells(&self) -> u32 {
        self.source_holes.round() as u32
    }
}

/// How a layout keeps its groups (method.md §10), for a layer with groups. `repr(C)`: the C API
/// hands it out as it is (snakegrid_group_metrics).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct GroupMetrics {
    /// Share of the blocks (a group's regions on one landmass) whose cells form one
    /// edge-connected piece. Higher is better; 1 when every block holds together.
    pub whole: f64,
    /// Share of the pairs of adjacent groups (groups with adjacent regions) whose cells come
    /// within 1 + group_gap cells of each other: touching without a gap, one empty cell apart
    /// with one. Higher is better.
    pub adjacency: f64,
    /// Mean angle, degrees, between the direction from one adjacent group's regions to the
    /// other's (means of their area centroids) and the direction between their cells (means of
    /// the cell centres). Lower is better.
    pub orientation: f64,
    /// Groups (a region without a group is a group of its own) and blocks.
    pub groups: u32,
    pub blocks: u32,
    /// Pairs of touching cells (8-neighbours for squares, 6 for hexagons) of different groups:
    /// 0 when group_gap 1 holds everywhere.
    pub contacts: u32,
    /// Pairs of adjacent groups.
    pub group_pairs: u32,
    /// The reach `adjacency` counts, in cells: 1 + group_gap.
    pub reach: u32,
}

/// Per-region quality. `repr(C)`: the C API hands it out as it is (snakegrid_region_metrics).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct RegionMetrics {
    /// Distance from the region's centroid to its cell centre, in cells, after the fit.
    pub displacement: f64,
    /// Share of the region's adjacent regions whose cells are 8-neighbours of its cell
    /// (1 when it has no neighbours).
    pub neighbours_kept: f64,
    /// Mean angle error to its adjacent regions, degrees (0 when it has none).
    pub orientation_error: f64,
}

/// The cell of one region.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionCell {
    pub id: String,
    /// Column from the left (0 = leftmost used column); for hexagons, offset columns (see
    /// [`GridMap::shifted`]).
    pub col: i32,
    /// Row from the top (0 = topmost used row).
    pub row: i32,
    /// Axial coordinates of a hexagon, from the cell at column 0, row 0 (which may be unused):
    /// q along a row (pointy) or a column (flat), r down to the next row (column); every
    /// neighbour is (q ± 1, r), (q, r ± 1), (q + 1, r − 1) or (q − 1, r + 1). For squares the
    /// column and the row.
    pub q: i32,
    pub r: i32,
    /// Its block of cells (method.md §10): its group's on its landmass, or without groups its
    /// landmass's; numbered from 1 by the block's top row, then its leftmost column there.
    pub block: u32,
    /// The square or hexagon, in map units.
    pub cell: Polygon<f64>,
    /// The region's centroid (§1), map units.
    pub centroid: Coord<f64>,
    /// Where the Snake moved it, map units.
    pub moved_centroid: Coord<f64>,
    pub metrics: RegionMetrics,
    /// What was wrong with its polygon if it was invalid and repaired (by the even-odd rule,
    /// as GIS tools repair), as the note on it says; `None` for a valid polygon.
    pub repair: Option<String>,
}

/// One candidate layout (§7) and how it ranked.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CandidateReport {
    /// Noise level MD of its Snake run (0 for the noise-free run).
    pub noise: f64,
    /// Lattice origin shift, fractions of a cell (x right, y down).
    pub shift: [f64; 2],
    pub metrics: LayoutMetrics,
    /// TOPSIS closeness to the ideal (higher is better).
    pub score: f64,
    pub snake: SnakeReport,
}

/// The result of a run.
#[derive(Clone, Debug)]
pub struct GridMap {
    /// Squares or hexagons.
    pub tiling: tiling::Tiling,
    /// For hexagons, the parity (0 or 1) of the rows (pointy) or columns (flat) of
    /// [`RegionCell`]'s numbering that sit half a cell right (pointy) or down (flat); `None` for
    /// squares.
    pub shifted: Option<i32>,
    /// One cell per region, in the order of the input regions.
    pub cells: Vec<RegionCell>,
    /// Side of a cell in map units.
    pub cell_size: f64,
    /// Metrics of the chosen layout.
    pub metrics: LayoutMetrics,
    /// How it keeps the groups, for a layer with groups.
    pub groups: Option<GroupMetrics>,
    /// The chosen candidate's Snake run.
    pub snake: SnakeReport,
    /// All candidates, best first; the first is the chosen layout.
    pub candidates: Vec<CandidateReport>,
    /// The chosen candidate's moved outline, map units, without rings too small to draw (an
    /// islet far below a cell, which the Snake's network holds as a point).
    pub moved_outline: MultiPolygon<f64>,
    /// Adjacent region pairs, as indices into the input order (i < j).
    pub adjacency: Vec<(usize, usize)>,
    /// What the user should know about the input, e.g. "feature 06: invalid polygon repaired
    /// (...)".
    pub notes: Vec<String>,
}

/// How the cells of a [`GridMap`] are laid out, as the JSON report and the layer's metadata
/// name it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CellLayout {
    /// "square" or "hex".
    pub shape: &'static str,
    /// For hexagons, "pointy" or "flat".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub orientation: Option<&'static str>,
    /// For hexagons, which rows (pointy) or columns (flat) of `grid_col`/`grid_row` are offset
    /// half a cell, and where: e.g. "odd rows right" (rows from 0 at the top).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub offset: Option<String>,
}

impl GridMap {
    /// The layout of the cells (see [`CellLayout`]).
    pub fn cell_layout(&self) -> CellLayout {
        let parity = |p: i32| if p == 1 { "odd" } else { "even" };
        match (self.tiling, self.shifted) {
            (tiling::Tiling::Hex(orientation), Some(p)) => {
                let (name, offset) = match orientation {
                    HexOrientation::Pointy => ("pointy", format!("{} rows right", parity(p))),
                    HexOrientation::Flat => ("flat", format!("{} columns down", parity(p))),
                };
                CellLayout {
                    shape: "hex",
                    orientation: Some(name),
                    offset: Some(offset),
                }
            }
            _ => CellLayout {
                shape: "square",
                orientation: None,
                offset: None,
            },
        }
    }
}

/// Runs the whole method on `regions` (planar coordinates, unique ids) and returns the best
/// candidate layout. The result does not depend on the order of `regions`.
pub fn generate(regions: &[Region], params: &Params, progress: Progress) -> Result<GridMap, Error> {
    candidates::generate(regions, params, progress)
}

/// The wall time [`generate`] is expected to take on `regions`, in seconds on the two-core machine
/// the progress model was measured on: what a host weighs its own stages (reading, writing)
/// against, so that one progress bar follows the clock through all of them. An estimate from
/// the vertices, the regions and the parameters, for progress only.
pub fn expected_seconds(regions: &[Region], params: &Params) -> f64 {
    candidates::expected_seconds(regions, params)
}
