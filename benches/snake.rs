//! Speed of the method on the shared layers (issue 2's speed goals; figures in BENCHMARKS.md):
//! one Snake step against the network's node count (it should grow about linearly: the sparse
//! Cholesky replaces the paper's dense inverses), the whole Snake, and the whole method.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use snakegrid::diagnostics::SnakeNetwork;
use snakegrid::io::{read_regions, Job};
use snakegrid::{generate, Params, Region};
use std::time::Duration;

const LAYERS: [&str; 5] = [
    "us_states",
    "nc_counties",
    "virginia_counties",
    "world_countries",
    "us_counties",
];

fn load(name: &str) -> Vec<Region> {
    let dir = std::env::var("SNAKEGRID_DATA")
        .unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data").to_owned());
    let job = Job {
        src: format!("{dir}/{name}.gpkg"),
        id_field: Some("id".into()),
        ..Job::default()
    };
    read_regions(&job).expect("shared layer").regions
}

fn snake_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("snake_step");
    group.measurement_time(Duration::from_secs(5));
    let one = Params {
        max_steps: 1,
        ..Params::default()
    };
    for name in LAYERS {
        let regions = load(name);
        let net = SnakeNetwork::of(&regions, &one).expect("a network");
        group.bench_with_input(BenchmarkId::new(name, net.nodes()), &net, |b, net| {
            b.iter(|| net.run(&one).expect("snake"))
        });
    }
    group.finish();
}

/// The paper's Table 2 range (about 100 to 900 network nodes): the whole Snake (30 steps) on the
/// US states with outlines of 1 to 17 vertices per region.
fn snake_paper_sizes(c: &mut Criterion) {
    let mut group = c.benchmark_group("snake_30_steps");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    let regions = load("us_states");
    for per_region in [1.0, 2.0, 4.0, 8.0, 12.0, 17.0] {
        let params = Params {
            vertices_per_region: per_region,
            ..Params::default()
        };
        let net = SnakeNetwork::of(&regions, &params).expect("a network");
        group.bench_with_input(
            BenchmarkId::new("us_states", net.nodes()),
            &net,
            |b, net| b.iter(|| net.run(&params).expect("snake")),
        );
    }
    group.finish();
}

fn whole_method(c: &mut Criterion) {
    let mut group = c.benchmark_group("generate");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    for name in &LAYERS[..4] {
        let regions = load(name);
        group.bench_function(*name, |b| {
            b.iter(|| generate(&regions, &Params::default(), &|_, _| true).expect("grid map"))
        });
    }
    group.finish();
}

criterion_group!(benches, snake_step, snake_paper_sizes, whole_method);
criterion_main!(benches);
