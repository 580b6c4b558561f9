//! Re-layout after hand edits: the pins an edited grid layer gives ([`crate::pins::from_edits`]).

use super::handle::{self, OutArray};
use super::options::Options;
use super::regions::Regions;
use super::status::{guard, Failure, Status};
use crate::core::pins::{self, EditedCell};
use crate::tiling::Tiling;
use geo::{Area, Centroid};

/// The pin an edited cell gives its region (snakegrid_edit_pins). `repr(C)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CEditPin {
    /// Whether the region is pinned: the user moved its cell, or ticked it to keep.
    pub pinned: bool,
    /// Whether the user moved the cell (more than a quarter cell from its position).
    pub moved: bool,
    /// Where the cell now lies: pass to snakegrid_regions_set_pin when `pinned`.
    pub col: i32,
    pub row: i32,
}

/// Reads an edited grid layer for a re-layout: `cells` holds the layer's cells (one polygon
/// each, under its region's id, in any planar CRS), `q` and `r` each cell's grid_q and grid_r
/// as written (for squares, grid_col and grid_row), `keep` (NULL: none) whether the user ticked
/// it to keep, all `count` long in the order of `cells`; `options` gives the cell shape. A cell
/// whose centre lies more than a quarter cell from the position q, r name was moved: its new
/// position is the nearest one on the lattice that the unmoved cells lie on. Writes per cell
/// to `out[k]` whether it is pinned (moved or kept) and where: set those pins on the source
/// regions (snakegrid_regions_set_pin) and run again, and the rest is laid out around them.
/// For hexagons the columns and rows written are in snakegrid's pinned convention (odd rows or
/// columns shifted), which is the layer's own when it shifted the odd ones.
///
/// Fails with SNAKEGRID_INVALID_INPUT, naming both ids, when two cells lie on one position, and
/// naming the id for a cell that is not one polygon or has no area; SNAKEGRID_INVALID_ARGUMENT
/// when `count` is not the number of cells. `out` is written only on success. Thread safety:
/// the handles are only read.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_edit_pins(
    cells: *const Regions,
    q: *const i32,
    r: *const i32,
    keep: *const bool,
    count: usize,
    options: *const Options,
    out: *mut CEditPin,
) -> Status {
    guard("snakegrid_edit_pins", || {
        // SAFETY: live handles not modified meanwhile; `q`, `r`, `out` (and `keep` unless NULL)
        // valid for `count` elements (header contract).
        let (list, params, q, r, keep, out) = unsafe {
            (
                handle::get(cells, "cells")?,
                handle::get(options, "options")?,
                handle::slice(q, count, "q")?,
                handle::slice(r, count, "r")?,
                if keep.is_null() {
                    None
                } else {
                    Some(handle::slice(keep, count, "keep")?)
                },
                OutArray::new(out, count, "out")?,
            )
        };
        if list.len() != count {
            return Err(Failure::new(
                Status::INVALID_ARGUMENT,
                format!("count is {count} but there are {} cells", list.len()),
            ));
        }
        let edited = (list.iter().enumerate())
            .map(|(k, cell)| {
                let [polygon] = cell.geometry.0.as_slice() else {
                    return Err(crate::Error::input(
                        Some(&cell.id),
                        format!(
                            "a cell must be one polygon, got {} parts",
                            cell.geometry.0.len()
                        ),
                    ));
                };
                Ok(EditedCell {
                    id: cell.id.clone(),
                    position: (q[k], r[k]),
                    centre: polygon.centroid().map_or(
                        geo::Coord {
                            x: f64::NAN,
                            y: 0.0,
                        },
                        |p| p.0,
                    ),
                    area: polygon.unsigned_area(),
                    keep: keep.is_some_and(|keep| keep[k]),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let pins = pins::from_edits(&edited, Tiling::of(params))?;
        out.write(pins.into_iter().map(|pin| match pin {
            Some(p) => CEditPin {
                pinned: true,
                moved: p.moved,
                col: p.pin.0,
                row: p.pin.1,
            },
            None => CEditPin::default(),
        }));
        Ok(())
    })
}
