#!/bin/sh
# Minimizes the fuzz corpora to what is committed (docs/FUZZING.md).
#
# Usage: fuzz/minimize.sh [TARGET...]   (default: every target)
# Input: fuzz/corpus/<target>/ as `fuzz/run.sh` grew it, and the seeds fuzz/seeds/<target>/.
# Output: fuzz/corpus/<target>/ replaced by the seeds plus a set cover of the edges they miss
# (libFuzzer `-set_cover_merge=1 -use_counters=0`: few files that reach every edge any file
# reaches; hit counts are not kept, which keeps the committed corpora under 1 MB). The old corpus goes to
# fuzz/corpus.full/<target>/ (ignored by git). Needs the targets built (`fuzz/run.sh` builds them).
set -eu
cd "$(dirname "$0")"
targets=${*:-store blob geojson cityjson obj walkable osm gpkg fgb shp citygml cityjsonseq dem hashes merge}
bin=target/$(rustc +nightly -vV | sed -n 's/^host: //p')/release
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_odr_violation=0"  # as in run.sh
for t in $targets; do
    rm -rf "corpus.full/$t" "corpus.min/$t"
    mkdir -p corpus.full "corpus.min/$t"
    mv "corpus/$t" "corpus.full/$t"
    # The seeds are kept whole (files already in the output stay); the rest adds what they miss.
    [ -d "seeds/$t" ] && cp "seeds/$t"/* "corpus.min/$t/"
    "$bin/$t" -set_cover_merge=1 -use_counters=0 -max_len=16384 -timeout=10 \
        "corpus.min/$t" "corpus.full/$t" >"corpus.min/$t.log" 2>&1
    mv "corpus.min/$t" "corpus/$t"
    echo "$t: $(ls "corpus/$t" | wc -l) files, $(du -sk --apparent-size "corpus/$t" | cut -f1) KiB"
done
rm -rf corpus.min
