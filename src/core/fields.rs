//! The fields a grid layer adds after the source's, in order: their names (at most 10
//! characters, the Shapefile limit), types, meaning and values. The command line, the C API and
//! the QGIS plugin all write these, so a layer looks the same whichever made it.

use super::RegionCell;

/// One added field.
pub struct OutputField {
    pub name: &'static str,
    /// Whole numbers (written as an integer field), else reals.
    pub integer: bool,
    /// What it holds, for documentation and tooltips.
    pub description: &'static str,
    value: fn(&RegionCell) -> f64,
}

impl OutputField {
    /// Its value for `cell` (an integer field's value is a whole number).
    pub fn value(&self, cell: &RegionCell) -> f64 {
        (self.value)(cell)
    }
}

/// Every added field, in the order a layer has them.
pub static OUTPUT_FIELDS: &[OutputField] = &[
    OutputField {
        name: "grid_col",
        integer: true,
        description: "column of the region's cell, from the left (0 = the leftmost used column)",
        value: |c| f64::from(c.col),
    },
    OutputField {
        name: "grid_row",
        integer: true,
        description: "row of the region's cell, from the top (0 = the topmost used row)",
        value: |c| f64::from(c.row),
    },
    OutputField {
        name: "grid_q",
        integer: true,
        description: "axial q of the region's hexagon, from the cell at grid_col 0, grid_row 0: \
                      along a row (pointy) or a column (flat); for squares, grid_col",
        value: |c| f64::from(c.q),
    },
    OutputField {
        name: "grid_r",
        integer: true,
        description: "axial r of the region's hexagon: the next row (pointy) or column (flat) \
                      down, half a cell over, is r + 1; for squares, grid_row",
        value: |c| f64::from(c.r),
    },
    OutputField {
        name: "cell_disp",
        integer: false,
        description: "distance from the region's centroid to its cell's centre, in cells, after \
                      the scale-and-shift fit of method.md §8",
        value: |c| c.metrics.displacement,
    },
    OutputField {
        name: "nbr_kept",
        integer: false,
        description: "share of the region's neighbours whose cells are still its neighbours",
        value: |c| c.metrics.neighbours_kept,
    },
    OutputField {
        name: "orient_err",
        integer: false,
        description: "mean direction error towards the region's neighbours, degrees",
        value: |c| c.metrics.orientation_error,
    },
    // Last, so that the fields before keep their indices in the C API.
    OutputField {
        name: "grid_group",
        integer: true,
        description: "the region's block of cells, numbered from 1 by the block's top row, then \
                      its leftmost column: with -group, its group's cells on its landmass \
                      (method.md §10); without, its landmass's",
        value: |c| f64::from(c.block),
    },
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_fit_a_shapefile_and_are_distinct() {
        let mut names: Vec<&str> = OUTPUT_FIELDS.iter().map(|f| f.name).collect();
        assert!(names.iter().all(|n| n.len() <= 10 && n.is_ascii()));
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), OUTPUT_FIELDS.len());
    }
}
