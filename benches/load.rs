//! Scene loading: readers, repair, convex decomposition and solid extraction, on the bundled real
//! data and a generated city. `make bench` runs it; figures go in issue notes, never in tests.

use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, Criterion};
use vocc::scene::{self, gencity, ReadOptions};

fn data(rel: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/..")).join(rel)
}

fn load(c: &mut Criterion) {
    let mut g = c.benchmark_group("load");
    g.sample_size(10);
    let height = |a: &str| ReadOptions {
        height_attr: Some(a.into()),
        ..ReadOptions::default()
    };
    let cases = [
        (
            "lyon_geojson",
            "data/lyon1/buildings_lyon1.geojson",
            height("HAUTEUR"),
        ),
        (
            "denhaag_cityjson",
            "data/denhaag/DenHaag_01.json",
            ReadOptions::default(),
        ),
        (
            "denhaag_obj",
            "data/denhaag/DenHaag_01_buildings.obj",
            ReadOptions::default(),
        ),
        (
            "gelderseplein_obj",
            "data/gelderseplein/gelderseplein.obj",
            ReadOptions::default(),
        ),
    ];
    for (name, rel, opts) in cases {
        let path = data(rel);
        g.bench_function(name, |b| {
            b.iter(|| scene::load(std::slice::from_ref(&path), &opts).unwrap())
        });
    }
    // A generated city of 10^4 buildings, written once.
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let city = dir.join("bench_city_10k.geojson");
    let buildings = gencity::generate(&gencity::CityParams {
        buildings: 10_000,
        seed: 1,
    });
    gencity::write_geojson(
        std::io::BufWriter::new(std::fs::File::create(&city).unwrap()),
        &buildings,
    )
    .unwrap();
    let opts = height("height");
    g.bench_function("gencity_10k_geojson", |b| {
        b.iter(|| scene::load(std::slice::from_ref(&city), &opts).unwrap())
    });
    g.finish();

    c.bench_function("gencity_generate_10k", |b| {
        b.iter(|| {
            gencity::generate(&gencity::CityParams {
                buildings: 10_000,
                seed: 1,
            })
        })
    });
}

criterion_group!(benches, load);
criterion_main!(benches);
