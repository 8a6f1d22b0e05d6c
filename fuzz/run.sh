#!/bin/sh
# Runs the fuzz targets one after the other (docs/FUZZING.md).
#
# Usage: fuzz/run.sh [SECONDS] [TARGET...]   (default: 600 s each, every target)
# Input: the committed corpora fuzz/corpus/<target>/ (new finds are added there) and, when
# present, the seeds fuzz/seeds/<target>/ (fuzz/seeds.py). Output: per target, libFuzzer's log in
# fuzz/logs/<target>.log with its final statistics, and any crash, timeout or OOM input in
# fuzz/artifacts/<target>/. Needs the nightly toolchain and cargo-fuzz. Exit status: 1 when any
# target found something. One target at a time, one job: the figures are per core.
set -u
cd "$(dirname "$0")"
secs=${1:-600}
[ $# -gt 0 ] && shift
targets=${*:-store blob geojson cityjson obj walkable osm gpkg fgb shp citygml cityjsonseq dem hashes merge}
cargo +nightly fuzz build || exit 2
bin=target/$(rustc +nightly -vV | sed -n 's/^host: //p')/release
mkdir -p logs
# The bundled SQLite (libsqlite3-sys, for GeoPackage) trips AddressSanitizer's one-definition-rule
# check at start-up (a global of sqlite3.c seen twice); that check is off, the rest of ASan is on.
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_odr_violation=0"
status=0
for t in $targets; do
    mkdir -p "corpus/$t" "artifacts/$t"
    seeds=""
    [ -d "seeds/$t" ] && seeds="seeds/$t"
    # -timeout: an input that takes 10 s is a finding; -max_len: room for larger scenes than the
    # largest seed (libFuzzer's default); the store and blob targets keep the default.
    case $t in gpkg) len="-max_len=65536" ;; geojson | cityjson | obj | walkable | osm | fgb | shp | citygml | cityjsonseq | dem) len="-max_len=16384" ;; *) len="" ;; esac
    echo "== $t: $secs s"
    # shellcheck disable=SC2086
    "$bin/$t" "corpus/$t" $seeds -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 \
        $len -print_final_stats=1 -artifact_prefix="artifacts/$t/" >"logs/$t.log" 2>&1 || status=1
    grep -E '^#[0-9]+.*DONE|^stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb)|^SUMMARY|^==[0-9]+== ?ERROR|panicked' "logs/$t.log"
    echo "corpus/$t: $(ls "corpus/$t" | wc -l) files"
done
exit $status
