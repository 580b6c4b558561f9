//! Where the user finds a run's metrics and parameters: the JSON report (`-json FILE`), the
//! layer metadata of the output, and the printed summary.

use super::{Job, Outcome};
use crate::core::{
    CandidateReport, CellLayout, Error, GridMap, GroupMetrics, LayoutMetrics, Params, SnakeReport,
};
use geo::{BoundingRect, Coord};
use serde::Serialize;

/// The machine-readable report of one run. Field order is fixed and numbers print in their
/// shortest exact form, so the same run gives the same bytes.
#[derive(Serialize)]
struct Report<'a> {
    snakegrid: &'static str,
    gdal: String,
    source: SourceInfo<'a>,
    destination: DestinationInfo<'a>,
    crs: CrsInfo,
    notes: &'a [String],
    parameters: &'a Params,
    /// Side of a cell in working CRS units.
    cell_size: f64,
    /// Squares or hexagons, and for hexagons which rows or columns are offset.
    cells: CellLayout,
    adjacent_pairs: usize,
    metrics: &'a LayoutMetrics,
    /// How the layout keeps the groups (method.md §10); null without a group field.
    groups: Option<&'a GroupMetrics>,
    snake: &'a SnakeReport,
    /// Every candidate layout, best (the one written) first.
    candidates: &'a [CandidateReport],
    /// One row per region, in input order.
    regions: Vec<RegionRow<'a>>,
}

#[derive(Serialize)]
pub(crate) struct SourceInfo<'a> {
    pub dataset: &'a str,
    pub layer: &'a str,
    #[serde(rename = "where")]
    pub where_clause: Option<&'a str>,
    /// The id field, or null for the feature ids.
    pub id_field: Option<&'a str>,
    /// The group field (`-group`), or null.
    pub group_field: Option<&'a str>,
    /// The pin fields (`-pin_col`, `-pin_row`), or null.
    pub pin_col_field: Option<&'a str>,
    pub pin_row_field: Option<&'a str>,
    pub label_field: Option<&'a str>,
    pub features: usize,
}

#[derive(Serialize)]
struct DestinationInfo<'a> {
    dataset: &'a str,
    layer: &'a str,
    format: &'a str,
}

#[derive(Serialize)]
pub(crate) struct CrsInfo {
    /// The source layer's CRS (null when it has none).
    pub source: Option<String>,
    /// The CRS of the cells and of the output.
    pub working: Option<String>,
    /// The working CRS in full, as PROJJSON (WKT1 cannot express every CRS, e.g. Equal Earth).
    pub working_projjson: Option<serde_json::Value>,
    /// The regions were projected from the source CRS to the working CRS.
    pub projected: bool,
}

#[derive(Serialize)]
struct RegionRow<'a> {
    id: &'a str,
    label: &'a str,
    col: i32,
    row: i32,
    /// Its block (grid_group).
    block: u32,
    /// In cells, after the fit (method.md §8).
    displacement: f64,
    neighbours_kept: f64,
    /// Degrees.
    orientation_error: f64,
    centroid: [f64; 2],
    moved_centroid: [f64; 2],
    cell_centre: [f64; 2],
    /// What was wrong with its polygon if it was repaired, else null.
    repair: Option<&'a str>,
}

/// The JSON report of a finished run; `labels` are in input order.
pub(crate) fn json(
    job: &Job,
    params: &Params,
    outcome: &Outcome,
    source: SourceInfo,
    crs: CrsInfo,
    labels: &[String],
) -> Result<String, Error> {
    let map = &outcome.map;
    let report = Report {
        snakegrid: env!("CARGO_PKG_VERSION"),
        gdal: gdal::version::version_info("RELEASE_NAME"),
        source,
        destination: DestinationInfo {
            dataset: &job.dst,
            layer: &outcome.layer,
            format: &outcome.format,
        },
        crs,
        notes: &outcome.notes,
        parameters: params,
        cell_size: map.cell_size,
        cells: map.cell_layout(),
        adjacent_pairs: map.adjacency.len(),
        metrics: &map.metrics,
        groups: map.groups.as_ref(),
        snake: &map.snake,
        candidates: &map.candidates,
        regions: rows(map, labels),
    };
    serde_json::to_string_pretty(&report)
        .map(|text| text + "\n")
        .map_err(|e| Error::Internal(format!("cannot serialise the report: {e}")))
}

/// The per-region rows of `map`, labelled by `labels` (input order).
fn rows<'a>(map: &'a GridMap, labels: &'a [String]) -> Vec<RegionRow<'a>> {
    let xy = |c: Coord<f64>| [c.x, c.y];
    map.cells
        .iter()
        .zip(labels)
        .map(|(cell, label)| RegionRow {
            id: &cell.id,
            label,
            col: cell.col,
            row: cell.row,
            block: cell.block,
            displacement: cell.metrics.displacement,
            neighbours_kept: cell.metrics.neighbours_kept,
            orientation_error: cell.metrics.orientation_error,
            centroid: xy(cell.centroid),
            moved_centroid: xy(cell.moved_centroid),
            cell_centre: cell
                .cell
                .bounding_rect()
                .map(|r| xy(r.center()))
                .unwrap_or([f64::NAN; 2]),
            repair: cell.repair.as_deref(),
        })
        .collect()
}

/// Layer metadata items: the run's parameters and metrics, for formats that keep them
/// (GeoPackage stores them in gpkg_metadata; QGIS shows them in the layer's properties).
/// `id_field`: the field of this layer that holds the ids, which is not the source's name when
/// that collided with a computed field.
pub(crate) fn metadata(
    job: &Job,
    layer: &str,
    id_field: Option<&str>,
    params: &Params,
    map: &GridMap,
) -> Vec<(String, String)> {
    let mut items = vec![
        (
            "SNAKEGRID_VERSION".to_owned(),
            env!("CARGO_PKG_VERSION").to_owned(),
        ),
        ("SNAKEGRID_SOURCE".to_owned(), job.src.clone()),
        ("SNAKEGRID_SOURCE_LAYER".to_owned(), layer.to_owned()),
        (
            "SNAKEGRID_SOURCE_ID_FIELD".to_owned(),
            job.id_field.clone().unwrap_or_else(|| "FID".into()),
        ),
        (
            "SNAKEGRID_ID_FIELD".to_owned(),
            id_field.unwrap_or("FID").to_owned(),
        ),
    ];
    if let Some(expression) = &job.where_clause {
        items.push(("SNAKEGRID_WHERE".to_owned(), expression.clone()));
    }
    items.push(("SNAKEGRID_CELL_SIZE".to_owned(), map.cell_size.to_string()));
    let cells = map.cell_layout();
    items.push(("SNAKEGRID_CELL".to_owned(), cells.shape.to_owned()));
    if let (Some(orientation), Some(offset)) = (cells.orientation, cells.offset) {
        items.push((
            "SNAKEGRID_HEX_ORIENTATION".to_owned(),
            orientation.to_owned(),
        ));
        items.push(("SNAKEGRID_HEX_OFFSET".to_owned(), offset));
    }
    // Every metric by its own name, so new metrics appear without touching this list.
    if let Ok(serde_json::Value::Object(metrics)) = serde_json::to_value(map.metrics) {
        for (name, value) in metrics {
            items.push((
                format!("SNAKEGRID_METRIC_{}", name.to_ascii_uppercase()),
                value.to_string(),
            ));
        }
    }
    let snake = &map.snake;
    items.extend([
        ("SNAKEGRID_SNAKE_STEPS".to_owned(), snake.steps.to_string()),
        (
            "SNAKEGRID_SNAKE_STOP_REASON".to_owned(),
            snake.stop_reason.as_str().to_owned(),
        ),
        (
            "SNAKEGRID_SNAKE_SPREAD_BEFORE".to_owned(),
            snake.spread_before.to_string(),
        ),
        (
            "SNAKEGRID_SNAKE_SPREAD_AFTER".to_owned(),
            snake.spread_after.to_string(),
        ),
        (
            "SNAKEGRID_PARAMETERS".to_owned(),
            serde_json::to_string(params).unwrap_or_default(),
        ),
    ]);
    items
}

/// The one-line layer description (GeoPackage's gpkg_contents.description).
pub(crate) fn description(map: &GridMap) -> String {
    let m = &map.metrics;
    format!(
        "snakegrid {} grid map: C_adjacent {:.3}, C_orientation {:.1} deg, C_location {:.3} cells, C_shape {:.3}",
        env!("CARGO_PKG_VERSION"),
        m.adjacent,
        m.orientation,
        m.location,
        m.shape
    )
}

/// A few readable lines on what a run did: metrics, the Snake, the chosen candidate, notes.
pub fn summary(job: &Job, outcome: &Outcome) -> String {
    let map = &outcome.map;
    let m = &map.metrics;
    let s = &map.snake;
    let crs = outcome.crs.as_deref().unwrap_or("source units (no CRS)");
    let mut text = format!(
        "{} regions from layer {} → {} (layer {}, {}); cell size {} in {crs}\n",
        map.cells.len(),
        outcome.source_layer,
        job.dst,
        outcome.layer,
        outcome.format,
        in_map_units(map.cell_size),
    );
    let cells = map.cell_layout();
    if let (Some(orientation), Some(offset)) = (cells.orientation, cells.offset) {
        text +=
            &format!("cells: {orientation} hexagons of that area (grid_col/grid_row: {offset})\n");
    }
    text += &format!(
        "metrics: C_adjacent {:.3} (rook {:.3}, false neighbours {:.3}), C_orientation {:.1}° \
         (misdirected {:.3}), C_location {:.3} cells (p90 {:.2}, max {:.2}; unfitted {}, from \
         moved centroids {:.3}), C_shape {:.3}\n",
        m.adjacent,
        m.adjacent_rook,
        m.false_neighbours,
        m.orientation,
        m.misdirected,
        m.location,
        m.location_p90,
        m.location_max,
        in_map_units(m.location_raw),
        m.location_moved,
        m.shape
    );
    // §8 counts holes in enclosed positions, so a ring of regions round a lake has thousands:
    // the regions' holes' area, in the same cells, tells those the source has from defects
    // (slivers between regions included, as the judge counts them).
    let lakes = match m.source_hole_cells() {
        0 => String::new(),
        cells => format!(" (the regions' holes: {cells} cells)"),
    };
    text += &format!(
        "layout: {} piece(s) (the regions: {}), {} hole(s){lakes}, {} notch(es), wrong landmass \
         {:.3}\n",
        m.pieces, m.source_pieces, m.holes, m.notches, m.wrong_landmass
    );
    if let Some(g) = &map.groups {
        text += &format!(
            "groups: {} in {} block(s), {:.3} of the blocks whole, {:.3} of {} adjacent group \
             pairs within {} cell(s), orientation {:.1}°, {} contact(s) between groups\n",
            g.groups,
            g.blocks,
            g.whole,
            g.adjacency,
            g.group_pairs,
            g.reach,
            g.orientation,
            g.contacts
        );
    }
    text += &format!(
        "snake: {} steps, stopped by {}, spread of neighbour distances {:.3} → {:.3} \
         (network of {} nodes, {} edges)\n",
        s.steps,
        s.stop_reason.as_str(),
        s.spread_before,
        s.spread_after,
        s.nodes,
        s.edges
    );
    if let Some(best) = map.candidates.first() {
        text += &format!(
            "chosen: best of {} candidates by TOPSIS (score {:.3}; noise {}, shift {}:{})\n",
            map.candidates.len(),
            best.score,
            best.noise,
            best.shift[0],
            best.shift[1]
        );
    }
    for note in &outcome.notes {
        text += &format!("note: {note}\n");
    }
    text
}

/// A length in map units: to a tenth for the usual metres or feet, to four significant digits
/// below 100, so that a layer in small units (degrees scaled down, kilometres of a small
/// island) does not read as a cell size of 0.
fn in_map_units(value: f64) -> String {
    let magnitude = value.abs();
    let decimals = if magnitude >= 100.0 || magnitude == 0.0 || !magnitude.is_finite() {
        1
    } else {
        (3 - magnitude.log10().floor() as i32).clamp(1, 17) as usize
    };
    round_to(value, decimals)
}

/// `value` with at most `decimals` decimals, without trailing zeros.
fn round_to(value: f64, decimals: usize) -> String {
    let text = format!("{value:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_in_small_map_units_keep_four_significant_digits() {
        assert_eq!(in_map_units(398_317.94), "398317.9");
        assert_eq!(in_map_units(150.0), "150");
        assert_eq!(in_map_units(12.3456), "12.35");
        assert_eq!(in_map_units(0.000_398_317_9), "0.0003983");
        assert_eq!(in_map_units(0.0), "0");
    }
}
