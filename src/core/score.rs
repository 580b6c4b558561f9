//! Scoring a layout the method did not make (a hand-edited grid map, another tool's output) with
//! the metrics of method.md §8, so layouts can be compared on equal terms.

use super::candidates::Input;
use super::metrics::{self, Scored};
use super::{Error, LayoutMetrics, Params, Region, RegionMetrics};
use geo::{Area, Centroid, Polygon};

/// Scores `cells` (one square per region, `cells[i]` belonging to `regions[i]`, same planar CRS)
/// against the regions. Columns and rows are recovered from the cell centres and the mean cell
/// side. Per-region metrics come back in the input order.
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
    let left = centres.iter().map(|c| c.x).fold(f64::INFINITY, f64::min);
    let top = centres
        .iter()
        .map(|c| c.y)
        .fold(f64::NEG_INFINITY, f64::max);
    let col_rows: Vec<(i32, i32)> = centres
        .iter()
        .map(|c| {
            (
                ((c.x - left) / side).round() as i32,
                ((top - c.y) / side).round() as i32,
            )
        })
        .collect();
    let reference = metrics::Reference::new(&input.prepared, input.frame);
    let (layout, sorted_metrics) = metrics::evaluate(&Scored {
        reference: &reference,
        // No Snake ran: the paper's variant measures from the centroids themselves.
        moved: &reference.centroids,
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
