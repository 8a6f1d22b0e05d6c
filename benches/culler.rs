//! The runtime culler: µs per cell entry (decode the cell's record, then build its PVS over
//! every object box), on Lyon (2,576 objects) and on a generated city of 100,000 buildings.
//! `make bench` runs it (`cargo bench -p vocc-bench --bench culler`, criterion).
//!
//! Setup (not timed): load the scene, bake the store (Lyon: every 100 m cell; the generated
//! city: the 25 m cells of the 400 m square at its centre, since the culler's cost depends on
//! the number of objects, not of baked cells; its detached buildings leave gaps that 100 m cells
//! see through, so only smaller cells get VOs there), build the box hierarchy once, and write the
//! store and the world boxes to `target/tmp/culler-NAME.{vocc,boxes}` for the C timing loop
//! (`make c-bench`, `examples/c/bench.c`). Each timed iteration enters the
//! next cell of the list, round robin.

use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, Criterion};
use vocc::bake::params::BakeParams;
use vocc::eval::metrics::object_boxes;
use vocc::eval::report::bake;
use vocc::runtime::culler::{pvs, pvs_with_stats, BoxTree};
use vocc::runtime::format::Store;
use vocc::scene::{self, ReadOptions, Scene};

fn bench_scene(c: &mut Criterion, name: &str, s: &Scene, cell_size: f64, region: Option<[f64; 4]>) {
    let params = BakeParams {
        cell_size,
        region,
        ..BakeParams::default()
    };
    let bytes = bake(s, params, None).expect("the bake runs").bytes;
    let store = Store::parse(&bytes).unwrap();
    // The scene's local frame is the store's: both come from the same load.
    let tree = BoxTree::new(&object_boxes(s));
    // The same store and boxes (world) for the C timing loop, examples/c/bench.c (make c-bench).
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    std::fs::write(dir.join(format!("culler-{name}.vocc")), &bytes).unwrap();
    // The box file as `vocc boxes` writes it: two '#' lines, then ID and box per object.
    let o = s.origin;
    let mut text = format!(
        "# vocc boxes: one object a line, ID XMIN YMIN ZMIN XMAX YMAX ZMAX\n# scene {:016x} objects {} crs {:?}\n",
        s.fingerprint(),
        s.objects.len(),
        s.crs().map_or("", |c| c.name.as_str())
    );
    for ob in &s.objects {
        let (a, b) = (ob.bbox.min + o, ob.bbox.max + o);
        text += &format!(
            "{} {} {} {} {} {} {}\n",
            ob.feature, a.x, a.y, a.z, b.x, b.y, b.z
        );
    }
    std::fs::write(dir.join(format!("culler-{name}.boxes")), text).unwrap();
    let cells: Vec<u32> = (0..store.cell_count())
        .filter(|&id| !store.cell(id).unwrap().vos().is_empty())
        .collect();
    let mut out = Vec::new();
    let (mut culled, mut vos, mut nodes, mut tested) = (0usize, 0usize, 0usize, 0usize);
    for &id in &cells {
        let rec = store.cell(id).unwrap();
        let st = pvs_with_stats(store.frame(), id, &rec, &tree, &mut out);
        nodes += st.nodes_tested;
        tested += st.boxes_tested;
        culled += tree.len() - out.len();
        vos += rec.vos().len();
    }
    eprintln!(
        "{name}: {} objects, {} cells with VOs; per cell {:.1} VOs, {:.1} objects culled, {:.0} nodes and {:.0} boxes tested",
        tree.len(),
        cells.len(),
        vos as f64 / cells.len().max(1) as f64,
        culled as f64 / cells.len().max(1) as f64,
        nodes as f64 / cells.len().max(1) as f64,
        tested as f64 / cells.len().max(1) as f64
    );
    assert!(!cells.is_empty(), "{name}: no cell got a VO");
    let mut i = 0;
    c.bench_function(&format!("culler/{name}/cell_entry"), |b| {
        b.iter(|| {
            let id = cells[i % cells.len()];
            i += 1;
            let rec = store.cell(id).unwrap();
            pvs(store.frame(), id, &rec, &tree, &mut out);
            out.len()
        })
    });
}

fn culler(c: &mut Criterion) {
    let root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/.."));
    let lyon = scene::load(
        &[root.join("data/lyon1/buildings_lyon1.geojson")],
        &ReadOptions {
            height_attr: Some("HAUTEUR".into()),
            ..ReadOptions::default()
        },
    )
    .unwrap();
    bench_scene(c, "lyon", &lyon, 100.0, None);

    let city = scene::gencity::generate(&scene::gencity::CityParams {
        buildings: 100_000,
        seed: 1,
    });
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("city_100k.geojson");
    let mut w = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    scene::gencity::write_geojson(&mut w, &city).unwrap();
    drop(w);
    let s = scene::load(
        &[path],
        &ReadOptions {
            height_attr: Some("height".into()),
            ..ReadOptions::default()
        },
    )
    .unwrap();
    let e = s.extent();
    let (cx, cy) = (0.5 * (e.min.x + e.max.x), 0.5 * (e.min.y + e.max.y));
    bench_scene(
        c,
        "generated_100k",
        &s,
        25.0,
        Some([cx - 200.0, cy - 200.0, cx + 200.0, cy + 200.0]),
    );
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30);
    targets = culler
}
criterion_main!(benches);
