//! The C API as C sees it: compiles the programs in tests/c/ with the `cc` crate's compiler
//! against include/snakegrid.h and the freshly built shared library, runs them, and checks that
//! the committed header's version macros match Cargo.toml. scripts/check-c-api.sh runs the
//! same programs through CMake, AddressSanitizer and valgrind.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The cdylib cargo built with this test. It sits beside the test binary in `deps/`; the copy
/// one level up is only refreshed by builds that ask for the library itself (`cargo build`), not
/// by `cargo test`, so it may be stale.
fn built_library() -> PathBuf {
    let exe = std::env::current_exe().expect("the test knows its own path");
    exe.with_file_name("libsnakegrid.so")
}

/// A folder with the library under its SONAME (libsnakegrid.so.0.1, which is what a linked
/// program asks the loader for) and its link name, both pointing at cargo's copy.
fn library_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let built = built_library();
        assert!(
            built.exists(),
            "{} is missing: the cdylib is built with the library",
            built.display()
        );
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join("c_api")
            .join("lib");
        std::fs::create_dir_all(&dir).unwrap();
        for name in [env!("SNAKEGRID_SONAME"), "libsnakegrid.so"] {
            let link = dir.join(name);
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink(&built, &link).unwrap();
        }
        dir
    })
}

/// Compiles `source` (C, or C++ for .cpp) into an executable linked against the library and
/// `libs`, with warnings as errors, and returns its path.
fn compile(source: &Path, libs: &[&str]) -> PathBuf {
    let cpp = source.extension().is_some_and(|e| e == "cpp");
    let target = env!("SNAKEGRID_TARGET");
    let compiler = cc::Build::new()
        .cpp(cpp)
        .target(target)
        .host(target)
        .opt_level(0)
        .debug(true)
        .cargo_metadata(false)
        .cargo_warnings(false)
        .get_compiler();
    let exe = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("c_api")
        .join(source.file_stem().unwrap());
    let lib = library_dir();
    let mut command = compiler.to_command();
    command
        .arg(if cpp { "-std=c++11" } else { "-std=c99" })
        .args(["-Wall", "-Wextra", "-Werror", "-pedantic"])
        .arg("-I")
        .arg(root().join("include"))
        .arg(source)
        .arg("-o")
        .arg(&exe)
        .arg(format!("-L{}", lib.display()))
        .arg(format!("-Wl,-rpath,{}", lib.display()))
        .arg("-lsnakegrid");
    for lib in libs {
        command.arg(lib);
    }
    let output = command.output().expect("the C compiler runs");
    assert!(
        output.status.success(),
        "compiling {} failed:\n{}",
        source.display(),
        String::from_utf8_lossy(&output.stderr)
    );
    exe
}

fn c_test(name: &str) -> PathBuf {
    root().join("tests/c").join(name)
}

/// Runs a compiled program, fails with its output unless it exits with 0, returns its stdout.
fn run(exe: &Path, args: &[&Path]) -> String {
    let output = Command::new(exe)
        .args(args)
        .output()
        .expect("the program runs");
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&output.stderr);
    print!("{stdout}");
    assert!(
        output.status.success(),
        "{} failed:\n{stdout}{stderr}",
        exe.display()
    );
    stdout
}

/// Runs one of the test programs, which end with "N passed, N failed".
fn run_tests(exe: &Path, args: &[&Path]) {
    let stdout = run(exe, args);
    assert!(stdout.contains(" 0 failed"), "{stdout}");
}

/// pkg-config's answer for GDAL, whose headers are included as system headers (they are not
/// -pedantic clean).
#[cfg(feature = "gdal")]
fn gdal_flags() -> Vec<String> {
    let query = |what: &str| {
        let output = Command::new("pkg-config")
            .args([what, "gdal"])
            .output()
            .expect("pkg-config runs");
        assert!(output.status.success(), "pkg-config finds no gdal");
        String::from_utf8(output.stdout).unwrap()
    };
    let includes = query("--cflags-only-I");
    let libs = query("--libs");
    includes
        .split_whitespace()
        .flat_map(|flag| {
            [
                "-isystem".to_owned(),
                flag.trim_start_matches("-I").to_owned(),
            ]
        })
        .chain(libs.split_whitespace().map(str::to_owned))
        .collect()
}

#[test]
fn the_in_memory_api_passes_its_c_tests() {
    let exe = compile(&c_test("test_api.c"), &["-lpthread", "-lm"]);
    run_tests(&exe, &[]);
}

#[cfg(feature = "gdal")]
#[test]
fn the_dataset_api_matches_the_in_memory_api_on_us_states() {
    // The sample bundled with the repository, so the C API tests need nothing beside it.
    let data = root().join("data/us_states.gpkg");
    let gdal = gdal_flags();
    let exe = compile(
        &c_test("test_dataset.c"),
        &gdal.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    let out = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("c_api")
        .join("dataset-out");
    std::fs::create_dir_all(&out).unwrap();
    run_tests(&exe, &[&data, &out]);
}

/// A fresh output folder for one C test.
#[cfg(feature = "gdal")]
fn output_dir(name: &str) -> PathBuf {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("c_api")
        .join(name);
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&out).unwrap();
    out
}

#[cfg(feature = "gdal")]
#[test]
fn every_bad_input_gets_a_clear_answer_through_the_c_api() {
    let exe = compile(&c_test("test_bad_inputs.c"), &["-lm"]);
    run_tests(
        &exe,
        &[
            &root().join("tests/data/bad"),
            &output_dir("bad-inputs-out"),
        ],
    );
}

#[cfg(feature = "gdal")]
#[test]
fn eight_threads_on_independent_handles_match_a_serial_run() {
    let exe = compile(&c_test("test_threads.c"), &["-lpthread"]);
    run_tests(
        &exe,
        &[
            &root().join("tests/data/bad/enclave.geojson"),
            &output_dir("threads-out"),
        ],
    );
}

#[test]
fn far_apart_clusters_lay_out_in_little_memory() {
    let exe = compile(&c_test("test_clusters.c"), &[]);
    run_tests(&exe, &[]);
}

#[test]
fn the_header_compiles_and_links_as_cpp() {
    let exe = compile(&c_test("test_header.cpp"), &[]);
    run_tests(&exe, &[]);
}

#[test]
fn the_committed_header_is_the_generated_one() {
    let committed_path = root().join("include/snakegrid.h");
    let generated = std::fs::read_to_string(env!("SNAKEGRID_GENERATED_HEADER")).unwrap();
    let committed = std::fs::read_to_string(&committed_path).unwrap_or_default();
    if committed != generated {
        if std::env::var_os("SNAKEGRID_UPDATE_HEADER").is_some() {
            std::fs::write(&committed_path, &generated).unwrap();
        } else {
            panic!(
                "include/snakegrid.h is stale: run SNAKEGRID_UPDATE_HEADER=1 cargo test --test \
                 c_api header, and commit it"
            );
        }
    }
}

#[test]
fn every_function_that_can_fail_warns_when_its_status_is_dropped() {
    // The header promises SNAKEGRID_MUST_USE on every function returning a status;
    // snakegrid_job_set_update lacked it.
    let header = std::fs::read_to_string(root().join("include/snakegrid.h")).unwrap();
    let lines: Vec<&str> = header.lines().collect();
    let mut checked = 0;
    for (k, line) in lines.iter().enumerate() {
        let Some(rest) = line.strip_prefix("snakegrid_status snakegrid_") else {
            continue;
        };
        let name = rest.split('(').next().unwrap();
        let marked = line.contains("SNAKEGRID_MUST_USE")
            || (k > 0 && lines[k - 1].trim() == "SNAKEGRID_MUST_USE");
        assert!(marked, "snakegrid_{name} lacks SNAKEGRID_MUST_USE");
        checked += 1;
    }
    assert!(
        checked > 40,
        "only {checked} functions returning a status found"
    );
}

#[test]
fn the_header_version_macros_match_cargo_toml() {
    let manifest = std::fs::read_to_string(root().join("Cargo.toml")).unwrap();
    let version = manifest
        .lines()
        .find_map(|line| line.strip_prefix("version = \""))
        .and_then(|rest| rest.strip_suffix('"'))
        .expect("Cargo.toml has a package version");
    let parts: Vec<&str> = version.split('.').collect();
    assert_eq!(parts.len(), 3, "{version}");
    let header = std::fs::read_to_string(root().join("include/snakegrid.h")).unwrap();
    for (name, value) in ["MAJOR", "MINOR", "PATCH"].iter().zip(&parts) {
        let line = format!("#define SNAKEGRID_VERSION_{name} {value}\n");
        assert!(header.contains(&line), "the header lacks {line:?}");
    }
    assert!(header.contains(&format!("#define SNAKEGRID_VERSION \"{version}\"\n")));
    let number: Vec<u64> = parts.iter().map(|p| p.parse().unwrap()).collect();
    let line = format!(
        "#define SNAKEGRID_VERSION_NUMBER {}\n",
        number[0] * 10_000 + number[1] * 100 + number[2]
    );
    assert!(header.contains(&line), "the header lacks {line:?}");
}

/// The first ```c block of a Markdown file of the repository, written out as `name`.
fn c_example(markdown: &str, name: &str) -> PathBuf {
    let text = std::fs::read_to_string(root().join(markdown)).unwrap();
    let example = text
        .split("```c\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .unwrap_or_else(|| panic!("{markdown} has a ```c example"));
    let source = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("c_api")
        .join(name);
    std::fs::create_dir_all(source.parent().unwrap()).unwrap();
    std::fs::write(&source, example).unwrap();
    source
}

#[test]
fn the_example_in_the_docs_compiles_and_runs_as_written() {
    let source = c_example("docs/c-api.md", "docs_example.c");
    let stdout = run(&compile(&source, &[]), &[]);
    assert!(stdout.starts_with("neighbours kept: "), "{stdout}");
    for id in ["sw", "se", "nw", "ne"] {
        assert!(stdout.contains(&format!("{id}: column ")), "{stdout}");
    }
}

#[cfg(feature = "gdal")]
#[test]
fn the_example_in_the_readme_compiles_and_runs_as_written() {
    let source = c_example("README.md", "readme_example.c");
    let out = output_dir("readme-example").join("us_grid.gpkg");
    let stdout = run(
        &compile(&source, &[]),
        &[&out, &root().join("data/us_states.gpkg")],
    );
    assert!(stdout.starts_with("C_adjacent 0."), "{stdout}");
    assert!(out.exists(), "the example wrote its grid map");
}

#[test]
fn the_docs_options_table_is_the_parameter_table() {
    let path = root().join("docs/c-api.md");
    let docs = std::fs::read_to_string(&path).unwrap();
    let begin = docs
        .find("<!-- BEGIN options")
        .expect("docs/c-api.md marks its options table");
    let start = docs[begin..].find("-->\n").unwrap() + begin + 4;
    let end = docs.find("<!-- END options -->").unwrap();
    let table = snakegrid::params::markdown();
    if docs[start..end] != table {
        if std::env::var_os("SNAKEGRID_UPDATE_DOCS").is_some() {
            std::fs::write(&path, format!("{}{table}{}", &docs[..start], &docs[end..])).unwrap();
        } else {
            panic!(
                "docs/c-api.md's options table is stale: run SNAKEGRID_UPDATE_DOCS=1 cargo test \
                 --test c_api docs"
            );
        }
    }
}
