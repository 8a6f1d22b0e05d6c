//! The `vocc` command line: a thin layer over the library (the command enum and dispatch; the
//! commands live in the modules below, the shared parsers in `args`, file handling in `files`).
//!
//! Input: command-line arguments. Output: reports on stdout, files where asked, errors on stderr
//! with a non-zero exit status. Invariant: no geometry here; every decision is the library's.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::error::ErrorKind;
use clap::{ArgGroup, Parser, Subcommand};

use vocc::scene;

use args::{
    parse_buildings, parse_cell_size, parse_eye, parse_generator, parse_num, parse_positive,
    parse_xy, usage, ReadArgs, SceneCheckArgs,
};
use files::write_atomically;
use vocc::bake::params::Generator;

mod args;
mod bake;
mod boxes;
mod debug_svg;
mod eval;
mod files;
mod info;
mod merge;
mod progress;
mod render;
mod report;
mod store;
mod view;

/// The exit status rule, shown by `--help`.
const EXIT_STATUS: &str = "Exit status:
  0  done
  1  the run failed: an input cannot be read or is refused, an output cannot be written, or the
     options do not fit the scene (a region outside the grid, a grid too large)
  2  the command line is wrong: an unknown option, a missing argument, or a value outside its
     option's range (checked before anything is read, printed with the command's usage)
  3  vocc eval: a false cull, or a ray from an eye reaching a stored VO unblocked
A closed output pipe (vocc ... | head) ends the run quietly with status 0.

Outputs: vocc creates the output it is asked for (a file, or eval --report's folder), never the
folders above it (a missing one is refused before any work), and writes it all or nothing. No
output may be one of the inputs. A store read with scene files (pvs, eval, render, inspect
--list-cells) must be given the scene it was baked from: another one is refused, naming what
differs (--allow-other-scene goes on with a warning).";

#[derive(Parser)]
#[command(
    name = "vocc",
    version,
    about = "Virtual occluders for city models",
    after_help = EXIT_STATUS,
    disable_help_subcommand = true
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Bake a scene into an occluder store: at most 10 virtual occluders per view cell.
    Bake(bake::BakeArgs),
    /// Describe a store (2.0 or 1.0), one cell's VOs with their stored fields, or every cell.
    Inspect(store::InspectArgs),
    /// Build the potentially visible set of one cell from a store and the scene's objects.
    ///
    /// The scene must be the one the store was baked from (same files, same reader flags): the
    /// store's scene section (object count, fingerprint, CRS) is checked, and another scene is
    /// refused naming what differs. A 1.0 store records no scene: a note says the check could
    /// not be made.
    #[command(group(ArgGroup::new("which").required(true).args(["cell", "at", "all_cells"])))]
    Pvs {
        /// Store file.
        store: PathBuf,
        /// Scene files (the occludees: each object's bounding box).
        #[arg(required = true)]
        scene: Vec<PathBuf>,
        #[command(flatten)]
        read: ReadArgs,
        #[command(flatten)]
        check: SceneCheckArgs,
        /// The cell, by id.
        #[arg(long, value_name = "ID")]
        cell: Option<u32>,
        /// The cell holding this world position X,Y.
        #[arg(long, value_name = "X,Y", value_parser = parse_xy, allow_hyphen_values = true)]
        at: Option<(f64, f64)>,
        /// Every cell of the store, one line each in cell order (the scene is read once).
        #[arg(long)]
        all_cells: bool,
        /// Print {"cell": ID, "objects": N, "pvs": [input feature numbers, ascending]}: the
        /// GeoJSON feature index (CityJSON city object, OBJ group), counted across the files in
        /// order with skipped ones included, as `vocc info` numbers them.
        #[arg(long)]
        json: bool,
    },
    /// Write a scene's object boxes, with their ids, as the text file the C example reads.
    ///
    /// One line per object: `ID XMIN YMIN ZMIN XMAX YMAX ZMAX`, world coordinates, ID the input
    /// feature number (the number `vocc pvs` and `vocc info` give), after two `#` lines: the
    /// format, and the scene (`# scene FINGERPRINT objects N crs "NAME"`) for checking against
    /// a store. The boxes are the very numbers `vocc pvs` culls (shortest round-trip form).
    #[command(after_help = "Examples:
  vocc boxes data/lyon1/buildings_lyon1.geojson --height-attr HAUTEUR -o lyon.boxes
  vocc boxes data/helsinki/Helsinki.osm.pbf --default-height 9 -o helsinki.boxes")]
    Boxes {
        /// Scene files, with the reader flags of the bake.
        #[arg(required = true)]
        scene: Vec<PathBuf>,
        #[command(flatten)]
        read: ReadArgs,
        /// Output box file.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Export one cell's VOs: as JSON (world coordinates), as OBJ quads, or as a per-cell blob.
    #[command(group(ArgGroup::new("format").required(true).args(["json", "obj", "blob"])))]
    Export {
        /// Store file.
        store: PathBuf,
        /// The cell.
        #[arg(long, value_name = "ID")]
        cell: u32,
        /// Print the VOs as JSON on stdout.
        #[arg(long, conflicts_with_all = ["obj", "blob"])]
        json: bool,
        /// Write the VO quads as an OBJ file.
        #[arg(long, value_name = "FILE", conflicts_with = "blob")]
        obj: Option<PathBuf>,
        /// Write the cell's self-contained blob, format 2.0 (and FILE.frame, the frame it
        /// decodes with).
        #[arg(long, value_name = "FILE")]
        blob: Option<PathBuf>,
    },
    /// Write (or serve) a page that shows the city in 3D, the cells, a cell's VOs and its PVS.
    View(view::ViewArgs),
    /// Load scene files and report objects, blockers, convex pieces, repairs and timings.
    Info {
        /// Scene files: GeoJSON, GeoPackage, FlatGeobuf or Shapefile footprints, OpenStreetMap PBF,
        /// CityJSON (0.3 to 0.9, 1.0, 1.1, 2.0), CityJSONSeq, CityGML 2.0, or OBJ (README, "What goes
        /// in").
        #[arg(required = true)]
        scene: Vec<PathBuf>,
        #[command(flatten)]
        read: ReadArgs,
        /// Print the full report as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Draw one cell as an SVG: its VOs and what they cull, or (--debug) its 2D growth.
    ///
    /// `vocc render STORE SCENE... --cell ID -o cell.svg` draws the cell, its VOs and the
    /// buildings, coloured visible, culled thanks to fusion, or culled by single buildings alone
    /// (like the paper's Fig. 8). `vocc render --debug SCENE... --at X,Y -o cell.svg` draws what
    /// the long generator does for that cell of the bake's grid (the hidden map, proposals,
    /// certified pieces, stored and picked VOs); with `--generator growth`, the 2D growth of one
    /// slice (blockers, seeds, supporting and separating lines, the dense VOs).
    #[command(after_help = "Examples:
  vocc render city.vocc city.geojson --height-attr height --cell 57 -o cell57.svg
  vocc render city.vocc city.geojson --height-attr height --at 1842000,5176050 --radius 400 -o cell.svg
  vocc render --debug city.geojson --height-attr height --at 1842000,5176050 -o long.svg
  vocc render --debug city.geojson --height-attr height --at 1842000,5176050 --generator growth -o growth.svg")]
    Render {
        /// Draw what a generator does for one cell instead (scene files only; the bake's grid).
        #[arg(long)]
        debug: bool,
        /// --debug: the generator drawn: `long` (the default, as `vocc bake`: hidden map,
        /// proposals, certified pieces, stored and picked VOs) or `growth` (one slice's growth).
        #[arg(long, default_value = "long", value_parser = parse_generator)]
        generator: Generator,
        /// --debug: eye heights above the ground, metres, as `vocc bake --eye`.
        #[arg(long, default_value = "1.5..2.0", value_parser = parse_eye, value_name = "LOW..HIGH", allow_hyphen_values = true)]
        eye: (f64, f64),
        /// --debug: how far past the cell's sides its VOs are sought, `auto` or metres, as `vocc
        /// bake --reach`.
        #[arg(long, default_value = "auto", value_parser = args::parse_reach, value_name = "auto|M")]
        reach: vocc::bake::params::Reach,
        /// STORE then scene files; with --debug, scene files only.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// The cell, by id (store mode).
        #[arg(long, value_name = "ID")]
        cell: Option<u32>,
        /// A point of the cell, in world coordinates: X,Y.
        #[arg(long, value_name = "X,Y", value_parser = parse_xy, allow_hyphen_values = true)]
        at: Option<(f64, f64)>,
        /// --debug: side of the square cells, metres (the bake's grid for that size).
        #[arg(long, default_value_t = 100.0, value_name = "M", value_parser = parse_cell_size, allow_hyphen_values = true)]
        cell_size: f64,
        /// --debug with `--generator growth`: slice height in world metres (default: half the
        /// median building height).
        #[arg(long, value_name = "Z", value_parser = parse_num, allow_hyphen_values = true)]
        slice: Option<f64>,
        /// Store mode: metres shown around the cell's centre.
        #[arg(long, default_value_t = 500.0, value_name = "M", value_parser = parse_positive, allow_hyphen_values = true)]
        radius: f64,
        #[command(flatten)]
        read: ReadArgs,
        #[command(flatten)]
        check: SceneCheckArgs,
        /// Output SVG file.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Join the shards of one bake (`bake --shard I/N`) into the store a single bake writes.
    ///
    /// Shards recording another frame, scene or set of options are refused.
    Merge {
        /// Shard store files.
        #[arg(required = true)]
        shards: Vec<PathBuf>,
        /// Output store file.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Evaluate a store against the ray-sampled ground truth (exit status 3 on a false cull).
    ///
    /// Reports false culls (there must be none), PVS/VS, the share of objects culled, occlusion
    /// against the number of VOs, and the culler's time per cell entry.
    Eval(eval::EvalArgs),
    /// Regenerate docs/RESULTS.md and its plots from the bundled data (what `make eval` runs).
    Results(eval::ResultsArgs),
    /// Print this help, or one command's (`vocc help bake`).
    Help {
        /// The command.
        command: Option<String>,
    },
    /// Write a deterministic procedural city (GeoJSON footprints, attribute `height`).
    GenCity {
        /// Number of buildings.
        #[arg(long, value_parser = parse_buildings)]
        buildings: usize,
        /// Random seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output GeoJSON file.
        #[arg(short, long)]
        output: PathBuf,
    },
}

fn main() {
    let raw: Vec<std::ffi::OsString> = std::env::args_os().collect();
    let cli = Cli::parse_from(&raw);
    deprecated_spellings(&raw);
    let code = match run(cli) {
        Ok(code) => code,
        Err(e) if broken_pipe(&e) => 0,
        Err(e) => match e.downcast::<args::UsageError>() {
            // A usage error found after parsing: clap's form and status (2).
            Ok(u) => usage_error(&u).exit(),
            Err(e) => {
                eprintln!("error: {e:#}");
                1
            }
        },
    };
    std::process::exit(code);
}

/// A usage error found after a command started ([`args::UsageError`]) as clap prints its
/// own: the message and the command's usage, exit status 2.
fn usage_error(u: &args::UsageError) -> clap::Error {
    use clap::CommandFactory;
    let mut cli = Cli::command();
    cli.build();
    match cli.find_subcommand_mut(u.command) {
        Some(c) => c.error(u.kind, &u.message),
        None => cli.error(u.kind, &u.message),
    }
}

/// The old spellings of renamed options still work; each use gets a note on stderr.
fn deprecated_spellings(raw: &[std::ffi::OsString]) {
    let args: Vec<&str> = raw.iter().skip(1).filter_map(|a| a.to_str()).collect();
    let Some(command) = args.iter().find(|a| !a.starts_with('-')) else {
        return;
    };
    let new = match *command {
        "bake" => "--walkable FILE",
        "eval" => "--sample N",
        "inspect" => "--list-cells",
        _ => return,
    };
    let end = args.iter().position(|a| *a == "--").unwrap_or(args.len());
    if args[..end]
        .iter()
        .any(|a| *a == "--cells" || a.starts_with("--cells="))
    {
        eprintln!(
            "note: `vocc {command} --cells` is deprecated (the name meant another thing in each command); use {new}"
        );
    }
}

/// Whether the error is a write into a closed pipe (`vocc ... | head`): Unix tools stop quietly.
fn broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            || c.downcast_ref::<serde_json::Error>()
                .is_some_and(|j| j.io_error_kind() == Some(std::io::ErrorKind::BrokenPipe))
    })
}

/// `vocc help [COMMAND]`.
fn help(command: Option<&str>) -> Result<()> {
    use clap::CommandFactory;
    let mut cli = Cli::command();
    match command {
        None => cli.print_help()?,
        Some(name) => match cli.find_subcommand_mut(name) {
            Some(c) => c.print_long_help()?,
            None => {
                return Err(usage(
                    "help",
                    ErrorKind::InvalidSubcommand,
                    format!("no command {name:?}; `vocc help` lists them"),
                ))
            }
        },
    }
    Ok(())
}

/// Runs one command; the exit status on success (see [`EXIT_STATUS`]).
fn run(cli: Cli) -> Result<i32> {
    let done: Result<()> = match cli.command {
        Command::Eval(a) => return eval::eval(a),
        Command::Help { command } => help(command.as_deref()),
        Command::Bake(a) => bake::run(a),
        Command::Inspect(a) => store::inspect(a),
        Command::Pvs {
            store,
            scene,
            read,
            check,
            cell,
            at,
            all_cells,
            json,
        } => {
            let cells = match all_cells {
                true => store::Cells::All,
                false => store::Cells::One(cell, at),
            };
            store::pvs(store, scene, &read, &check, cells, json)
        }
        Command::Boxes {
            scene,
            read,
            output,
        } => boxes::boxes(&scene, &read, &output),
        Command::Export {
            store,
            cell,
            json,
            obj,
            blob,
        } => {
            // clap requires exactly one of the three.
            let to = match (json, obj, blob) {
                (_, Some(f), _) => store::ExportTo::Obj(f),
                (_, None, Some(f)) => store::ExportTo::Blob(f),
                _ => store::ExportTo::Json,
            };
            store::export(store, cell, to)
        }
        Command::View(a) => view::run(a),
        Command::Info { scene, read, json } => info::info(&scene, &read, json),
        Command::Render {
            debug,
            generator,
            eye,
            reach,
            files,
            cell,
            at,
            cell_size,
            slice,
            radius,
            read,
            check,
            output,
        } => {
            if debug {
                let Some(at) = at else {
                    return Err(usage(
                        "render",
                        ErrorKind::MissingRequiredArgument,
                        "--debug needs --at X,Y (the cell is the one holding that point)",
                    ));
                };
                if cell.is_some() {
                    return Err(usage(
                        "render",
                        ErrorKind::ArgumentConflict,
                        "--debug takes --at X,Y, not --cell (it bakes no store)",
                    ));
                }
                render::render_debug(
                    &files, &read, at, cell_size, eye, reach, generator, slice, &output,
                )
            } else {
                if files.len() < 2 {
                    return Err(usage(
                        "render",
                        ErrorKind::MissingRequiredArgument,
                        "give the store, then the scene files it was baked from (or --debug with scene files alone)",
                    ));
                }
                if cell.is_none() == at.is_none() {
                    return Err(usage(
                        "render",
                        if cell.is_none() {
                            ErrorKind::MissingRequiredArgument
                        } else {
                            ErrorKind::ArgumentConflict
                        },
                        "give one of --cell ID, --at X,Y",
                    ));
                }
                render::render_store(files, &read, &check, cell, at, radius, &output)
            }
        }
        Command::Merge { shards, output } => merge::merge(shards, &output),
        Command::Results(a) => eval::results(a),
        Command::GenCity {
            buildings,
            seed,
            output,
        } => {
            files::check_output(&output, &[])?;
            let t = Instant::now();
            let city = scene::gencity::generate(&scene::gencity::CityParams { buildings, seed });
            write_atomically(&output, |w| scene::gencity::write_geojson(w, &city))?;
            eprintln!(
                "wrote {} buildings to {} in {:.2} s",
                city.len(),
                output.display(),
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
    };
    done.map(|()| 0)
}
