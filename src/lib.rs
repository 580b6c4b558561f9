//! snakegrid turns a layer of regions into a grid map: one equal square cell per region, placed
//! so that cells stay near their regions, neighbours stay neighbours, directions hold and the
//! whole keeps the outline of the map. It implements the snake-model method of Wei, Yang, Xu and
//! Ding (2024) as specified in `method.md`, with an adjacency-aware refinement on top.
//!
//! - [`core`]: the method, planar and free of I/O ([`generate`] is the entry point);
//! - [`io`]: reading and writing any vector layer through GDAL;
//! - `ffi`: the stable C API (see `include/snakegrid.h`).

pub mod core;
pub mod ffi;
pub mod io;
pub mod wkb;

pub use crate::core::params;

pub use crate::core::{
    generate, score, CandidateReport, Error, GridMap, LayoutMetrics, LoadModel, Params, Progress,
    Region, RegionCell, RegionMetrics, SnakeReport, StopReason, PARAMETERS,
};
