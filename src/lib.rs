//! snakegrid turns a layer of regions into a grid map: one equal cell per region, placed so
//! that cells stay near their regions, neighbours stay neighbours, directions hold and the whole
//! keeps the outline of the map. It implements the snake-model method of Wei, Yang, Xu and Ding
//! (2024) as specified in `method.md`, with an adjacency- and shape-aware refinement on top.
//!
//! The Rust API is [`generate`] (regions in, a [`GridMap`] out), [`score`] (the metrics of any
//! layout) and the [`params`] table; everything is planar and in-memory. Beside it:
//! - [`io`] (feature `gdal`, on by default): reading and writing any vector layer through GDAL,
//!   as the command line and the C API's dataset job do;
//! - [`wkb`]: regions from and cells to WKB, as the C API exchanges them;
//! - [`diagnostics`]: the Snake's network step by step, for benchmarks and pictures;
//! - the C API (`include/snakegrid.h`), exported by the `cdylib`.
//!
//! `unsafe` code is confined to the C API and the GDAL layer; anywhere else it does not compile.
#![deny(unsafe_code)]

mod core;
#[allow(unsafe_code)]
mod ffi;
#[cfg(feature = "gdal")]
#[allow(unsafe_code)]
pub mod io;
pub mod job;
pub mod wkb;

pub use crate::core::{crs, diagnostics, fields, hexjson, input, params, pins, tiling};
pub use crate::core::{
    expected_seconds, generate, score, CandidateReport, CellLayout, Error, GridMap, GroupMetrics,
    HexOrientation, LayoutMetrics, LoadModel, Params, Progress, Region, RegionCell, RegionMetrics,
    SnakeReport, StopReason, PARAMETERS,
};
