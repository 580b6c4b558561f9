//! Scoring a layout made elsewhere (a hand-edited grid map, another tool's) against its regions
//! with the metrics of a run ([`crate::score`]), so that layouts compare on equal terms.

use super::handle::{self, Out, OutArray};
use super::regions::Regions;
use super::status::{guard, Failure, Status};
use crate::core::{Error, LayoutMetrics, Region, RegionMetrics};
use geo::Polygon;
use std::collections::HashMap;

/// Each region's cell, found by id among `cells`. A cell must be one polygon; a region without
/// a cell, a cell without a region and a repeated cell id are refused, naming the id, since
/// matching them up by position instead would score the wrong layout without a word.
fn cells_by_id(regions: &[Region], cells: &[Region]) -> Result<Vec<Polygon<f64>>, Error> {
    let mut by_id = HashMap::with_capacity(cells.len());
    for cell in cells {
        let square = match cell.geometry.0.as_slice() {
            [square] => square,
            parts => {
                return Err(Error::input(
                    Some(&cell.id),
                    format!("a cell must be one polygon, got {} parts", parts.len()),
                ))
            }
        };
        if by_id.insert(cell.id.as_str(), square).is_some() {
            return Err(Error::input(Some(&cell.id), "two cells have this id"));
        }
    }
    let matched = regions
        .iter()
        .map(|region| {
            by_id
                .remove(region.id.as_str())
                .cloned()
                .ok_or_else(|| Error::input(Some(&region.id), "the region has no cell"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    // Report the first extra cell in the caller's order, so the message does not depend on the
    // hash map's.
    match cells.iter().find(|c| by_id.contains_key(c.id.as_str())) {
        Some(extra) => Err(Error::input(Some(&extra.id), "the cell has no region")),
        None => Ok(matched),
    }
}

/// Scores an existing layout: `cells` holds one square per region under the region's id (the
/// grid layer of a run, perhaps edited by hand), in the CRS of `regions`. Writes the layout's
/// metrics to `*layout` and, when `region_metrics` is not NULL, region `i`'s metrics to
/// `region_metrics[i]` in the order of `regions`; `region_metrics_len` must then be the number
/// of regions. Columns and rows are recovered from the cell centres and the mean cell side.
///
/// Fails with SNAKEGRID_INVALID_INPUT, naming the id, for a region without a cell, a cell
/// without a region, a repeated cell id, a cell that is not one polygon or has no area, and for
/// regions snakegrid_run() would refuse; SNAKEGRID_INVALID_ARGUMENT for a `region_metrics_len`
/// that is not the number of regions. Thread safety: both handles are only read, so they may be
/// shared by several calls from any threads while no thread modifies or frees them.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_score(
    regions: *const Regions,
    cells: *const Regions,
    layout: *mut LayoutMetrics,
    region_metrics: *mut RegionMetrics,
    region_metrics_len: usize,
) -> Status {
    guard("snakegrid_score", || {
        // SAFETY: live handles not modified meanwhile, `layout` NULL or writable, and
        // `region_metrics` NULL or writable for `region_metrics_len` elements (header contract).
        let (list, cell_list, layout, per_region) = unsafe {
            (
                handle::get(regions, "regions")?,
                handle::get(cells, "cells")?,
                Out::new(layout, "layout")?,
                if region_metrics.is_null() {
                    None
                } else {
                    Some(OutArray::new(
                        region_metrics,
                        region_metrics_len,
                        "region_metrics",
                    )?)
                },
            )
        };
        if let Some(array) = &per_region {
            if array.len() != list.len() {
                return Err(Failure::new(
                    Status::INVALID_ARGUMENT,
                    format!(
                        "region_metrics_len is {} but there are {} regions",
                        array.len(),
                        list.len()
                    ),
                ));
            }
        }
        let squares = cells_by_id(list, cell_list)?;
        let (metrics, per) = crate::score(list, &squares)?;
        layout.write(metrics);
        if let Some(array) = per_region {
            array.write(per.iter().copied());
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use geo::{polygon, MultiPolygon};

    fn region(id: &str, x: f64) -> Region {
        Region {
            id: id.to_owned(),
            geometry: MultiPolygon(vec![
                polygon![(x: x, y: 0.0), (x: x + 1.0, y: 0.0), (x: x + 1.0, y: 1.0), (x: x, y: 1.0)],
            ]),
            group: None,
            pin: None,
        }
    }

    #[test]
    fn cells_are_matched_by_id_whatever_their_order() {
        let regions = [region("a", 0.0), region("b", 1.0)];
        let cells = [region("b", 11.0), region("a", 10.0)];
        let matched = cells_by_id(&regions, &cells).unwrap();
        assert_eq!(matched[0], cells[1].geometry.0[0]);
        assert_eq!(matched[1], cells[0].geometry.0[0]);
    }

    #[test]
    fn missing_extra_and_repeated_cells_are_named() {
        let regions = [region("a", 0.0), region("b", 1.0)];
        let message = |cells: &[Region]| cells_by_id(&regions, cells).unwrap_err().to_string();
        assert_eq!(
            message(&[region("a", 0.0)]),
            "feature b: the region has no cell"
        );
        assert_eq!(
            message(&[region("a", 0.0), region("b", 1.0), region("c", 2.0)]),
            "feature c: the cell has no region"
        );
        assert_eq!(
            message(&[region("a", 0.0), region("a", 1.0)]),
            "feature a: two cells have this id"
        );
    }
}
