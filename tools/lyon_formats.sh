#!/bin/sh
# Writes Lyon (data/lyon1/buildings_lyon1.geojson, EPSG:3946) in the other formats vocc reads,
# for tests/formats.rs: GeoPackage, FlatGeobuf (no spatial index, so features keep the file's
# order), Shapefile (.shp, .shx, .dbf, .prj, .cpg) and RFC 7946 GeoJSON in longitude/latitude
# (EPSG:4326, no `crs` member, 7 decimals: what most exports give). Only the columns vocc's
# examples read are kept (ID, HAUTEUR, Z_MIN_SOL, Z_MAX_TOIT). Needs GDAL's ogr2ogr (3.6.2 was
# used: `apt-get install gdal-bin`); vocc's build and tests do not.
set -eu
cd "$(dirname "$0")/../data/lyon1"
src=buildings_lyon1.geojson
cols=ID,HAUTEUR,Z_MIN_SOL,Z_MAX_TOIT
rm -f buildings_lyon1.gpkg buildings_lyon1.fgb buildings_lyon1.shp buildings_lyon1.shx \
    buildings_lyon1.dbf buildings_lyon1.prj buildings_lyon1.cpg buildings_lyon1_lonlat.geojson
ogr2ogr -f GPKG -select $cols -nln buildings_lyon1 buildings_lyon1.gpkg $src
ogr2ogr -f FlatGeobuf -select $cols -lco SPATIAL_INDEX=NO buildings_lyon1.fgb $src
ogr2ogr -f "ESRI Shapefile" -select $cols buildings_lyon1.shp $src
ogr2ogr -f GeoJSON -select $cols -t_srs EPSG:4326 -lco RFC7946=YES buildings_lyon1_lonlat.geojson $src
