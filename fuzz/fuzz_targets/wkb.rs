//! Any bytes given as a region's WKB: an error or a (multi)polygon, never a panic. Whatever is
//! read must also survive the checks a run makes first, and its polygons must write back.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    if let Ok(geometry) = snakegrid::wkb::to_multi_polygon(bytes) {
        for polygon in &geometry.0 {
            snakegrid::wkb::from_polygon(polygon);
        }
        let region = snakegrid::Region {
            id: "fuzz".into(),
            geometry,
        };
        // Only the input checks: a run with no Snake steps, one shift, no noise, no refinement
        // is cheap, and it must end in a grid map or an error, not a panic.
        let mut params = snakegrid::Params::default();
        params.max_steps = 0;
        params.noise_levels.clear();
        params.shifts.truncate(1);
        params.refine = false;
        let _ = snakegrid::generate(&[region], &params, &|_, _| true);
    }
});
