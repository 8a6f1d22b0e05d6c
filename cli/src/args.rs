//! Argument types and parsers shared by the subcommands: the scene readers' options
//! ([`ReadArgs`]) and the value parsers of numeric options.
//!
//! Input: command-line strings. Output: typed values, or a message naming what was expected.
//! Invariant: every numeric option is parsed here, by one rule (finite numbers, ranges checked
//! at parse time), so a bad value is a usage error (exit status 2) whatever the option.

use clap::error::ErrorKind;
use clap::Args;

use vocc::bake::params::{Effort, Generator, Reach, Slices, MAX_CELL_SIZE_M, MIN_CELL_SIZE_M};
use vocc::bake::slice::MAX_SLICES;
use vocc::runtime::frame::MAX_VOS_PER_CELL;
use vocc::scene::{OnBadHeight, ReadOptions};

/// Options of the scene readers.
#[derive(Args, Clone, Debug)]
pub struct ReadArgs {
    /// Footprints (GeoJSON, GeoPackage, FlatGeobuf, Shapefile): attribute with the building
    /// height above its base, metres.
    #[arg(long, value_name = "NAME")]
    pub height_attr: Option<String>,
    /// Footprints: attribute with the base elevation, metres (default: base at 0).
    #[arg(long, value_name = "NAME")]
    pub base_attr: Option<String>,
    /// Footprints: attribute with the number of storeys, used when the height is missing.
    #[arg(long, value_name = "NAME")]
    pub levels_attr: Option<String>,
    /// Metres per storey for --levels-attr.
    #[arg(long, default_value_t = 3.0, value_name = "M", value_parser = parse_positive, allow_hyphen_values = true)]
    pub storey_height: f64,
    /// CityJSON, CityJSONSeq, CityGML: level of detail to read (default: the highest each
    /// object has).
    #[arg(long)]
    pub lod: Option<String>,
    /// Footprints and OpenStreetMap: a height, storey or base value that is not a number
    /// ("12.13 m" and "12,5" are numbers; "tall" is not) or beyond 1,000 m (a base beyond
    /// 10,000 m): `skip` tries the storey count, then --default-height, and otherwise skips the
    /// feature, counted with its reason; `error` stops the load there.
    #[arg(long, value_enum, default_value_t = OnBadHeightArg::Skip, value_name = "skip|error")]
    pub on_bad_height: OnBadHeightArg,
    /// Footprints and OpenStreetMap: height of a feature with no usable height or storey
    /// count, metres (the last fallback; default: such features are skipped).
    #[arg(long, value_name = "M", value_parser = parse_positive, allow_hyphen_values = true)]
    pub default_height: Option<f64>,
    /// CityJSON, CityJSONSeq: also read these city object types, besides Building and BuildingPart
    /// (comma-separated, as the file writes them: Bridge,OtherConstruction,+GenericCityObject).
    #[arg(long, value_delimiter = ',', value_name = "TYPE,...")]
    pub types: Vec<String>,
    /// Footprints: attribute with the height of the bottom above the base, metres (a part
    /// standing on others; OpenStreetMap's tag is the default, read where present).
    #[arg(long, value_name = "NAME", default_value = "min_height")]
    pub min_height_attr: String,
    /// Footprints: attribute with the storey the bottom starts at, when the bottom's height is
    /// missing.
    #[arg(long, value_name = "NAME", default_value = "building:min_level")]
    pub min_levels_attr: String,
    /// The metric CRS to project the scene into (EPSG:N). Default: the CRS the input states;
    /// longitude/latitude input (stated, or detected: every coordinate within range) goes to the
    /// UTM zone of its centre.
    #[arg(long, value_name = "EPSG:N")]
    pub crs: Option<String>,
    /// Terrain to read beside the scene: a GeoTIFF DEM (.tif, georeferenced, in the scene's CRS)
    /// or an OBJ mesh of the ground; may be given more than once. The terrain occludes, and a
    /// cell's eyes stand on it.
    #[arg(long, value_name = "FILE")]
    pub terrain: Vec<std::path::PathBuf>,
    /// Leave out the terrain the scene files hold (a CityJSON's TINRelief, read by default).
    #[arg(long)]
    pub no_terrain: bool,
}

/// A usage error found after parsing (a missing or conflicting argument that clap's
/// declarations cannot express), raised before anything is read; `main` prints it as clap
/// prints its own, with the command's usage, and exits with status 2.
#[derive(Debug)]
pub struct UsageError {
    /// The subcommand whose usage is shown.
    pub command: &'static str,
    pub kind: ErrorKind,
    pub message: String,
}

impl std::fmt::Display for UsageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for UsageError {}

/// A [`UsageError`] of `command`, as an `anyhow::Error`.
pub fn usage(
    command: &'static str,
    kind: ErrorKind,
    message: impl std::fmt::Display,
) -> anyhow::Error {
    anyhow::Error::new(UsageError {
        command,
        kind,
        message: message.to_string(),
    })
}

/// Checking a scene against the one a store was baked from (`pvs`, `eval`, `render`,
/// `inspect --list-cells`).
#[derive(Args, Clone, Copy, Debug)]
pub struct SceneCheckArgs {
    /// Go on when the scene is not the one the store was baked from (its object count,
    /// fingerprint or CRS differ), with a warning instead of an error. A PVS over another scene
    /// is not guaranteed: the store's VOs were certified against the blockers baked.
    #[arg(long)]
    pub allow_other_scene: bool,
}

/// `--on-bad-height`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum OnBadHeightArg {
    Skip,
    Error,
}

impl ReadArgs {
    pub fn options(&self) -> ReadOptions {
        ReadOptions {
            height_attr: self.height_attr.clone(),
            base_attr: self.base_attr.clone(),
            levels_attr: self.levels_attr.clone(),
            storey_height: self.storey_height,
            lod: self.lod.clone(),
            on_bad_height: match self.on_bad_height {
                OnBadHeightArg::Skip => OnBadHeight::Skip,
                OnBadHeightArg::Error => OnBadHeight::Error,
            },
            default_height: self.default_height,
            types: self.types.iter().map(|t| t.trim().to_string()).collect(),
            min_height_attr: Some(self.min_height_attr.clone()).filter(|s| !s.is_empty()),
            min_levels_attr: Some(self.min_levels_attr.clone()).filter(|s| !s.is_empty()),
            crs: self.crs.clone(),
            terrain: self.terrain.clone(),
            no_terrain: self.no_terrain,
        }
    }
}

/// `bake --shard`: shard I of N, or `auto` (the index from the job array's environment).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShardSpec {
    Fixed(u32, u32),
    Auto,
}

/// Parses `I/N` (0 <= I < N) or `auto`.
pub fn parse_shard(s: &str) -> Result<ShardSpec, String> {
    if s == "auto" {
        return Ok(ShardSpec::Auto);
    }
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| format!("expected I/N or auto, got {s:?}"))?;
    let num = |t: &str| t.trim().parse::<u32>().ok();
    match (num(i), num(n)) {
        (Some(i), Some(n)) if i < n => Ok(ShardSpec::Fixed(i, n)),
        (Some(i), Some(n)) => Err(format!(
            "the shard index {i} is not below the shard count {n} (shards are numbered 0 to N - 1)"
        )),
        _ => Err(format!("expected I/N with whole numbers, got {s:?}")),
    }
}

/// Parses a finite number (the one number rule of every option).
pub fn parse_num(t: &str) -> Result<f64, String> {
    t.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("{t:?} is not a finite number"))
}

/// Parses "X,Y".
pub fn parse_xy(s: &str) -> Result<(f64, f64), String> {
    let (x, y) = s
        .split_once(',')
        .ok_or_else(|| format!("expected X,Y, got {s:?}"))?;
    Ok((parse_num(x)?, parse_num(y)?))
}

/// Parses "LOW..HIGH".
pub fn parse_range(s: &str) -> Result<(f64, f64), String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("expected LOW..HIGH, got {s:?}"))?;
    Ok((parse_num(a)?, parse_num(b)?))
}

/// Parses `auto` or a slice count 1 to [`MAX_SLICES`].
pub fn parse_slices(s: &str) -> Result<Slices, String> {
    if s == "auto" {
        return Ok(Slices::Auto);
    }
    match s.parse::<u8>() {
        Ok(n) if n >= 1 && n as usize <= MAX_SLICES => Ok(Slices::Fixed(n)),
        _ => Err(format!("expected `auto` or 1 to {MAX_SLICES}, got {s:?}")),
    }
}

/// Parses `fast`, `default` or `tight`.
pub fn parse_effort(s: &str) -> Result<Effort, String> {
    s.parse()
}

/// Parses `long` or `growth`.
pub fn parse_generator(s: &str) -> Result<Generator, String> {
    s.parse()
}

/// Parses "X0,Y0,X1,Y1" with X0 <= X1 and Y0 <= Y1.
pub fn parse_rect(s: &str) -> Result<[f64; 4], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| parse_num(t).ok())
        .collect::<Option<Vec<f64>>>()
        .ok_or_else(|| format!("expected four numbers X0,Y0,X1,Y1, got {s:?}"))?;
    match v[..] {
        [x0, y0, x1, y1] if x0 <= x1 && y0 <= y1 => Ok([x0, y0, x1, y1]),
        _ => Err(format!(
            "expected X0,Y0,X1,Y1 with X0 <= X1 and Y0 <= Y1, got {s:?}"
        )),
    }
}

/// Parses a finite number greater than 0.
pub fn parse_positive(s: &str) -> Result<f64, String> {
    let v = parse_num(s)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("expected a number greater than 0, got {s:?}"))
    }
}

/// Parses a view cell size, metres ([`MIN_CELL_SIZE_M`] to [`MAX_CELL_SIZE_M`]).
pub fn parse_cell_size(s: &str) -> Result<f64, String> {
    let v = parse_num(s)?;
    if (MIN_CELL_SIZE_M..=MAX_CELL_SIZE_M).contains(&v) {
        Ok(v)
    } else {
        Err(format!(
            "expected a cell size of {MIN_CELL_SIZE_M} to {MAX_CELL_SIZE_M} metres, got {s:?}"
        ))
    }
}

/// Parses eye heights above the ground "LOW..HIGH" with 0 <= LOW <= HIGH.
pub fn parse_eye(s: &str) -> Result<(f64, f64), String> {
    let (lo, hi) = parse_range(s)?;
    if 0.0 <= lo && lo <= hi {
        Ok((lo, hi))
    } else {
        Err(format!(
            "expected eye heights LOW..HIGH with 0 <= LOW <= HIGH, got {s:?}"
        ))
    }
}

/// Parses a whole number in `lo..=hi`.
fn whole(s: &str, lo: u64, hi: u64) -> Result<u64, String> {
    match s.trim().parse::<u64>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        _ if hi == u64::MAX => Err(format!(
            "expected a whole number of at least {lo}, got {s:?}"
        )),
        _ => Err(format!(
            "expected a whole number from {lo} to {hi}, got {s:?}"
        )),
    }
}

/// Parses a count of at least 1.
pub fn parse_count(s: &str) -> Result<usize, String> {
    whole(s, 1, usize::MAX as u64).map(|v| v as usize)
}

/// Parses a count of at least 1, as u32.
pub fn parse_count_u32(s: &str) -> Result<u32, String> {
    whole(s, 1, u32::MAX as u64).map(|v| v as u32)
}

/// Parses `--max-vos`: 1 to [`MAX_VOS_PER_CELL`].
pub fn parse_max_vos(s: &str) -> Result<usize, String> {
    whole(s, 1, MAX_VOS_PER_CELL as u64).map(|v| v as usize)
}

/// Parses `bake --bytes-per-cell`: a number of bytes of at least 8 (a store's smallest record
/// with one VO), or `none` for no budget.
pub fn parse_bytes_per_cell(s: &str) -> Result<f64, String> {
    if s == "none" {
        return Ok(f64::INFINITY);
    }
    match s.parse::<f64>() {
        Ok(b) if b.is_finite() && b >= 8.0 => Ok(b),
        _ => Err(format!(
            "expected a number of bytes of at least 8, or `none`, got {s:?}"
        )),
    }
}

/// Parses `bake --reach`: `auto` (the default: from the scene, `vocc::bake::reach`), or metres
/// from [`MIN_REACH_M`](vocc::bake::params::MIN_REACH_M) to
/// [`MAX_REACH_M`](vocc::bake::params::MAX_REACH_M).
pub fn parse_reach(s: &str) -> Result<Reach, String> {
    use vocc::bake::params::{MAX_REACH_M, MIN_REACH_M};
    if s == "auto" {
        return Ok(Reach::Auto);
    }
    match s.parse::<f64>() {
        Ok(m) if (MIN_REACH_M..=MAX_REACH_M).contains(&m) => Ok(Reach::Metres(m)),
        _ => Err(format!(
            "expected `auto` or metres from {MIN_REACH_M} to {MAX_REACH_M}, got {s:?}"
        )),
    }
}

/// `bake --far-block`: the default's blocks (split where sparse), or one side for every block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FarBlock {
    Auto,
    /// Metres; 0: no far field.
    Metres(f64),
}

/// Parses `bake --far-block`: `auto`, `off` (or 0) for no far field, or metres from the least
/// cell size up to [`MAX_FAR_BLOCK_M`](vocc::bake::params::MAX_FAR_BLOCK_M) (rounded to whole
/// cells, at least one, by the bake).
pub fn parse_far_block(s: &str) -> Result<FarBlock, String> {
    use vocc::bake::params::MAX_FAR_BLOCK_M;
    match s {
        "auto" => return Ok(FarBlock::Auto),
        "off" => return Ok(FarBlock::Metres(0.0)),
        _ => {}
    }
    match s.parse::<f64>() {
        Ok(m) if m == 0.0 || (MIN_CELL_SIZE_M..=MAX_FAR_BLOCK_M).contains(&m) => {
            Ok(FarBlock::Metres(m))
        }
        _ => Err(format!(
            "expected `auto`, `off`, or metres from {MIN_CELL_SIZE_M} to {MAX_FAR_BLOCK_M}, got {s:?}"
        )),
    }
}

/// The most buildings `gen-city` writes: 10^7 take about 1.5 GB of memory and a 3 GB file.
pub const MAX_GEN_BUILDINGS: u64 = 10_000_000;

/// Parses `gen-city --buildings`: 1 to [`MAX_GEN_BUILDINGS`].
pub fn parse_buildings(s: &str) -> Result<usize, String> {
    whole(s, 1, MAX_GEN_BUILDINGS)
        .map(|v| v as usize)
        .map_err(|e| format!("{e} (10^7 buildings take about 1.5 GB of memory and a 3 GB file)"))
}
