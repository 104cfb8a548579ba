//! Volume meshing by isosurface stuffing on a graded BCC lattice.
//!
//! Computes a [`TetMesh`] of a region given implicitly by a [`Domain`]: a function that
//! is negative inside the region, zero on its boundary and 1-Lipschitz (a signed
//! distance, or the max of signed distances for an intersection). For the method this is
//! the solid inside the input surface (handles) or the shell between the surface and a
//! bounding sphere (tunnels); the pipeline builds those domains. This replaces the
//! paper's TetGen step (sec. 4, "preprocessing"); see issue 3 for why.
//!
//! Steps (Labelle & Shewchuk, "Isosurface Stuffing", SIGGRAPH 2007):
//! 1. `octree`: a balanced octree whose cells have size `h` wherever the boundary may
//!    pass (|f(centre)| < half-diagonal + h; [`Domain::spacing_near`] may ask for less
//!    detail on parts of the boundary), smaller where the domain asks for it
//!    ([`Domain::sizing`]: thin parts, down to `h / 2^refine_levels`), and coarser away
//!    from the boundary.
//! 2. `background`: the octree's BCC tetrahedralisation (graded, conforming).
//! 3. `stuffing`: domain values at the lattice vertices, cut points on sign-changing
//!    edges, warping of vertices too close to a cut point, and the stencils that fill
//!    each background tet with its inside part.
//! 4. `repair`: pinches below the lattice resolution (tets touching along an edge or at
//!    a vertex only) are undone by dropping the smaller side, and reported.
//!
//! Conventions: lengths in the domain's units; output tets positively oriented; vertex
//! kinds from the sign (inside: interior) and [`Domain::boundary_kind`] (on the zero
//! set). Entry point: [`stuff_volume`].

mod background;
mod csr;
mod octree;
mod repair;
mod stuffing;

use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};
use std::time::Instant;

use serde::Serialize;

use crate::error::{Error, ErrorKind, Result};
use crate::tet::{TetMesh, VertexKind};
use octree::{Cell, Key, Octree};

/// A region to mesh, given implicitly.
pub trait Domain: Sync {
    /// Negative inside, zero on the boundary, positive outside; 1-Lipschitz.
    fn value(&self, p: [f64; 3]) -> f64;

    /// [`Domain::value`] at many points (implementations may parallelise; the result
    /// must not depend on the thread count).
    fn values(&self, points: &[[f64; 3]]) -> Vec<f64> {
        points.iter().map(|&p| self.value(p)).collect()
    }

    /// Like [`Domain::values`], but only values of magnitude below `band` must be exact;
    /// beyond it any value of the right sign and magnitude ≥ `band` will do (lets an
    /// implementation skip exact distances far from the boundary).
    fn values_within(&self, points: &[[f64; 3]], band: f64) -> Vec<f64> {
        let _ = band;
        self.values(points)
    }

    /// Where the segment `a`–`b` (whose ends have opposite signs) crosses the boundary,
    /// as a parameter in (0, 1), if the domain can say directly (e.g. by a ray cast);
    /// `None` lets the mesher search for the root of [`Domain::value`].
    fn crossing(&self, a: [f64; 3], b: [f64; 3]) -> Option<f64> {
        let _ = (a, b);
        None
    }

    /// Which boundary a point on the zero set lies on.
    fn boundary_kind(&self, p: [f64; 3]) -> VertexKind;

    /// A box `(min, max)` that contains the whole region.
    fn bounds(&self) -> ([f64; 3], [f64; 3]);

    /// Points where the lattice spacing must not exceed the given length (thin parts).
    fn sizing(&self) -> Vec<([f64; 3], f64)> {
        Vec::new()
    }

    /// The spacing wanted where the boundary passes near `p`, given the requested `h`:
    /// `h` by default; a shell returns more near its outer sphere, which needs no detail.
    fn spacing_near(&self, _p: [f64; 3], h: f64) -> f64 {
        h
    }

    /// The largest value [`Domain::spacing_near`] returns for this `h`.
    fn coarsest_spacing(&self, h: f64) -> f64 {
        h
    }
}

/// Options of the stuffing mesher.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StuffingOptions {
    /// Lattice spacing (cell size) along the boundary, in the domain's units.
    pub h: f64,
    /// How many halvings below `h` thin parts may ask for (default 3: down to `h/8`).
    pub refine_levels: u32,
}

impl StuffingOptions {
    /// Spacing `h` with the default refinement floor.
    pub fn new(h: f64) -> Self {
        StuffingOptions {
            h,
            refine_levels: 3,
        }
    }
}

/// Counts that describe a stuffing run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StuffingStats {
    /// Spacing along the boundary.
    pub h: f64,
    /// Smallest cell size used.
    pub finest_cell: f64,
    /// Octree leaves.
    pub octree_leaves: usize,
    /// Background lattice vertices and tets.
    pub background_vertices: usize,
    /// Background tets.
    pub background_tets: usize,
    /// Lattice vertices warped onto the boundary.
    pub warped_vertices: usize,
    /// Cut points used as boundary vertices.
    pub cut_points: usize,
    /// Output tets that warping made non-positive (0 unless the guarantees fail).
    pub inverted_tets: usize,
    /// Tets dropped to undo pinches below the lattice resolution.
    pub pinch_tets_removed: usize,
    /// Interior vertices those drops left on the boundary (now boundary vertices,
    /// slightly inside the true surface).
    pub exposed_vertices: usize,
    /// Seconds per step: octree, background, lattice values, stuffing, repair.
    pub seconds: [f64; 5],
}

/// A stuffed volume mesh and its statistics.
#[derive(Debug, Clone)]
pub struct VolumeMesh {
    /// The tet mesh.
    pub mesh: TetMesh,
    /// What the run did.
    pub stats: StuffingStats,
}

/// Factor on α for edges no longer than h/2 (refined thin parts).
const THIN_ALPHA_SCALE: f64 = 0.5;

/// Upper bound on background lattice vertices before the mesher refuses (memory guard).
const MAX_OCTREE_CELLS: usize = 40_000_000;

/// Mesh `domain` by isosurface stuffing with spacing `options.h` along its boundary.
pub fn stuff_volume(domain: &dyn Domain, options: &StuffingOptions) -> Result<VolumeMesh> {
    let h = options.h;
    let (lo, hi) = domain.bounds();
    if !(h.is_finite() && h > 0.0) {
        return Err(Error::invalid_argument(format!("h = {h} must be positive")));
    }
    if (0..3).any(|k| !(lo[k].is_finite() && hi[k].is_finite() && hi[k] >= lo[k])) {
        return Err(Error::invalid_argument(
            "the domain's bounds are not finite",
        ));
    }
    if options.refine_levels > 10 {
        return Err(Error::invalid_argument("refine_levels must be at most 10"));
    }

    // The integer grid: one unit is half the smallest allowed cell.
    let unit = h / f64::from(1u32 << options.refine_levels) / 2.0;
    let h_units = 2i64 << options.refine_levels;
    let extent = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max) + 4.0 * h;
    let mut root_size = h_units;
    while (root_size as f64) * unit < extent {
        root_size *= 2;
        if root_size > (1i64 << 40) {
            return Err(Error::invalid_argument(format!(
                "h = {h} is too small for a domain of extent {extent}"
            )));
        }
    }
    // Centre the root on the domain.
    let mid = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
    let origin = mid.map(|m| m - 0.5 * root_size as f64 * unit);
    let to_point = |k: Key| {
        [
            origin[0] + k[0] as f64 * unit,
            origin[1] + k[1] as f64 * unit,
            origin[2] + k[2] as f64 * unit,
        ]
    };
    let to_key = |p: [f64; 3]| [0, 1, 2].map(|k| ((p[k] - origin[k]) / unit).floor() as i64);
    let root = Cell {
        origin: [0, 0, 0],
        size: root_size,
    };

    let mut clock = Instant::now();
    let mut seconds = [0.0; 5];
    let mut lap = |i: usize| {
        seconds[i] = clock.elapsed().as_secs_f64();
        clock = Instant::now();
    };

    // 1. Octree.
    let sizing: Vec<(Key, i64)> = domain
        .sizing()
        .into_iter()
        .filter(|(p, s)| p.iter().all(|c| c.is_finite()) && s.is_finite() && *s > 0.0)
        .map(|(p, s)| (to_key(p), ((s / unit) as i64).max(2)))
        .collect();
    let table = octree::sizing_table(root, &sizing);
    let mut cells_seen = 0usize;
    let mut too_big = false;
    // Leaves whose closed cube lies wholly outside the region (value at the centre
    // beyond the half diagonal): tets touching only such leaves produce nothing.
    let mut dead: HashSet<Cell> = HashSet::default();
    // Every evaluated cell's centre value (exact below its band, else a bound).
    let mut centre_values: HashMap<Cell, f64> = HashMap::default();
    let tree = Octree::build(root, |cells| {
        cells_seen += cells.len();
        if cells_seen > MAX_OCTREE_CELLS {
            too_big = true;
            return vec![false; cells.len()];
        }
        let centres: Vec<[f64; 3]> = cells.iter().map(|c| to_point(c.center())).collect();
        // All cells of one level have the same size.
        let half_diagonal = 0.5 * 3f64.sqrt() * cells.first().map_or(0, |c| c.size) as f64 * unit;
        let coarsest = domain.coarsest_spacing(h).max(h);
        let values = domain.values_within(&centres, half_diagonal + coarsest);
        cells
            .iter()
            .zip(values)
            .map(|(cell, f)| {
                centre_values.insert(*cell, f);
                if f > half_diagonal * (1.0 + 1e-9) {
                    dead.insert(*cell);
                }
                let thin = table.get(cell).is_some_and(|&req| req < cell.size);
                if thin {
                    return true;
                }
                if f.abs() >= half_diagonal + coarsest {
                    return false;
                }
                let size = cell.size as f64 * unit;
                let wanted = domain.spacing_near(to_point(cell.center()), h).max(h);
                f.abs() < half_diagonal + wanted && size > wanted * (1.0 + 1e-9)
            })
            .collect()
    });
    if too_big {
        return Err(Error::new(
            ErrorKind::InvalidArgument,
            format!("h = {h} asks for more than {MAX_OCTREE_CELLS} octree cells; use a larger h"),
        ));
    }
    let leaves = tree.leaves();
    let finest = leaves.iter().map(|c| c.size).min().unwrap_or(root_size);
    lap(0);

    // 2. Background BCC tetrahedralisation.
    let background = background::tetrahedralize(&tree, &|c| dead.contains(c));
    let positions: Vec<[f64; 3]> = background.keys.iter().map(|&k| to_point(k)).collect();
    lap(1);
    // Only signs matter at lattice vertices (cut points are found on the true function).
    // A vertex inside a leaf whose centre value exceeds the half diagonal has that sign
    // (the function is 1-Lipschitz); only the others are evaluated.
    let mut values = vec![0.0; positions.len()];
    let mut unknown = Vec::new();
    for (v, &k) in background.keys.iter().enumerate() {
        let known = tree.leaf_containing(k).and_then(|leaf| {
            let f = *centre_values.get(&leaf)?;
            if leaf.center() == k {
                // The leaf's own centre: its value is known already (sign exact).
                return (f != 0.0).then_some(f);
            }
            let half_diagonal = 0.5 * 3f64.sqrt() * leaf.size as f64 * unit;
            (f.abs() > half_diagonal * (1.0 + 1e-6))
                .then(|| f.signum() * (f.abs() - half_diagonal).max(1e-6 * half_diagonal))
        });
        match known {
            Some(f) => values[v] = f,
            None => unknown.push(v),
        }
    }
    let points: Vec<[f64; 3]> = unknown.iter().map(|&v| positions[v]).collect();
    for (&v, f) in unknown.iter().zip(domain.values_within(&points, h)) {
        values[v] = f;
    }
    lap(2);

    // 3. Stuffing.
    let keys = &background.keys;
    // The paper's α for axis-parallel and other edges; in cells finer than h (thin
    // parts, at most a few cells across) half of it, since a full warp there moves a
    // vertex by a large fraction of the part's thickness and can cut it in two.
    let alpha = |a: u32, b: u32| {
        let (ka, kb) = (keys[a as usize], keys[b as usize]);
        let d = [0, 1, 2].map(|k| (ka[k] - kb[k]).abs());
        let axis_parallel = d.iter().filter(|&&x| x != 0).count() == 1;
        let base = if axis_parallel {
            stuffing::ALPHA_LONG
        } else {
            stuffing::ALPHA_SHORT
        };
        let length2 = d.iter().map(|&x| x * x).sum::<i64>();
        let refined = 4 * length2 <= h_units * h_units;
        if refined {
            base * THIN_ALPHA_SCALE
        } else {
            base
        }
    };
    let value = |p: [f64; 3]| domain.value(p);
    let crossing = |a: [f64; 3], b: [f64; 3]| domain.crossing(a, b);
    let mut stuffed = stuffing::stuff(
        &value,
        &crossing,
        positions,
        &values,
        &alpha,
        &background.tets,
    );

    lap(3);

    // 4. Pinches below the lattice resolution.
    let mut interior: Vec<bool> = stuffed.signs.iter().map(|&s| s < 0).collect();
    let repair = repair::repair_pinches(&stuffed.positions, &mut stuffed.tets, &interior);
    for &v in &repair.exposed {
        interior[v as usize] = false;
    }

    lap(4);

    // Keep the vertices the tets use, in index order.
    let mut new_id = vec![u32::MAX; stuffed.positions.len()];
    for t in &stuffed.tets {
        for &v in t {
            new_id[v as usize] = 0;
        }
    }
    let mut out_positions = Vec::new();
    let mut kinds = Vec::new();
    for (v, id) in new_id.iter_mut().enumerate() {
        if *id == 0 {
            *id = out_positions.len() as u32;
            let p = stuffed.positions[v];
            out_positions.push(p);
            kinds.push(if interior[v] {
                VertexKind::Interior
            } else {
                domain.boundary_kind(p)
            });
        }
    }
    let tets: Vec<[u32; 4]> = stuffed
        .tets
        .iter()
        .map(|t| t.map(|v| new_id[v as usize]))
        .collect();
    let mesh = TetMesh::new(out_positions, tets, kinds)?;

    Ok(VolumeMesh {
        mesh,
        stats: StuffingStats {
            h,
            finest_cell: finest as f64 * unit,
            octree_leaves: leaves.len(),
            background_vertices: background.keys.len(),
            background_tets: background.tets.len(),
            warped_vertices: stuffed.warped,
            cut_points: stuffed.cut_points,
            inverted_tets: stuffed.inverted,
            pinch_tets_removed: repair.removed_tets,
            exposed_vertices: repair.exposed.len(),
            seconds,
        },
    })
}
