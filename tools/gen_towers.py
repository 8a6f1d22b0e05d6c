#!/usr/bin/env python3
"""Writes a district of free-standing towers as GeoJSON (EPSG:32654, attribute `height`): a
stand-in for issue 31's held-out "district of towers" (999 objects over 3.9 x 3.4 km, heights
2 to 541 m, median 111 m, 69% of the scene hidden from the median cell), which the repo does not
have. Standard library only, deterministic for a seed.

The towers stand on a street grid of 120 x 110 m blocks, one a block (jittered by up to 20 m,
the blocks shuffled; once every block holds one, a second beside it), 88% of them towers with
heights 111 m e^N(0, 0.55) within 2..541 m, the rest low buildings of 2 to 20 m; one is 541 m
and one 2 m. A tower's footprint is a square of half-side HALF_MIN..HALF_MAX m (stretched 0.7 to
1.3 times along x), a low building's 5..20 m; 30% are turned by up to 0.3 rad. With the default
13..20 m the district's mean visible set is 283 of 999 objects (72% hidden), close to the held-out
district's; 10..16 m sees more (414), 18..30 m less (139).

Usage: python3 tools/gen_towers.py [--seed N] [--half MIN,MAX] > towers.geojson
Measured with it: README, "How far a cell reaches" (the reach `--reach auto` picks).
"""
import argparse
import json
import math
import random


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--half", default="13,20", help="a tower's half-side, MIN,MAX metres")
    a = ap.parse_args()
    half_min, half_max = (float(v) for v in a.half.split(","))
    rng = random.Random(a.seed)
    width, depth = 3900.0, 3400.0
    x0, y0 = 380000.0, 3940000.0
    bx, by = 120.0, 110.0
    plots = [(i, j) for i in range(int(width // bx)) for j in range(int(depth // by))]
    rng.shuffle(plots)
    heights = []
    while len(heights) < 999:
        if rng.random() < 0.12:
            heights.append(rng.uniform(2, 20))
        else:
            h = 111 * math.exp(rng.gauss(0, 0.55))
            if 2 <= h <= 541:
                heights.append(h)
    heights[0], heights[1] = 541.0, 2.0
    feats = []
    for k, h in enumerate(heights):
        i, j = plots[k % len(plots)]
        cx = x0 + (i + 0.5) * bx + rng.uniform(-20, 20)
        cy = y0 + (j + 0.5) * by + rng.uniform(-20, 20)
        if k >= len(plots):
            cx, cy = cx + 45, cy + 40
        s = rng.uniform(half_min, half_max) if h > 20 else rng.uniform(5, 20)
        turn = rng.uniform(-0.3, 0.3) if rng.random() < 0.3 else 0.0
        w2, d2 = s * rng.uniform(0.7, 1.3), s
        c, n = math.cos(turn), math.sin(turn)
        ring = [
            [round(cx + u * c - v * n, 3), round(cy + u * n + v * c, 3)]
            for (u, v) in [(-w2, -d2), (w2, -d2), (w2, d2), (-w2, d2), (-w2, -d2)]
        ]
        feats.append({
            "type": "Feature",
            "properties": {"id": f"t{k}", "height": round(h, 1)},
            "geometry": {"type": "Polygon", "coordinates": [ring]},
        })
    print(json.dumps({
        "type": "FeatureCollection",
        "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32654"}},
        "features": feats,
    }))


if __name__ == "__main__":
    main()
