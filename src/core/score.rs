//! Scoring a layout the method did not make (a hand-edited grid map, another tool's output) with
//! the metrics of method.md §8, so layouts can be compared on equal terms.

use super::candidates::Input;
use super::metrics::{self, Scored};
use super::params::HexOrientation;
use super::tiling::Tiling;
use super::{Error, LayoutMetrics, Params, Region, RegionMetrics};
use geo::{Area, Centroid, Coord, Polygon};

/// Scores `cells` (one square or hexagon per region, `cells[i]` belonging to `regions[i]`, same
/// planar CRS) against the regions. The tiling is told by the cells' corners (see
/// [`tiling_of`]); positions are recovered from the cell centres and the median cell area.
/// Per-region metrics come back in the input order.
pub fn score(
    regions: &[Region],
    cells: &[Polygon<f64>],
) -> Result<(LayoutMetrics, Vec<RegionMetrics>), Error> {
    if cells.len() != regions.len() {
        return Err(Error::input(
            None,
            format!("{} cells for {} regions", cells.len(), regions.len()),
        ));
    }
    let input = Input::of(regions, &Params::default(), &|_, _| true)?;
    let mut centres = Vec::with_capacity(cells.len());
    for &i in &input.order {
        let centre = cells[i]
            .centroid()
            .filter(|_| cells[i].unsigned_area() > 0.0)
            .ok_or_else(|| Error::input(Some(&regions[i].id), "the cell has no area"))?;
        centres.push(centre.0);
    }
    // The cell side as the judge takes it: the square root of the median cell area.
    let mut areas: Vec<f64> = cells.iter().map(|c| c.unsigned_area()).collect();
    areas.sort_by(f64::total_cmp);
    let middle = areas.len() / 2;
    let median = if areas.len().is_multiple_of(2) {
        (areas[middle - 1] + areas[middle]) / 2.0
    } else {
        areas[middle]
    };
    let side = median.sqrt();
    let tiling = tiling_of(&cells[input.order[0]]);
    let first = centres[0];
    let col_rows: Vec<(i32, i32)> = centres
        .iter()
        .map(|&c| tiling.position_at((c - first) / side))
        .collect();
    let reference = metrics::Reference::new(&input.prepared, input.frame);
    let (layout, sorted_metrics) = metrics::evaluate(&Scored {
        reference: &reference,
        // No Snake ran: the paper's variant measures from the centroids themselves.
        moved: &reference.centroids,
        tiling,
        cells: &col_rows,
        centres: &centres,
        cell_size: side,
    });
    let mut per_region = vec![RegionMetrics::default(); regions.len()];
    for (k, &i) in input.order.iter().enumerate() {
        per_region[i] = sorted_metrics[k];
    }
    Ok((layout, per_region))
}

/// The tiling a cell belongs to: a hexagon has six corners, pointy when one of them is its
/// highest point alone, flat when its top is an edge; anything else is taken as a square.
fn tiling_of(cell: &Polygon<f64>) -> Tiling {
    let mut corners: Vec<Coord<f64>> = cell.exterior().0.clone();
    corners.dedup();
    if corners.len() > 1 && corners.first() == corners.last() {
        corners.pop();
    }
    if corners.len() != 6 {
        return Tiling::Square;
    }
    let top = corners
        .iter()
        .map(|c| c.y)
        .fold(f64::NEG_INFINITY, f64::max);
    let bottom = corners.iter().map(|c| c.y).fold(f64::INFINITY, f64::min);
    let near_top = (corners.iter())
        .filter(|c| top - c.y < 1e-6 * (top - bottom))
        .count();
    Tiling::Hex(if near_top == 1 {
        HexOrientation::Pointy
    } else {
        HexOrientation::Flat
    })
}
