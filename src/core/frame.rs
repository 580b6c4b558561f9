//! The unit-cell frame of method.md §0: coordinates translated to the centre of the layer and
//! divided by the cell size S = sqrt(total area / M), so every length parameter is a fraction of
//! a cell whatever the map units are.

use geo::{Area, BoundingRect, Coord, MapCoords, MultiPolygon};
use rayon::prelude::*;

/// An affine map between map units and cells: `unit = (map − origin) / scale`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Map coordinates of the frame's origin (the centre of the layer's bounding box).
    pub origin: Coord<f64>,
    /// S, the side of a cell in map units.
    pub scale: f64,
}

impl Frame {
    /// The frame of `regions`. `None` when they have no area.
    pub fn of(regions: &[&MultiPolygon<f64>]) -> Option<Frame> {
        // Each region's area on any core, summed in order: the sum's rounding does not depend
        // on the threads.
        let areas: Vec<f64> = regions.par_iter().map(|r| r.unsigned_area()).collect();
        let area: f64 = areas.iter().sum();
        let scale = (area / regions.len() as f64).sqrt();
        let bounds = super::geometry::bounds(regions.iter().filter_map(|r| r.bounding_rect()))?;
        (scale.is_finite() && scale > 0.0).then(|| Frame {
            origin: bounds.center(),
            scale,
        })
    }

    pub fn to_unit(self, c: Coord<f64>) -> Coord<f64> {
        (c - self.origin) / self.scale
    }

    pub fn to_map(self, c: Coord<f64>) -> Coord<f64> {
        c * self.scale + self.origin
    }

    pub fn polygons_to_unit(&self, p: &MultiPolygon<f64>) -> MultiPolygon<f64> {
        p.map_coords(|c| self.to_unit(c))
    }

    pub fn polygons_to_map(&self, p: &MultiPolygon<f64>) -> MultiPolygon<f64> {
        p.map_coords(|c| self.to_map(c))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geo::{polygon, MultiPolygon};

    #[test]
    fn the_frame_makes_cells_unit_sized_and_round_trips() {
        let a = MultiPolygon(vec![
            polygon![(x: 0.0, y: 0.0), (x: 200.0, y: 0.0), (x: 200.0, y: 200.0), (x: 0.0, y: 200.0)],
        ]);
        let b = MultiPolygon(vec![
            polygon![(x: 200.0, y: 0.0), (x: 400.0, y: 0.0), (x: 400.0, y: 200.0), (x: 200.0, y: 200.0)],
        ]);
        let f = Frame::of(&[&a, &b]).unwrap();
        assert_eq!(f.scale, 200.0);
        assert_eq!(f.origin, Coord { x: 200.0, y: 100.0 });
        let unit = f.polygons_to_unit(&a);
        assert!((unit.unsigned_area() - 1.0).abs() < 1e-12);
        let back = f.to_map(f.to_unit(Coord { x: 12.5, y: -3.0 }));
        assert!((back.x - 12.5).abs() < 1e-12 && (back.y + 3.0).abs() < 1e-12);
    }
}
