//! The committed header `include/vocc.h` is what cbindgen makes of `src/lib.rs` with
//! `cbindgen.toml`. Fails with the first differing line when they differ;
//! `VOCC_BLESS_HEADER=1` (what `make header` sets) rewrites the header instead.

use std::path::Path;

#[test]
fn committed_header_matches_the_code() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(dir.join("src/lib.rs"))
        .generate()
        .expect("cbindgen parses src/lib.rs");
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let path = dir.join("include/vocc.h");
    if std::env::var_os("VOCC_BLESS_HEADER").is_some() {
        std::fs::write(&path, &generated).expect("write include/vocc.h");
        return;
    }
    let committed = std::fs::read(&path).unwrap_or_default();
    if committed != generated {
        let (c, g) = (
            String::from_utf8_lossy(&committed),
            String::from_utf8_lossy(&generated),
        );
        let first = c
            .lines()
            .zip(g.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(c.lines().count().min(g.lines().count()));
        panic!(
            "capi/include/vocc.h differs from what cbindgen generates from capi/src/lib.rs \
             (first at line {}: committed {:?}, generated {:?}); run `make header` and commit it",
            first + 1,
            c.lines().nth(first).unwrap_or("<end>"),
            g.lines().nth(first).unwrap_or("<end>")
        );
    }
}
