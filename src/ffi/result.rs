//! Reading a finished run: per-region cells and metrics, the layout's metrics, the Snake's
//! report and the ranked candidates. Everything is computed when the run ends, so the accessors
//! only read and may be called from several threads at once.

use super::handle::{self, Handle, Out};
use super::status::{c_string, guard, guard_free, Failure, Status};
use crate::core::{
    hexjson, CandidateReport, GridMap, GroupMetrics, LayoutMetrics, RegionCell, RegionMetrics,
    SnakeReport, StopReason,
};
use std::ffi::{c_char, CString};

/// The outcome of a successful run. Made by snakegrid_run() or snakegrid_run_job(), freed by
/// snakegrid_result_free(). Strings and WKB buffers read from it belong to it and stay valid
/// until it is freed.
pub struct RunResult {
    _opaque: [u8; 0],
}

/// What a result handle holds: the grid map and its C views, made once.
pub(crate) struct Output {
    map: GridMap,
    ids: Vec<CString>,
    /// Per region, what was wrong with its polygon if it was repaired.
    repairs: Vec<Option<CString>>,
    cells_wkb: Vec<Vec<u8>>,
    moved_outline_wkb: Vec<u8>,
    notes: Vec<CString>,
    /// The HexJSON of a hexagon layout, each hexagon labelled with its id.
    hexjson: Option<CString>,
}

impl Output {
    /// The cell of region `index`.
    pub(crate) fn cell(&self, index: usize) -> Result<&RegionCell, Failure> {
        at(&self.map.cells, index, "regions")
    }

    pub(crate) fn new(map: GridMap, notes: &[String]) -> Output {
        Output {
            ids: map.cells.iter().map(|c| c_string(&c.id)).collect(),
            repairs: (map.cells.iter())
                .map(|c| c.repair.as_deref().map(c_string))
                .collect(),
            cells_wkb: map
                .cells
                .iter()
                .map(|c| crate::wkb::from_polygon(&c.cell))
                .collect(),
            moved_outline_wkb: crate::wkb::from_multi_polygon(&map.moved_outline),
            notes: notes.iter().map(|n| c_string(n)).collect(),
            hexjson: {
                let ids: Vec<String> = map.cells.iter().map(|c| c.id.clone()).collect();
                hexjson::of_map(&map, &ids, Vec::new()).map(|text| c_string(&text))
            },
            map,
        }
    }
}

impl Handle for RunResult {
    type Inner = Output;
    const TAG: u64 = u64::from_be_bytes(*b"sgRESULT");
    const NAME: &'static str = "snakegrid_result";
}

/// Why the Snake stopped (method.md section 5).
/// cbindgen:rename-all=prefix:SNAKEGRID_STOP_
#[allow(non_camel_case_types, clippy::upper_case_acronyms)]
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SnakeStop {
    /// No node moved more than epsilon in the last step: the centroids are grid-like.
    CONVERGED = 0,
    /// The largest uncapped force did not fall for 3 steps (only when asked for).
    NO_PROGRESS = 1,
    /// The step limit (option max_steps) was reached.
    MAX_STEPS = 2,
    /// A step stayed invalid after halving it 4 times; the last valid state was kept.
    INVALID_STEP = 3,
    /// The Snake was switched off (max_steps = 0) or had nothing to move.
    NOT_RUN = 4,
}

impl From<StopReason> for SnakeStop {
    fn from(reason: StopReason) -> Self {
        match reason {
            StopReason::Converged => SnakeStop::CONVERGED,
            StopReason::NoProgress => SnakeStop::NO_PROGRESS,
            StopReason::MaxSteps => SnakeStop::MAX_STEPS,
            StopReason::InvalidStep => SnakeStop::INVALID_STEP,
            StopReason::NotRun => SnakeStop::NOT_RUN,
        }
    }
}

/// What the Snake did in one run.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CSnakeReport {
    /// Steps made.
    pub steps: usize,
    /// Why it stopped.
    pub stop_reason: SnakeStop,
    /// Coefficient of variation of the distances between neighbouring centroids, before.
    pub spread_before: f64,
    /// The same after the last step: the Snake exists to make it smaller.
    pub spread_after: f64,
    /// Nodes of the network.
    pub nodes: usize,
    /// Edges of the network.
    pub edges: usize,
}

impl From<&SnakeReport> for CSnakeReport {
    fn from(s: &SnakeReport) -> Self {
        CSnakeReport {
            steps: s.steps,
            stop_reason: s.stop_reason.into(),
            spread_before: s.spread_before,
            spread_after: s.spread_after,
            nodes: s.nodes,
            edges: s.edges,
        }
    }
}

/// One candidate layout (method.md section 7) and how it ranked.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CCandidate {
    /// Noise level MD of its Snake run (0 for the noise-free run).
    pub noise: f64,
    /// Lattice origin shift to the right, in cells.
    pub shift_x: f64,
    /// Lattice origin shift downwards, in cells.
    pub shift_y: f64,
    /// TOPSIS closeness to the ideal (higher is better).
    pub score: f64,
    /// Its layout metrics.
    pub metrics: LayoutMetrics,
    /// Its Snake run.
    pub snake: CSnakeReport,
}

impl From<&CandidateReport> for CCandidate {
    fn from(c: &CandidateReport) -> Self {
        CCandidate {
            noise: c.noise,
            shift_x: c.shift[0],
            shift_y: c.shift[1],
            score: c.score,
            metrics: c.metrics,
            snake: (&c.snake).into(),
        }
    }
}

/// Frees a result handle and everything read from it. NULL is ignored.
///
/// Thread safety: not concurrently with any other use of the same handle.
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_free(result: *mut RunResult) {
    // SAFETY: `result` is NULL or a handle not used elsewhere meanwhile (header contract).
    guard_free("snakegrid_result_free", || unsafe {
        handle::free(result, "result")
    })
}

/// Reads the result and writes one value computed from it to `*out`: the body shared by every
/// accessor below.
///
/// # Safety
/// `result` NULL or a live result handle not being freed meanwhile; `out` NULL or writable.
pub(crate) unsafe fn read<T>(
    function: &str,
    result: *const RunResult,
    out: *mut T,
    value: impl FnOnce(&Output) -> Result<T, Failure>,
) -> Status {
    guard(function, || {
        // SAFETY: the caller's guarantees.
        let output = unsafe { handle::get(result, "result") }?;
        // SAFETY: the caller's guarantees.
        let out = unsafe { Out::new(out, "out") }?;
        out.write(value(output)?);
        Ok(())
    })
}

/// `items[index]`, or SNAKEGRID_INVALID_ARGUMENT naming the range.
fn at<'a, T>(items: &'a [T], index: usize, what: &str) -> Result<&'a T, Failure> {
    items.get(index).ok_or_else(|| {
        Failure::new(
            Status::INVALID_ARGUMENT,
            format!(
                "index {index} is out of range: the result has {} {what}",
                items.len()
            ),
        )
    })
}

/// The number of regions, each with one cell; regions are numbered 0..count-1 in the order
/// they were given (added to the regions handle, or read from the source layer).
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_count(
    result: *const RunResult,
    out: *mut usize,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        read("snakegrid_result_count", result, out, |o| {
            Ok(o.map.cells.len())
        })
    }
}

/// The side of a cell, in map units.
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_cell_size(
    result: *const RunResult,
    out: *mut f64,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        read("snakegrid_result_cell_size", result, out, |o| {
            Ok(o.map.cell_size)
        })
    }
}

/// The id of region `index`, as given. The string belongs to the result.
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_region_id(
    result: *const RunResult,
    index: usize,
    out: *mut *const c_char,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        read("snakegrid_result_region_id", result, out, |o| {
            Ok(at(&o.ids, index, "regions")?.as_ptr())
        })
    }
}

/// What was wrong with region `index`'s polygon if it was invalid and repaired (by the
/// even-odd rule), e.g. "a ring intersects itself at (3.5, 2)"; NULL for a valid polygon.
/// The notes name the first repairs and count the rest; this names each. The string belongs
/// to the result.
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_region_repair(
    result: *const RunResult,
    index: usize,
    out: *mut *const c_char,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        read("snakegrid_result_region_repair", result, out, |o| {
            let repair = at(&o.repairs, index, "regions")?;
            Ok(repair.as_ref().map_or(std::ptr::null(), |r| r.as_ptr()))
        })
    }
}

/// The cell of region `index`: column from the left and row from the top, both from 0 at the
/// leftmost and topmost used cells.
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_cell(
    result: *const RunResult,
    index: usize,
    col: *mut i32,
    row: *mut i32,
) -> Status {
    guard("snakegrid_result_cell", || {
        // SAFETY: a live result handle (header contract).
        let output = unsafe { handle::get(result, "result") }?;
        // SAFETY: NULL or writable (header contract).
        let (col, row) = unsafe { (Out::new(col, "col")?, Out::new(row, "row")?) };
        let cell = at(&output.map.cells, index, "regions")?;
        col.write(cell.col);
        row.write(cell.row);
        Ok(())
    })
}

/// The square cell of region `index` as little-endian 2D WKB (a Polygon) in map units:
/// `*wkb` points to `*wkb_len` bytes that belong to the result.
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_cell_wkb(
    result: *const RunResult,
    index: usize,
    wkb: *mut *const u8,
    wkb_len: *mut usize,
) -> Status {
    guard("snakegrid_result_cell_wkb", || {
        // SAFETY: a live result handle (header contract).
        let output = unsafe { handle::get(result, "result") }?;
        // SAFETY: NULL or writable (header contract).
        let (wkb, wkb_len) = unsafe { (Out::new(wkb, "wkb")?, Out::new(wkb_len, "wkb_len")?) };
        let bytes = at(&output.cells_wkb, index, "regions")?;
        wkb.write(bytes.as_ptr());
        wkb_len.write(bytes.len());
        Ok(())
    })
}

/// The map's outline after the Snake moved it (method.md section 6, the shape the lattice was
/// fitted to), as little-endian 2D WKB (a MultiPolygon) in map units: `*wkb` points to
/// `*wkb_len` bytes that belong to the result.
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_moved_outline_wkb(
    result: *const RunResult,
    wkb: *mut *const u8,
    wkb_len: *mut usize,
) -> Status {
    guard("snakegrid_result_moved_outline_wkb", || {
        // SAFETY: a live result handle (header contract).
        let output = unsafe { handle::get(result, "result") }?;
        // SAFETY: NULL or writable (header contract).
        let (wkb, wkb_len) = unsafe { (Out::new(wkb, "wkb")?, Out::new(wkb_len, "wkb_len")?) };
        wkb.write(output.moved_outline_wkb.as_ptr());
        wkb_len.write(output.moved_outline_wkb.len());
        Ok(())
    })
}

/// How well region `index` is placed.
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_region_metrics(
    result: *const RunResult,
    index: usize,
    out: *mut RegionMetrics,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        read("snakegrid_result_region_metrics", result, out, |o| {
            Ok(at(&o.map.cells, index, "regions")?.metrics)
        })
    }
}

/// The metrics of the chosen layout.
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_layout_metrics(
    result: *const RunResult,
    out: *mut LayoutMetrics,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        read("snakegrid_result_layout_metrics", result, out, |o| {
            Ok(o.map.metrics)
        })
    }
}

/// How the chosen layout keeps its groups (method.md §10): the regions were given groups
/// (snakegrid_regions_set_group, or the dataset job's group_field).
///
/// Fails with SNAKEGRID_INVALID_ARGUMENT for a map laid out without groups.
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_group_metrics(
    result: *const RunResult,
    out: *mut GroupMetrics,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        read("snakegrid_result_group_metrics", result, out, |o| {
            o.map.groups.ok_or_else(|| {
                Failure::new(
                    Status::INVALID_ARGUMENT,
                    "the map was laid out without groups (no region has a group)",
                )
            })
        })
    }
}

/// What the Snake did in the chosen layout's run.
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_snake_report(
    result: *const RunResult,
    out: *mut CSnakeReport,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        read("snakegrid_result_snake_report", result, out, |o| {
            Ok((&o.map.snake).into())
        })
    }
}

/// The number of candidate layouts that were ranked (at least 1).
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_candidate_count(
    result: *const RunResult,
    out: *mut usize,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        read("snakegrid_result_candidate_count", result, out, |o| {
            Ok(o.map.candidates.len())
        })
    }
}

/// Candidate `index`, best first: candidate 0 is the chosen layout.
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_candidate(
    result: *const RunResult,
    index: usize,
    out: *mut CCandidate,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        read("snakegrid_result_candidate", result, out, |o| {
            Ok(at(&o.map.candidates, index, "candidates")?.into())
        })
    }
}

/// The number of notes the run left for the user: the input's (e.g. that an invalid polygon was
/// repaired, from either entry point) and, for snakegrid_run_job(), the dataset's (e.g. that a
/// geographic source was projected).
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_note_count(
    result: *const RunResult,
    out: *mut usize,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        read("snakegrid_result_note_count", result, out, |o| {
            Ok(o.notes.len())
        })
    }
}

/// Note `index`, a sentence. The string belongs to the result.
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_note(
    result: *const RunResult,
    index: usize,
    out: *mut *const c_char,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        read("snakegrid_result_note", result, out, |o| {
            Ok(at(&o.notes, index, "notes")?.as_ptr())
        })
    }
}

/// The layout as HexJSON (Open Innovations' hexagon map format, as d3-hexjson renders it):
/// `{"layout": "odd-r" | "even-r" | "odd-q" | "even-q", "hexes": {id: {"q", "r", "n"}}}`, q the
/// column, r counted from the bottom, n the region's id. The string belongs to the result.
///
/// Fails with SNAKEGRID_INVALID_ARGUMENT for a layout of squares (run with the option cell set to
/// hex).
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_hexjson(
    result: *const RunResult,
    out: *mut *const c_char,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        read("snakegrid_result_hexjson", result, out, |o| {
            (o.hexjson.as_ref())
                .map(|text| text.as_ptr())
                .ok_or_else(|| Failure::new(Status::INVALID_ARGUMENT, hexjson::NEEDS_HEXAGONS))
        })
    }
}
