//! The corpus of bad and awkward inputs in tests/data/bad/ (made by scripts/make-bad-inputs.py,
//! listed with the expected outcome in cases.tsv) through the library and the command line;
//! tests/c/test_bad_inputs.c runs the same manifest through the C API. Every case either gives a
//! valid grid map or fails with a message naming the feature and the problem, and a failed or
//! cancelled run leaves nothing at the destination.
// Reads and writes datasets: needs the GDAL layer.
#![cfg(feature = "gdal")]

use snakegrid::io::{read_regions, run, Job};
use snakegrid::{generate, Error, Params};
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::Scratch;

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad")
}

/// One line of cases.tsv.
struct Case {
    file: String,
    id_field: Option<String>,
    ok: bool,
    /// The kind of error expected (`invalid_input`, `io_error`), when not `ok`.
    error: Option<String>,
    /// What the error message (or, for a success, one of the notes) must contain.
    text: Option<String>,
}

fn cases() -> Vec<Case> {
    let manifest = std::fs::read_to_string(corpus().join("cases.tsv")).unwrap();
    let cases: Vec<Case> = manifest
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|line| {
            let columns: Vec<&str> = line.split('\t').collect();
            assert_eq!(columns.len(), 4, "cases.tsv: {line:?}");
            let optional = |s: &str| (s != "-").then(|| s.to_owned());
            assert!(
                matches!(columns[2], "ok" | "invalid_input" | "io_error"),
                "cases.tsv: {line:?}"
            );
            Case {
                file: columns[0].to_owned(),
                id_field: optional(columns[1]),
                ok: columns[2] == "ok",
                error: (columns[2] != "ok").then(|| columns[2].to_owned()),
                text: optional(columns[3]),
            }
        })
        .collect();
    assert!(cases.len() >= 20, "the corpus is there");
    cases
}

fn job(case: &Case, dst: &Path) -> Job {
    Job {
        src: corpus().join(&case.file).to_string_lossy().into_owned(),
        id_field: case.id_field.clone(),
        dst: dst.to_string_lossy().into_owned(),
        ..Job::default()
    }
}

#[test]
fn every_case_through_the_library() {
    for case in cases() {
        let job = job(&case, Path::new("unused.gpkg"));
        let result = read_regions(&job).and_then(|source| {
            let map = generate(&source.regions, &Params::default(), &|_, _| true)?;
            Ok((source, map))
        });
        match (case.ok, result) {
            (true, Ok((source, map))) => {
                common::assert_valid_grid(&source.regions, &map);
                common::assert_ids_and_order_do_not_matter(&source.regions, &Params::default());
                if let Some(text) = &case.text {
                    // The reading's notes (curves, CRS) and the layout's (repairs).
                    let notes: Vec<&String> = source.notes.iter().chain(&map.notes).collect();
                    assert!(
                        notes.iter().any(|n| n.contains(text.as_str())),
                        "{}: no note holds {text:?}: {notes:?}",
                        case.file,
                    );
                }
            }
            (false, Err(e)) => {
                let kind = match e {
                    Error::InvalidInput { .. } => "invalid_input",
                    Error::Io(_) => "io_error",
                    _ => "another kind",
                };
                assert_eq!(Some(kind), case.error.as_deref(), "{}: {e}", case.file);
                let message = e.to_string();
                let expected = case.text.as_deref().unwrap_or_default();
                assert!(
                    message.contains(expected),
                    "{}: {message:?} does not say {expected:?}",
                    case.file
                );
            }
            (true, Err(e)) => panic!("{}: expected a grid map, got {e}", case.file),
            (false, Ok(_)) => panic!("{}: expected an error, got a grid map", case.file),
        }
    }
}

#[test]
fn every_case_through_the_command_line() {
    let scratch = Scratch::new("cli");
    for case in cases() {
        let dst = scratch.path("grid.gpkg");
        let src = corpus().join(&case.file);
        let mut command = Command::new(env!("CARGO_BIN_EXE_snakegrid"));
        if let Some(id) = &case.id_field {
            command.args(["-id", id]);
        }
        let output = command.arg(&dst).arg(&src).output().unwrap();
        let stdout = String::from_utf8_lossy(&output.stdout);
        let stderr = String::from_utf8_lossy(&output.stderr);
        if case.ok {
            assert!(output.status.success(), "{}: {stderr}", case.file);
            assert_eq!(scratch.listing(), ["grid.gpkg"], "{}", case.file);
            if let Some(text) = &case.text {
                assert!(
                    stdout.contains(&format!("note: {text}")),
                    "{}: the summary has no note {text:?}: {stdout}",
                    case.file
                );
            }
            std::fs::remove_file(&dst).unwrap();
        } else {
            assert_eq!(output.status.code(), Some(1), "{}: {stderr}", case.file);
            // Only the one error line (after the progress line it cut short), no panic text.
            let progress = |l: &str| l.chars().all(|c| c.is_ascii_digit() || c == '.');
            let lines: Vec<&str> = stderr
                .lines()
                .filter(|l| !l.trim().is_empty() && !progress(l))
                .collect();
            assert_eq!(lines.len(), 1, "{}: {stderr:?}", case.file);
            let expected = case.text.as_deref().unwrap_or_default();
            assert!(
                lines[0].starts_with("snakegrid: ERROR: ") && lines[0].contains(expected),
                "{}: {:?} does not say {expected:?}",
                case.file,
                lines[0]
            );
            assert!(
                scratch.listing().is_empty(),
                "{}: {:?}",
                case.file,
                scratch.listing()
            );
        }
    }
}

#[test]
fn a_failed_run_leaves_an_existing_destination_untouched_even_with_overwrite() {
    let scratch = Scratch::new("untouched");
    let dst = scratch.path("grid.gpkg");
    let before = b"not a grid map, and must stay so";
    for case in cases().iter().filter(|c| !c.ok) {
        std::fs::write(&dst, before).unwrap();
        let job = Job {
            overwrite: true,
            json_report: Some(scratch.path("r.json").to_string_lossy().into_owned()),
            ..job(case, &dst)
        };
        assert!(
            run(&job, &Params::default(), &|_, _| true).is_err(),
            "{}",
            case.file
        );
        assert_eq!(std::fs::read(&dst).unwrap(), before, "{}", case.file);
        assert_eq!(scratch.listing(), ["grid.gpkg"], "{}", case.file);
    }
}

#[test]
fn a_cancelled_run_leaves_an_existing_destination_untouched_at_every_stage() {
    let scratch = Scratch::new("cancelled");
    let dst = scratch.path("grid.gpkg");
    let before = b"the previous grid map";
    let case = cases()
        .into_iter()
        .find(|c| c.file == "enclave.geojson")
        .expect("the corpus has the enclave");
    let job = Job {
        overwrite: true,
        svg: Some(scratch.path("p.svg").to_string_lossy().into_owned()),
        ..job(&case, &dst)
    };
    // At the first report of each stage, from reading to writing, and at the last report that
    // may still cancel (writing's end).
    let stages = [
        "reading",
        "checking geometry",
        "outline",
        "Snake step",
        "layout",
        "writing",
    ];
    for stage in stages {
        std::fs::write(&dst, before).unwrap();
        let seen = std::sync::atomic::AtomicBool::new(false);
        let result = run(&job, &Params::default(), &|_, message| {
            let here = message.starts_with(stage);
            seen.fetch_or(here, std::sync::atomic::Ordering::Relaxed);
            !here
        });
        assert!(seen.into_inner(), "no report names {stage:?}");
        assert_eq!(result.err(), Some(Error::Cancelled), "cancelled at {stage}");
        assert_eq!(std::fs::read(&dst).unwrap(), before, "cancelled at {stage}");
        assert_eq!(scratch.listing(), ["grid.gpkg"], "cancelled at {stage}");
    }
    // While the features are read: the host is asked as reading begins and again at the first
    // feature.
    std::fs::write(&dst, before).unwrap();
    let readings = std::sync::atomic::AtomicUsize::new(0);
    let result = run(&job, &Params::default(), &|_, message| {
        message != "reading" || readings.fetch_add(1, std::sync::atomic::Ordering::Relaxed) == 0
    });
    assert_eq!(readings.into_inner(), 2);
    assert_eq!(result.err(), Some(Error::Cancelled), "cancelled reading");
    assert_eq!(std::fs::read(&dst).unwrap(), before, "cancelled reading");
    assert_eq!(scratch.listing(), ["grid.gpkg"], "cancelled reading");
    std::fs::write(&dst, before).unwrap();
    let result = run(&job, &Params::default(), &|fraction, _| fraction < 1.0);
    assert_eq!(result.err(), Some(Error::Cancelled), "cancelled at the end");
    assert_eq!(std::fs::read(&dst).unwrap(), before, "cancelled at the end");
    assert_eq!(scratch.listing(), ["grid.gpkg"], "cancelled at the end");
    run(&job, &Params::default(), &|_, _| true).unwrap();
    assert_ne!(std::fs::read(&dst).unwrap(), before);
    assert_eq!(scratch.listing(), ["grid.gpkg", "p.svg"]);
}

#[test]
fn a_layer_across_the_antimeridian_keeps_its_shape() {
    // Squares a{row}{column} in two rows of four, from 176°E eastwards across 180° to 176°W.
    let job = Job {
        src: corpus()
            .join("antimeridian.geojson")
            .to_string_lossy()
            .into_owned(),
        id_field: Some("code".into()),
        ..Job::default()
    };
    let source = read_regions(&job).unwrap();
    assert!(
        source.notes.iter().any(|n| n.contains("180.0E)")),
        "centred on the antimeridian: {:?}",
        source.notes
    );
    let map = generate(&source.regions, &Params::default(), &|_, _| true).unwrap();
    let cell = |id: &str| {
        let c = map.cells.iter().find(|c| c.id == id).unwrap();
        (c.col, c.row)
    };
    for row in 0..2 {
        for col in 0..3 {
            let (west, east) = (
                cell(&format!("a{row}{col}")),
                cell(&format!("a{row}{}", col + 1)),
            );
            assert!(
                west.0 < east.0,
                "a{row}{col} {west:?} is west of its neighbour {east:?}"
            );
        }
    }
    for col in 0..4 {
        let (south, north) = (cell(&format!("a0{col}")), cell(&format!("a1{col}")));
        assert!(
            north.1 < south.1,
            "a1{col} {north:?} is north of a0{col} {south:?}"
        );
    }
}

#[test]
fn coordinates_out_of_proportion_are_refused_by_name() {
    // Found by fuzzing (fuzz/corpus/wkb/needle_1e231): a valid polygon 3e231 units long and
    // 1e-90 units² in area, whose unit-cell frame overflows.
    let bytes =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/wkb/needle_1e231"))
            .unwrap();
    let needle = snakegrid::Region {
        id: "needle".into(),
        geometry: snakegrid::wkb::to_multi_polygon(&bytes).unwrap(),
        group: None,
        pin: None,
    };
    let error = generate(&[needle], &Params::default(), &|_, _| true).unwrap_err();
    assert!(
        error
            .to_string()
            .starts_with("feature needle: a coordinate (3.1e231) is beyond ±1e100"),
        "{error}"
    );
    // Within that range, a needle 1e50 units long and 1e-40 wide reaches 5e44 times the side
    // of its own area's square from its centre.
    let needle = snakegrid::Region {
        id: "needle".into(),
        geometry: geo::MultiPolygon(vec![geo::Rect::new(
            geo::coord! { x: 0.0, y: 0.0 },
            geo::coord! { x: 1e50, y: 1e-40 },
        )
        .to_polygon()]),
        group: None,
        pin: None,
    };
    let error = generate(&[needle], &Params::default(), &|_, _| true).unwrap_err();
    assert!(
        error
            .to_string()
            .starts_with("feature needle: the geometry reaches more than"),
        "{error}"
    );
}

#[test]
fn a_region_whose_union_has_no_area_is_refused_by_name_and_a_repairable_one_is_laid_out() {
    // Found by fuzzing (fuzz/corpus/wkb/): regions whose subnormal coordinates (8e-320, 1e-314)
    // leave the union of the regions empty, or (before the overlay repaired invalid regions)
    // left the outline empty.
    let region = |case: &str| snakegrid::Region {
        id: "sliver".into(),
        geometry: snakegrid::wkb::to_multi_polygon(
            &std::fs::read(
                Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("fuzz/corpus/wkb")
                    .join(case),
            )
            .unwrap(),
        )
        .unwrap(),
        group: None,
        pin: None,
    };
    let error = generate(&[region("empty_union")], &Params::default(), &|_, _| true).unwrap_err();
    assert!(
        error
            .to_string()
            .starts_with("feature sliver: the union of the regions has no area"),
        "{error}"
    );
    // A unit square overlapping a triangle, some corners a subnormal distance from 0: repaired
    // by the even-odd rule into a region with area, which takes the one cell.
    let map = generate(&[region("empty_outline")], &Params::default(), &|_, _| true).unwrap();
    assert_eq!(map.cells.len(), 1);
    assert!(
        map.notes
            .iter()
            .any(|n| n.contains("invalid polygon repaired")),
        "{:?}",
        map.notes
    );
}
