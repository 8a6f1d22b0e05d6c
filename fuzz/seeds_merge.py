#!/usr/bin/env python3
"""Seeds of the `hashes` and `merge` fuzz targets (docs/FUZZING.md), deterministic.

Input: the store seeds fuzz/seeds/store/doc-* (FORMAT.md's worked examples, 1.0 and 2.0) and
gencity-40m-* (small bakes). Output: fuzz/seeds/hashes/ (`.hashes` files: version 2 shards and
whole bakes, version 1, no cells, and the shard index at the count that made `vocc merge` panic)
and fuzz/seeds/merge/ (inputs as `vocc::fuzzing::merge_shards` splits them: a count byte, then per
shard a u16 length and a store, a u16 length and its hashes): one store as shard 0 of 1, one store
as both shards of 2 (equal records merge), a missing shard, a repeated one, a whole bake given as
a shard, hashes of another store. Standard library only; rerunning gives the same bytes.
"""
import glob
import hashlib
import os
import struct
import zlib

ROOT = os.path.dirname(os.path.abspath(__file__))


def hashes(cells, store_crc, global_hash, shard=None, version=2):
    b = b"VOCCHASH" + struct.pack("<HHIIQ", version, 0, len(cells), store_crc, global_hash)
    if version == 2:
        i, n = shard if shard else (0, 0)
        b += struct.pack("<II", i, n)
    for c in cells:
        b += struct.pack("<Q", c)
    return b + struct.pack("<I", zlib.crc32(b))


def cell_count(store):
    nx, ny = struct.unpack_from("<II", store, 16 + 48)
    return nx * ny


def merge_input(shards):
    out = bytes([len(shards) - 1])
    for s, h in shards:
        for part in (s, h):
            out += struct.pack("<H", len(part)) + part
    return out


def write(target, name, data):
    d = os.path.join(ROOT, "seeds", target)
    os.makedirs(d, exist_ok=True)
    tag = hashlib.sha1(data).hexdigest()[:12]
    with open(os.path.join(d, f"{name}-{tag}"), "wb") as f:
        f.write(data)


def main():
    stores = [
        open(p, "rb").read()
        for p in sorted(glob.glob(os.path.join(ROOT, "seeds/store/doc-*")))
        + sorted(glob.glob(os.path.join(ROOT, "seeds/store/gencity-40m-*")))
    ]
    small = [s for s in stores if len(s) < 6000]
    for k, s in enumerate(small):
        n = cell_count(s)
        crc = zlib.crc32(s)
        cells = [(0x9E3779B97F4A7C15 * (i + 1 + k)) % (1 << 64) or 1 for i in range(n)]
        write("hashes", "shard", hashes(cells, crc, 7 + k, (0, 2)))
        write("hashes", "whole", hashes(cells, crc, 7 + k))
        write("hashes", "v1", hashes(cells, crc, 7 + k, version=1))
        one = hashes(cells, crc, 7 + k, (0, 1))
        write("merge", "one-of-one", merge_input([(s, one)]))
        half = [c if i % 2 == 0 else 0 for i, c in enumerate(cells)]
        other = [c if i % 2 == 1 else 0 for i, c in enumerate(cells)]
        a = hashes(half, crc, 7 + k, (0, 2))
        b = hashes(other, crc, 7 + k, (1, 2))
        write("merge", "two-of-two", merge_input([(s, a), (s, b)]))
        write("merge", "missing", merge_input([(s, a)]))
        write("merge", "repeated", merge_input([(s, a), (s, a)]))
        write("merge", "whole", merge_input([(s, hashes(cells, crc, 7 + k))]))
        write("merge", "other-store", merge_input([(s, hashes(cells, crc ^ 1, 7 + k, (0, 1)))]))
    write("hashes", "empty", hashes([], 0, 0))
    # Issue 34: shard 3 of 2 decoded, and `vocc merge` panicked indexing the shards it had seen.
    write("hashes", "shard-3-of-2", hashes([], 0, 0, (3, 2)))
    write("hashes", "shard-2-of-2", hashes([], 0, 0, (2, 2)))


if __name__ == "__main__":
    main()
