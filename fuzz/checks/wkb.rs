// What the `wkb` fuzz target checks of any bytes given as a region's WKB, shared with
// tests/fuzz_corpus.rs, which replays the kept corpus (fuzz/corpus/wkb/) in every test run.

/// An error or a (multi)polygon, never a panic. Whatever is read must also survive the checks a
/// run makes first, and its polygons must write back.
pub fn check(bytes: &[u8]) {
    if let Ok(geometry) = snakegrid::wkb::to_multi_polygon(bytes) {
        for polygon in &geometry.0 {
            snakegrid::wkb::from_polygon(polygon);
        }
        let region = snakegrid::Region {
            id: "fuzz".into(),
            geometry,
            group: None,
            pin: None,
        };
        // Only the input checks: a run with no Snake steps, one shift, no noise, no refinement
        // is cheap, and it must end in a grid map or an error, not a panic.
        let params = snakegrid::Params {
            max_steps: 0,
            noise_levels: Vec::new(),
            shifts: vec![[0.0, 0.0]],
            refine: false,
            ..snakegrid::Params::default()
        };
        let _ = snakegrid::generate(&[region], &params, &|_, _| true);
    }
}
