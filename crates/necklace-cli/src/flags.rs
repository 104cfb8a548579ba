//! The command line: clap's description of every command and flag, and their
//! translation into library options. No behaviour lives here.

use std::path::PathBuf;

use clap::{Parser, Subcommand};
use necklace::loops::LoopOptions;
use necklace::morse::{MorseOptions, Preconditioner, Schedule, SolverOptions};
use necklace::pipeline::{InputOptions, NeckOptions};
use necklace::simplify::SimplifyOptions;
use necklace::volume::{Mesher, VolumeOptions};

#[derive(Parser)]
#[command(
    name = "necklace",
    version,
    about = "Neck loops (handles and tunnels) of closed triangle meshes"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
    /// No progress bars.
    #[arg(short, long, global = true)]
    pub quiet: bool,
    /// Print seconds per stage and side to stderr.
    #[arg(short, long, global = true)]
    pub verbose: bool,
}

#[derive(Subcommand)]
pub enum Command {
    /// Print counts, the validity report and the genus per component of a mesh
    /// (OBJ, OFF, PLY or STL).
    Info {
        /// The mesh file.
        mesh: PathBuf,
        #[command(flatten)]
        input: InputArgs,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Mesh the volume inside a surface (or, with --exterior, the shell between it and a
    /// bounding sphere) into tetrahedra.
    Volume {
        /// The closed surface mesh.
        mesh: PathBuf,
        /// Mesh the outside shell instead of the inside.
        #[arg(long)]
        exterior: bool,
        #[command(flatten)]
        input: InputArgs,
        /// Lattice spacing along the surface (default: bounding-box diagonal / 64).
        #[arg(long, allow_negative_numbers = true)]
        h: Option<f64>,
        /// Memory budget (bytes, or with K, M, G or T: 8G is 8e9 bytes): thin parts
        /// are not refined past it, and a mesh estimated over it is refused before it
        /// is built.
        #[arg(long, default_value = "8G", value_parser = parse_memory, allow_negative_numbers = true)]
        max_memory: u64,
        /// On a side whose topology the surface does not predict (it crosses itself, or
        /// a component has no genus), no cell finer than this fraction of h is asked
        /// for (0 turns the bound off); a warning says when it binds.
        #[arg(long, default_value_t = 0.25, allow_negative_numbers = true)]
        unchecked_min_cell: f64,
        /// The volume mesher: necklace's isosurface stuffing, the Delaunay
        /// tetrahedralization of points sampled on the surface (`sampled`, experimental),
        /// restricted Delaunay refinement from those points (`refined`, experimental), or
        /// TetGen "pq1.2" (needs a build with --features tetgen, which is AGPL-3.0).
        #[arg(long, value_enum, default_value = "stuffing")]
        mesher: MesherArg,
        /// Output tet mesh (.vtu, .mesh, .node or .msh).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Find the critical points of the smoothed distance field inside a surface (or,
    /// with --exterior, in the shell around it) and the 2-saddles that mark necks.
    Critical {
        /// The closed surface mesh.
        mesh: PathBuf,
        /// Work in the outside shell (tunnels) instead of the inside (handles).
        #[arg(long)]
        exterior: bool,
        #[command(flatten)]
        method: MethodArgs,
        /// Write the critical points at step N (with type, selected, persistence and
        /// colours) as a PLY point cloud.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Write the interactive page (view.html) of an existing run's folder: the surface,
    /// its loops and saddles to turn round, a table of the loops, the barcode.
    View {
        /// The folder `necklace loops MESH -o DIR` wrote (its loops.json is read).
        dir: PathBuf,
        /// The mesh (default: the file loops.json names as its input).
        #[arg(long)]
        mesh: Option<PathBuf>,
    },
    /// Cut a surface along its neck loops into parts: the surface with the loops as
    /// edges and a segment label per face (PLY), and a table of the segments (area,
    /// volume with the loops capped, Euler characteristic, boundaries, genus, bounding
    /// loops). Separating loops split parts off; cycle-closing loops cut a handle open.
    Segment {
        /// The closed surface mesh.
        mesh: PathBuf,
        /// The loops to cut along, from `necklace loops MESH -o DIR` (DIR/loops.json, or
        /// `--json` output); without it, the loops are found first (default options).
        #[arg(long)]
        loops: Option<PathBuf>,
        /// Cut only along these loops (their indices in loops.json); repeat for several.
        /// Default: every loop.
        #[arg(long = "loop", value_name = "INDEX")]
        chosen: Vec<usize>,
        /// Without --loops: find handle loops only.
        #[arg(long)]
        handles: bool,
        /// Without --loops: find tunnel loops only.
        #[arg(long)]
        tunnels: bool,
        /// The segmented surface, as PLY with the face property `segment`.
        #[arg(short, long)]
        output: PathBuf,
        /// Print `{"segments": [...]}` instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Find the neck loops of a closed surface: handles (around narrow parts of the
    /// solid) and tunnels (around narrow parts of the space around it); both unless one
    /// is asked for.
    Loops {
        /// The closed surface mesh.
        mesh: PathBuf,
        #[command(flatten)]
        neck: NeckArgs,
        /// Write loops.obj, loops.ply, loops.json and critical.ply into this folder.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Also write view.png (a picture of the surface and its loops) into the folder.
        #[arg(long, requires = "output")]
        png: bool,
        /// Also write view.html (an interactive page: turn the shape, click a loop) into
        /// the folder.
        #[arg(long, requires = "output")]
        html: bool,
        /// Also write field.vtu (volume meshes with the smoothed field) into the folder.
        #[arg(long, requires = "output")]
        volume: bool,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Find the neck loops of many meshes (files, folders searched recursively, @LIST
    /// files of paths), each in its own worker process with a time and memory limit,
    /// one JSON line per mesh appended to the runs file; a rerun skips the meshes
    /// already done.
    Batch {
        /// Mesh files, folders, or @LIST (a file of paths, one per line).
        #[arg(required = true)]
        inputs: Vec<String>,
        /// The runs file (JSON lines), appended to and resumed from.
        #[arg(short, long)]
        output: PathBuf,
        /// Meshes run at the same time (default: the cores; each worker then gets the
        /// cores over the jobs as threads).
        #[arg(long, allow_negative_numbers = true)]
        jobs: Option<usize>,
        /// Seconds a mesh may take; a worker over it is stopped and its row says
        /// `timeout`.
        #[arg(long, allow_negative_numbers = true)]
        timeout: Option<f64>,
        /// Write each mesh's run folder (loops.json, loops.ply, ...) under this folder.
        #[arg(long)]
        save_runs: Option<PathBuf>,
        /// Run again the meshes whose row is not `ok`.
        #[arg(long)]
        retry_failed: bool,
        #[command(flatten)]
        neck: NeckArgs,
    },
    /// One mesh of a batch (run by `batch` in a worker process): prints its row.
    #[command(hide = true)]
    BatchWorker {
        mesh: PathBuf,
        /// The options, as JSON.
        #[arg(long)]
        options: String,
        /// Write the run's folder here.
        #[arg(long)]
        save_run: Option<PathBuf>,
    },
    /// Remove handles and tunnels along their neck loops:
    /// a handle is cut through along a thin band round its loop, a tunnel's hole plugged,
    /// each opening closed by faired caps; loops shortest first, each operation checked
    /// (a valid solid, the genus one lower, no crossings) or skipped with its reason.
    Repair {
        /// The closed surface mesh.
        mesh: PathBuf,
        /// The repaired surface (.obj, .off or .ply).
        #[arg(short, long)]
        output: PathBuf,
        /// Remove classes until the surface has this genus (default 0).
        #[arg(long, conflicts_with = "max_length", allow_negative_numbers = true)]
        genus: Option<usize>,
        /// Remove every loop shorter than this instead (noise), whatever genus results.
        #[arg(long, allow_negative_numbers = true)]
        max_length: Option<f64>,
        /// Only cut handles, or only plug tunnels.
        #[arg(long, value_enum)]
        only: Option<OnlyArg>,
        /// Each side of the band a cut removes lies this fraction of the loop's radius
        /// from it.
        #[arg(long, default_value_t = 0.15, allow_negative_numbers = true)]
        band: f64,
        /// Draw the input and the output side by side, the removed loops marked, into
        /// DIR/repair.png.
        #[arg(long, value_name = "DIR")]
        png: Option<PathBuf>,
        #[command(flatten)]
        method: MethodArgs,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Draw a mesh with loops and saddles from several directions into a PNG.
    Render {
        /// The surface mesh.
        mesh: PathBuf,
        /// loops.json written by `necklace loops -o DIR`.
        #[arg(long)]
        loops: Option<PathBuf>,
        /// Saddles to draw as dots: the JSON of `necklace critical --json`, or a loops.json.
        #[arg(long)]
        critical: Option<PathBuf>,
        /// Output picture (.png).
        #[arg(short, long)]
        output: PathBuf,
        /// Width in pixels.
        #[arg(long, default_value_t = 1200, allow_negative_numbers = true)]
        size: u32,
        /// Number of views: three-quarter, front, side, top (1 to 4).
        #[arg(long, default_value_t = 4, allow_negative_numbers = true)]
        views: usize,
        /// Opacity of the surface over loops and saddles behind it (0 to 1).
        #[arg(long, default_value_t = 0.7, allow_negative_numbers = true)]
        opacity: f64,
    },
    /// Run the whole method on built-in shapes (a chain of balls, a varying torus, a
    /// genus-3 pretzel): tables, loops and pictures; no input file needed.
    Demo {
        /// Folder for the results (one subfolder per shape).
        #[arg(short, long, default_value = "necklace-demo")]
        output: PathBuf,
    },
    /// Time every mesh of a folder in both modes (stages named as in the paper's
    /// Table 1), then a series over the lattice spacing h on one model.
    Bench {
        /// Folder of meshes (.obj, .off, .ply, .stl).
        dir: PathBuf,
        /// Also write the table as CSV; the h series goes beside it as
        /// NAME-scaling.csv and NAME-scaling.png.
        #[arg(long)]
        csv: Option<PathBuf>,
        /// Model of the h series (part of its file name; default bunny, else the first).
        #[arg(long)]
        scaling: Option<String>,
        /// Skip the h series.
        #[arg(long)]
        no_scaling: bool,
        /// Smoothing schedule: `scales` (default) or `paper` (20 steps), to compare
        /// the two in one build.
        #[arg(long, value_enum, default_value_t = ScheduleArg::Scales)]
        schedule: ScheduleArg,
    },
    /// Generate an analytic test shape with known necks and write it as a mesh.
    Shape {
        /// One of `necklace shape --list` (sphere, ellipsoid, capsule, limb, torus,
        /// varying-torus, dumbbell, chain, satellites, eight, pretzel, buckyball,
        /// bent-ring, rings, torus-knot).
        #[arg(required_unless_present = "list")]
        name: Option<String>,
        /// A shape parameter, `name=value` (repeatable); `--list` shows them.
        #[arg(long = "param", value_name = "K=V", value_parser = parse_param)]
        params: Vec<(String, f64)>,
        /// Output file (.obj, .off or .ply).
        #[arg(short, long, required_unless_present = "list")]
        output: Option<PathBuf>,
        /// List the shapes, their parameters and their expected necks.
        #[arg(long)]
        list: bool,
    },
}

/// The method's settings of `loops` and `batch`: which sides, and every stage's.
#[derive(clap::Args)]
pub struct NeckArgs {
    /// Find handle loops (inside).
    #[arg(long)]
    pub handles: bool,
    /// Find tunnel loops (outside).
    #[arg(long)]
    pub tunnels: bool,
    /// Run the two sides one after the other instead of at the same time: slower,
    /// with the peak memory of the larger side instead of both (figures in the
    /// "options" table of docs/benchmarks.md).
    #[arg(long)]
    pub one_side_at_a_time: bool,
    /// Mesh each side of a surface whose genus is known (and that does not cross
    /// itself) within a sixteenth, then a quarter of its memory budget before the
    /// whole, and keep the first mesh whose budget did not bind or whose topology and
    /// loop rank match the surface's: far faster where slivers make the budget bind,
    /// but such a mesh can miss necks in thin parts that do not change the ranks.
    #[arg(long)]
    pub budget_steps: bool,
    /// Simplify a surface with more triangles than this (0: never) for the volume
    /// mesh, distance field and saddles; the loops are cut again with the same
    /// planes and tightened on the input.
    #[arg(long, default_value_t = SimplifyOptions::default().above, value_name = "TRIANGLES")]
    pub simplify_above: usize,
    /// How many triangles the simplified copy keeps.
    #[arg(long, default_value_t = SimplifyOptions::default().target, value_name = "TRIANGLES")]
    pub simplify_to: usize,
    #[command(flatten)]
    pub method: MethodArgs,
    /// Where the plane through a saddle has no curve around it: parallel planes tried
    /// on each side, 0.125 % of the diagonal apart.
    #[arg(long, default_value_t = LoopOptions::default().plane_offsets, allow_negative_numbers = true)]
    pub plane_offsets: usize,
    /// A kept cycle-closing loop is also cut from parallel planes up to this many
    /// steps (0.5 % of the diagonal) away on each side, and the shortest loop of its
    /// class wins (0: off).
    #[arg(long, default_value_t = LoopOptions::default().slide_steps, allow_negative_numbers = true)]
    pub slide_steps: usize,
    /// A separating saddle below --min-bulge is a neck only if the curve one loop
    /// radius away is at least this much longer than its loop, on both sides
    /// (0: a cylinder).
    #[arg(long, default_value_t = LoopOptions::default().min_opening, allow_negative_numbers = true)]
    pub min_opening: f64,
    /// ... and its loop is at most this many times the circumference of the
    /// inscribed ball at the saddle (larger: a loop round a flat part).
    #[arg(long, default_value_t = LoopOptions::default().max_flatness, allow_negative_numbers = true)]
    pub max_flatness: f64,
}

impl NeckArgs {
    /// The library's options (`keep_volume`: keep the volume meshes for field.vtu).
    pub fn options(&self, keep_volume: bool) -> NeckOptions {
        NeckOptions {
            loops: LoopOptions {
                plane_offsets: self.plane_offsets,
                slide_steps: self.slide_steps,
                min_opening: self.min_opening,
                max_flatness: self.max_flatness,
                ..LoopOptions::default()
            },
            // Neither flag: both kinds.
            handles: self.handles || !self.tunnels,
            tunnels: self.tunnels || !self.handles,
            volume: self.method.volume(),
            morse: self.method.morse(),
            keep_volume,
            sides_at_once: !self.one_side_at_a_time,
            at_once_max_tets: NeckOptions::default().at_once_max_tets,
            budget_steps: self.budget_steps,
            input: self.method.input.options(),
            simplify: SimplifyOptions {
                above: self.simplify_above,
                target: self.simplify_to,
                ..SimplifyOptions::default()
            },
        }
    }
}

/// How a mesh file is read into the surface the method works on.
#[derive(clap::Args)]
pub struct InputArgs {
    /// Weld corners closer than this fraction of the bounding-box diagonal into one
    /// vertex (STL stores each triangle's corners apart; OBJ and PLY repeat positions
    /// along texture seams).
    #[arg(long, default_value_t = necklace::pipeline::DEFAULT_WELD, value_name = "FRACTION", allow_negative_numbers = true)]
    pub weld: f64,
    /// Keep the vertices as the file gives them (no welding).
    #[arg(long)]
    pub no_weld: bool,
}

impl InputArgs {
    pub fn options(&self) -> InputOptions {
        InputOptions {
            weld: (!self.no_weld).then_some(self.weld),
        }
    }
}

/// The method's settings shared by `critical` and `loops`.
#[derive(clap::Args)]
pub struct MethodArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Smoothing schedule: `scales` classifies over a geometric range of heat times
    /// (from 2h to a quarter of the diagonal); `paper` takes --steps steps of --tau and
    /// classifies from step 10 on, as the paper does.
    #[arg(long, value_enum, default_value_t = ScheduleArg::Scales)]
    pub schedule: ScheduleArg,
    /// Scale space: classified levels.
    #[arg(long, default_value_t = 32, allow_negative_numbers = true)]
    pub levels: usize,
    /// Scale space: smallest bulge ratio (the lobe's largest inscribed radius / the
    /// neck's) of a neck that cuts off a part; a separating saddle below it is a neck
    /// only if its loop opens out on both sides (`loops --min-opening`).
    #[arg(long, default_value_t = 1.5, allow_negative_numbers = true)]
    pub min_bulge: f64,
    /// Scale space: levels a saddle must live to be a neck.
    #[arg(long, default_value_t = 3, allow_negative_numbers = true)]
    pub min_levels: usize,
    /// Paper schedule: last smoothing step N (classification runs from step 10 to N).
    #[arg(long, default_value_t = 20, allow_negative_numbers = true)]
    pub steps: usize,
    /// Paper schedule: heat time step in units where the bounding box's longest side
    /// is 1.
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true)]
    pub tau: f64,
    /// Lattice spacing of the volume mesh (default: bounding-box diagonal / 64).
    #[arg(long, allow_negative_numbers = true)]
    pub h: Option<f64>,
    /// Memory budget of the run (bytes, or with K, M, G or T: 8G is 8e9 bytes), shared
    /// by the two volume meshes: thin parts are not refined past it, and a mesh
    /// estimated over it is refused before it is built.
    #[arg(long, default_value = "8G", value_parser = parse_memory, allow_negative_numbers = true)]
    pub max_memory: u64,
    /// On a side whose topology the surface does not predict (it crosses itself, or
    /// a component has no genus), no cell finer than this fraction of h is asked
    /// for (0 turns the bound off); a warning says when it binds.
    #[arg(long, default_value_t = 0.25, allow_negative_numbers = true)]
    pub unchecked_min_cell: f64,
    /// The volume mesher: necklace's isosurface stuffing, the Delaunay tetrahedralization
    /// of points sampled on the surface (`sampled`, experimental), restricted Delaunay
    /// refinement from those points (`refined`, experimental), or TetGen "pq1.2"
    /// (needs a build with --features tetgen, which is AGPL-3.0).
    #[arg(long, value_enum, default_value = "stuffing")]
    pub mesher: MesherArg,
    /// The most heat steps (--levels, or --steps with the paper schedule) a run may
    /// take: more is refused before any work.
    #[arg(long, default_value_t = necklace::morse::DEFAULT_MAX_STEPS, allow_negative_numbers = true)]
    pub max_steps: usize,
    /// Preconditioner of the heat steps' conjugate gradients: `jacobi` (the diagonal),
    /// `multigrid` (a smoothed-aggregation V-cycle: fewer, dearer iterations, more
    /// memory), or `auto` (multigrid from 300 000 to 1 000 000 unknowns, jacobi outside); the
    /// fields agree to the solver's tolerance.
    #[arg(long, value_enum, default_value_t = SolverArg::Auto)]
    pub solver: SolverArg,
}

impl MethodArgs {
    pub fn volume(&self) -> VolumeOptions {
        VolumeOptions {
            h: self.h,
            max_memory: self.max_memory,
            mesher: self.mesher.into(),
            unchecked_min_cell: self.unchecked_min_cell,
            ..VolumeOptions::default()
        }
    }

    pub fn morse(&self) -> MorseOptions {
        MorseOptions {
            schedule: self.schedule.into(),
            levels: self.levels,
            min_bulge: self.min_bulge,
            min_levels: self.min_levels,
            steps: self.steps,
            tau: self.tau,
            max_steps: self.max_steps,
            solver: SolverOptions {
                preconditioner: self.solver.into(),
                ..SolverOptions::default()
            },
            ..MorseOptions::default()
        }
    }
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum OnlyArg {
    Handles,
    Tunnels,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum SolverArg {
    Auto,
    Jacobi,
    Multigrid,
}

impl From<SolverArg> for Preconditioner {
    fn from(s: SolverArg) -> Preconditioner {
        match s {
            SolverArg::Multigrid => Preconditioner::Multigrid,
            SolverArg::Jacobi => Preconditioner::Jacobi,
            SolverArg::Auto => Preconditioner::Auto,
        }
    }
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum ScheduleArg {
    Scales,
    Paper,
}

impl From<ScheduleArg> for Schedule {
    fn from(s: ScheduleArg) -> Schedule {
        match s {
            ScheduleArg::Scales => Schedule::ScaleSpace,
            ScheduleArg::Paper => Schedule::Paper,
        }
    }
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum MesherArg {
    Stuffing,
    Tetgen,
    Sampled,
    Refined,
}

pub fn parse_param(s: &str) -> std::result::Result<(String, f64), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected name=value, got '{s}'"))?;
    let v: f64 = v
        .trim()
        .parse()
        .map_err(|_| format!("'{v}' is not a number"))?;
    Ok((k.trim().to_string(), v))
}

impl From<MesherArg> for Mesher {
    fn from(m: MesherArg) -> Mesher {
        match m {
            MesherArg::Stuffing => Mesher::Stuffing,
            MesherArg::Tetgen => Mesher::Tetgen,
            MesherArg::Sampled => Mesher::Sampled,
            MesherArg::Refined => Mesher::Refined,
        }
    }
}

/// A memory size: bytes, or a number with K, M, G or T (powers of 1000; a trailing B is
/// allowed), e.g. `4G`, `1.5G`, `500M`.
pub fn parse_memory(text: &str) -> Result<u64, String> {
    let t = text.trim().to_ascii_uppercase();
    let t = t.strip_suffix('B').unwrap_or(&t);
    let (number, unit) = match t.char_indices().last() {
        Some((i, 'K')) => (&t[..i], 1e3),
        Some((i, 'M')) => (&t[..i], 1e6),
        Some((i, 'G')) => (&t[..i], 1e9),
        Some((i, 'T')) => (&t[..i], 1e12),
        _ => (t, 1.0),
    };
    let value: f64 = number
        .trim()
        .parse()
        .map_err(|_| format!("{text:?} is not a size (e.g. 4G, 500M or a number of bytes)"))?;
    let bytes = value * unit;
    if !(1.0..1.8e19).contains(&bytes) {
        return Err(format!("{text:?} must be a positive size below 18E bytes"));
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::parse_memory;

    #[test]
    fn memory_sizes_read_with_their_units() {
        assert_eq!(parse_memory("4G"), Ok(4_000_000_000));
        assert_eq!(parse_memory("1.5gb"), Ok(1_500_000_000));
        assert_eq!(parse_memory("500M"), Ok(500_000_000));
        assert_eq!(parse_memory("64k"), Ok(64_000));
        assert_eq!(parse_memory("123"), Ok(123));
        for bad in ["", "G", "lots", "-1G", "0", "nanG", "1e30"] {
            assert!(parse_memory(bad).is_err(), "{bad}");
        }
    }
}
