# vocc: the common tasks. Each target installs nothing beyond the Rust toolchain and crates.io.

CARGO ?= cargo
DEMO_SCENE := data/lyon1/buildings_lyon1.geojson

.PHONY: build test test-long test-web web-bundle demo bench scale eval eval-tokyo lint fresh-clone pictures fuzz header c-bench c-size

build:
	$(CARGO) build --release

# The whole test suite, as CI runs it: all tests, the embeddable core without the geometry stack
# (and that it depends on thiserror alone), the C ABI (capi/: its tests, the header against
# cbindgen, the C example against `vocc pvs`), the Python package (a wheel built with maturin in
# a venv under target/py, then its pytest suite), the JavaScript runtime (js/test.sh: node's test
# runner against the CLI on Lyon, FORMAT.md's tables and the fuzz corpora), formatting.
test:
	$(CARGO) test --locked
	$(CARGO) test --locked --no-default-features -p vocc -p vocc-capi --lib --test header
	@deps="$$($(CARGO) tree --locked --no-default-features -p vocc -e normal --depth 1 --prefix none | awk 'NR > 1 {print $$1}' | sort -u | tr '\n' ' ')"; \
	  test "$$deps" = "thiserror " || { echo "runtime dependencies: $$deps(ARCHITECTURE.md invariant 9 allows thiserror alone)" >&2; exit 1; }
	CARGO="$(CARGO)" examples/c/test.sh
	CARGO="$(CARGO)" python/test.sh
	CARGO="$(CARGO)" js/test.sh
	$(CARGO) fmt --all -- --check

# The viewer page in a real browser (js/test-web.sh): installs Chromium from the system packages
# when it is missing (as root), the npm packages of js/ (npm ci), checks the committed bundle
# js/dist/viewer.js and the runtime's types, then opens the Lyon page (2.0) and a Salt River page
# (2.1, on its DEM) in headless Chromium, clicks a cell, checks the PVS count shown against `vocc
# pvs`, times the load and the PVS builds, and saves a screenshot in target/tmp/web/.
test-web:
	CARGO="$(CARGO)" js/test-web.sh

# Rebuilds js/dist/viewer.js (three.js, the viewer and the runtime, bundled by esbuild), which
# `vocc view` puts in every page; commit it with the sources.
web-bundle:
	cd js && npm ci --no-audit --no-fund && node viewer/build.mjs

# The long versions of checks that `make test` runs on fewer cells: the incremental rebake tests
# over every cell of Lyon and of a generated city (`make test` bakes one band of cells across
# each scene). About 5 minutes on 2 cores once built.
test-long:
	$(CARGO) test --locked --test all incremental:: -- --ignored

# The main job on the bundled example: bake Lyon into an occluder store, then describe it.
demo:
	$(CARGO) run --locked --release -- bake $(DEMO_SCENE) --height-attr HAUTEUR -o target/lyon.vocc
	$(CARGO) run --locked --release -- inspect target/lyon.vocc

# The benchmarks are the workspace member benches/ (package vocc-bench), so `cargo test` does not
# build criterion; one of them: cargo bench -p vocc-bench --bench culler
bench:
	$(CARGO) bench --locked -p vocc-bench

# The bake at scale: generated cities of 10^4, 10^5 and 10^6 buildings, end to end, with peak
# memory. Since the far field (issue 31) the 10^6 city takes some 4-5 core-hours, about 2-2.5 hours
# on 2 cores (docs/SCALING.md); `cargo bench -p vocc-bench --bench scale` alone runs 10^4 and 10^5.
scale:
	VOCC_SCALE=10000,100000,1000000 $(CARGO) bench --locked -p vocc-bench --bench scale

# Regenerates docs/RESULTS.md and docs/img/*.svg from the bundled data (about 2 hours on 2 cores
# before Tokyo centre was added, whose section alone took 18.5 minutes). `make eval ONLY="Tokyo centre"`
# regenerates one dataset's section and keeps the rest of the file (`vocc results --only`).
eval:
	$(CARGO) run --locked --release -- results -o docs/RESULTS.md $(if $(ONLY),--only "$(ONLY)")

# Tokyo centre, every 100 m cell (issue 31's figures): the default bake, then `vocc eval` of all
# 961 cells by the three oracles, its report in docs/tokyo/ (about 25 minutes on 2 cores).
eval-tokyo:
	$(CARGO) run --locked --release -- bake $(TOKYO) --height-attr height -o target/tokyo.vocc
	$(CARGO) run --locked --release -- eval target/tokyo.vocc $(TOKYO) --height-attr height --report docs/tokyo

# Clippy on every workspace member: the library, the CLI (cli/), the C ABI (capi/, where every
# unsafe block must carry a SAFETY comment), the Python binding (python/) and the benchmarks.
lint:
	$(CARGO) clippy --locked --workspace --all-targets -- -D warnings

# Clones the committed main into a temporary folder and runs the README's two commands there.
fresh-clone:
	tools/fresh-clone.sh

# Regenerates the pictures in docs/img: the paper's Fig. 3 configuration, a Lyon cell, and two
# Lyon cells before (the growth generator) and after (the long generator), like the paper's Fig. 8,
# and a Tokyo cell the same way (its 2 MB SVGs are shot to PNG with Chromium: CHROMIUM=path); an
# interior cell of the generated 10^6 city at --reach 900 and 2500 (15 MB SVGs, shot to JPEG); a
# cell of the towers' stand-in (tools/gen_towers.py) at --reach 900 and auto.
TOKYO = data/tokyo-central/tokyo_central_utm54n.geojson
CHROMIUM ?= chromium
pictures:
	$(CARGO) test --locked --test all umbra_cases::
	cp target/tmp/umbra-cases/fig3_staggered.svg docs/img/
	$(CARGO) run --locked --release -- render --debug $(DEMO_SCENE) --height-attr HAUTEUR \
		--at 1842000,5176050 --generator growth -o docs/img/lyon_cell_100m.svg
	$(CARGO) run --locked --release -- bake $(DEMO_SCENE) --height-attr HAUTEUR -o target/lyon.vocc
	$(CARGO) run --locked --release -- bake $(DEMO_SCENE) --height-attr HAUTEUR --generator growth \
		-o target/lyon_growth.vocc
	$(CARGO) run --locked --release -- render target/lyon.vocc $(DEMO_SCENE) --height-attr HAUTEUR \
		--at 1842000,5176050 --radius 400 -o docs/img/lyon_cell_store.svg
	$(CARGO) run --locked --release -- bake data/capetown/salt_river_footprints_utm34s.geojson \
		--height-attr height --base-attr base_z --terrain data/capetown/capetown_dem25m_utm34s.tif \
		-o target/saltriver.vocc
	$(CARGO) run --locked --release -- render target/saltriver.vocc \
		data/capetown/salt_river_footprints_utm34s.geojson --height-attr height --base-attr base_z \
		--terrain data/capetown/capetown_dem25m_utm34s.tif --cell 221 --radius 700 \
		-o docs/img/saltriver_cell_terrain.svg
	for at in 1842000,5176050 1841450,5175850; do \
		$(CARGO) run --locked --release -- render target/lyon_growth.vocc $(DEMO_SCENE) --height-attr HAUTEUR \
			--at $$at --radius 700 -o docs/img/lyon_before_$$at.svg; \
		$(CARGO) run --locked --release -- render target/lyon.vocc $(DEMO_SCENE) --height-attr HAUTEUR \
			--at $$at --radius 700 -o docs/img/lyon_after_$$at.svg; \
	done
	$(CARGO) run --locked --release -- bake $(TOKYO) --height-attr height -o target/tokyo.vocc
	$(CARGO) run --locked --release -- bake $(TOKYO) --height-attr height --generator growth \
		-o target/tokyo_growth.vocc
	mkdir -p target/tmp/pictures
	for st in tokyo_growth tokyo; do \
		$(CARGO) run --locked --release -- render target/$$st.vocc $(TOKYO) --height-attr height \
			--cell 480 --radius 1500 -o target/tmp/pictures/$$st.svg && \
		$(CHROMIUM) --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=900,980 \
			--screenshot=$(CURDIR)/docs/img/$${st}_cell_480.png file://$(CURDIR)/target/tmp/pictures/$$st.svg \
			|| exit 1; \
	done
	$(CARGO) run --locked --release -- gen-city --buildings 1000000 --seed 1 -o target/tmp/pictures/city.geojson
	for reach in 900 2500; do \
		$(CARGO) run --locked --release -- bake target/tmp/pictures/city.geojson --height-attr height \
			--region 512001.6,5012001.6,512799.4,5012799.4 --reach $$reach \
			-o target/tmp/pictures/city_$$reach.vocc && \
		$(CARGO) run --locked --release -- render target/tmp/pictures/city_$$reach.vocc \
			target/tmp/pictures/city.geojson --height-attr height --cell 31218 --radius 4000 \
			-o target/tmp/pictures/city_$$reach.svg && \
		$(CHROMIUM) --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=900,980 \
			--screenshot=$(CURDIR)/docs/img/gen_city_1e6_reach_$$reach.jpg \
			file://$(CURDIR)/target/tmp/pictures/city_$$reach.svg || exit 1; \
	done

	mkdir -p target/tmp/pictures
	python3 tools/gen_towers.py > target/tmp/pictures/towers.geojson
	for reach in 900 auto; do \
		$(CARGO) run --locked --release -- bake target/tmp/pictures/towers.geojson --height-attr height \
			--reach $$reach -o target/tmp/pictures/towers_$$reach.vocc && \
		$(CARGO) run --locked --release -- render target/tmp/pictures/towers_$$reach.vocc \
			target/tmp/pictures/towers.geojson --height-attr height --cell 498 --radius 2000 \
			-o docs/img/towers_reach_$$reach.svg || exit 1; \
	done

# Fuzzing (docs/FUZZING.md): every cargo-fuzz target for FUZZ_SECONDS each (default 600), one after
# the other, growing fuzz/corpus/; logs in fuzz/logs/, findings in fuzz/artifacts/. Needs the
# nightly toolchain and cargo-fuzz (`cargo install cargo-fuzz`). `make test` replays the committed
# corpora on stable (tests/fuzz_corpus.rs); fuzz/minimize.sh shrinks fuzz/corpus/ back to a
# committable size. Example: make fuzz FUZZ_SECONDS=60
FUZZ_SECONDS ?= 600
fuzz:
	fuzz/run.sh $(FUZZ_SECONDS)

# Regenerates the C header capi/include/vocc.h from capi/src/lib.rs (cbindgen); `make test` fails
# while the committed header differs.
header:
	VOCC_BLESS_HEADER=1 $(CARGO) test --locked -p vocc-capi --test header

# The culler through the C ABI, µs per cell entry (docs/EMBEDDING.md), on the stores and boxes that
# `cargo bench -p vocc-bench --bench culler` (the Rust figures) writes to target/tmp: run that first.
c-bench:
	$(CARGO) build --locked --release -p vocc-capi
	mkdir -p target/tmp/c-bench
	cc -std=c99 -O2 -Icapi/include examples/c/bench.c target/release/libvocc.a -lm -lpthread -ldl \
		-o target/tmp/c-bench/bench
	for name in lyon generated_100k; do \
		target/tmp/c-bench/bench target/tmp/culler-$$name.vocc target/tmp/culler-$$name.boxes 30; done

# The C library's size, stripped (docs/EMBEDDING.md).
c-size:
	$(CARGO) build --locked --release -p vocc-capi
	mkdir -p target/tmp/c-size
	strip -o target/tmp/c-size/libvocc.so target/release/libvocc.so
	strip -g -o target/tmp/c-size/libvocc.a target/release/libvocc.a
	cc -std=c99 -O2 -Icapi/include examples/c/pvs.c target/release/libvocc.a -lm -lpthread -ldl \
		-s -Wl,--gc-sections -o target/tmp/c-size/pvs
	printf '#include <stdio.h>\nint main(void) { puts("hi"); return 0; }\n' > target/tmp/c-size/hello.c
	cc -O2 -s target/tmp/c-size/hello.c -o target/tmp/c-size/hello
	ls -l target/tmp/c-size/libvocc.so target/tmp/c-size/libvocc.a target/tmp/c-size/pvs target/tmp/c-size/hello
