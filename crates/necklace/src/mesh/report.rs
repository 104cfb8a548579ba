//! The validity report of a surface mesh (what `necklace info` prints).

use std::collections::HashSet;
use std::fmt;

use serde::{Deserialize, Serialize};

use super::topology::{find, union, Topology};
use super::SurfaceMesh;
use crate::geom::{cross, dot, norm, sub};

/// A triangle counts as zero-area when its height is below this fraction of its longest
/// side (2A ≤ ε·L²).
const ZERO_AREA_RELATIVE: f64 = 1e-12;

/// The largest absolute coordinate the method accepts: a volume is a product of three
/// coordinates, which overflows `f64` (1.8e308) not far above 1e100.
pub const MAX_COORDINATE: f64 = 1e100;

/// A closed mesh is flat when |signed volume| ≤ this × (bounding-box diagonal)³.
const FLAT_RELATIVE: f64 = 1e-12;

/// Counts, validity flags and genus of a surface mesh. Built by [`MeshReport::new`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeshReport {
    /// Number of vertices (including unreferenced ones).
    pub vertices: usize,
    /// Number of triangles.
    pub faces: usize,
    /// Number of unique undirected edges.
    pub edges: usize,
    /// Connected components of the edge graph.
    pub components: usize,
    /// Genus per component (`None` where undefined: non-manifold or non-oriented).
    pub genus: Vec<Option<i64>>,
    /// Euler characteristic V − E + F of the whole mesh.
    pub euler: i64,
    /// Every edge has exactly two incident faces.
    pub watertight: bool,
    /// No non-manifold edge and no non-manifold vertex (boundaries allowed).
    pub manifold: bool,
    /// Every edge is used in opposite directions by its faces.
    pub oriented: bool,
    /// Every component faces away from the solid it bounds; `None` unless the mesh is
    /// watertight, manifold and oriented and encloses a volume. [`MeshReport::new`]
    /// judges by the total signed volume; `pipeline::inspect_surface` per component,
    /// from how the components nest (see `inward_components`).
    pub outward: Option<bool>,
    /// Components whose faces point into the solid they bound (an outermost component
    /// with negative volume, a cavity with positive volume); `None` when not measured
    /// (`pipeline::inspect_surface` measures it).
    pub inward_components: Option<usize>,
    /// Pairs of triangles that cross each other (not at a shared vertex or edge); `None`
    /// when not measured (`pipeline::inspect_surface` measures it).
    pub self_intersections: Option<usize>,
    /// Watertight, but no component encloses a volume (each one's signed volume is zero
    /// for the mesh's size): flat, doubled sheets, or all vertices at one point. Such a
    /// surface bounds no solid.
    pub flat: bool,
    /// The largest absolute coordinate; above [`MAX_COORDINATE`] areas and volumes
    /// overflow and the mesh is refused by the method.
    pub max_abs_coordinate: f64,
    /// Signed enclosed volume (meaningful for closed meshes).
    pub signed_volume: f64,
    /// Total surface area.
    pub area: f64,
    /// Edges with one face.
    pub boundary_edges: usize,
    /// Closed chains of boundary edges (holes).
    pub boundary_loops: usize,
    /// Edges with three or more faces.
    pub non_manifold_edges: usize,
    /// Vertices whose faces form more than one fan.
    pub non_manifold_vertices: usize,
    /// Edges whose faces disagree on orientation.
    pub inconsistent_edges: usize,
    /// Vertices used by no triangle.
    pub unreferenced_vertices: usize,
    /// Vertices at exactly the same position as an earlier vertex.
    pub duplicate_vertices: usize,
    /// Triangles that repeat a vertex index.
    pub degenerate_faces: usize,
    /// Triangles of (numerically) zero area, including degenerate ones.
    pub zero_area_faces: usize,
    /// Smallest interior angle of any non-degenerate triangle, in degrees (0 if none).
    pub min_angle_deg: f64,
    /// Mean length of the unique edges.
    pub mean_edge_length: f64,
    /// Bounding-box corner with the smallest coordinates.
    pub bbox_min: [f64; 3],
    /// Bounding-box corner with the largest coordinates.
    pub bbox_max: [f64; 3],
    /// Length of the bounding-box diagonal.
    pub bbox_diagonal: f64,
    /// One entry per component, in the order of their lowest vertex.
    pub component_details: Vec<ComponentReport>,
}

/// Counts and topology of one connected component.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ComponentReport {
    /// Vertices in the component.
    pub vertices: usize,
    /// Edges in the component.
    pub edges: usize,
    /// Triangles in the component.
    pub faces: usize,
    /// V − E + F of the component.
    pub euler: i64,
    /// Boundary loops of the component.
    pub boundary_loops: usize,
    /// From χ = 2 − 2g − b; `None` when the component is non-manifold or not oriented.
    pub genus: Option<i64>,
    /// Signed volume enclosed by the component's triangles.
    pub signed_volume: f64,
}

impl MeshReport {
    /// Analyse `mesh`. `O(F log F)`; never fails, whatever the mesh.
    pub fn new(mesh: &SurfaceMesh) -> Self {
        let topo = Topology::new(mesh);
        let nv = mesh.num_vertices();
        let (component_of, num_components) = topo.components(mesh);

        let boundary = topo.boundary_edges();
        let non_manifold_edges = topo.non_manifold_edges();
        let non_manifold_vertices = topo.non_manifold_vertices(mesh);
        let inconsistent = topo.inconsistently_oriented_edges(mesh);

        // Per-component counts.
        let mut comps = vec![
            ComponentReport {
                vertices: 0,
                edges: 0,
                faces: 0,
                euler: 0,
                boundary_loops: 0,
                genus: None,
                signed_volume: 0.0,
            };
            num_components
        ];
        let comp = |v: u32| component_of[v as usize].map(|c| c as usize);
        for c in component_of.iter().flatten() {
            comps[*c as usize].vertices += 1;
        }
        for e in topo.edges() {
            if let Some(c) = comp(e[0]) {
                comps[c].edges += 1;
            }
        }
        let origin = mesh.positions.first().copied().unwrap_or([0.0; 3]);
        for (f, t) in mesh.triangles.iter().enumerate() {
            if let Some(c) = comp(t[0]) {
                comps[c].faces += 1;
                let [a, b, d] = mesh.corners(f);
                let (a, b, d) = (sub(a, origin), sub(b, origin), sub(d, origin));
                comps[c].signed_volume += dot(a, cross(b, d)) / 6.0;
            }
        }

        // Boundary loops: connected sets of boundary edges, counted per component.
        let mut parent: Vec<usize> = (0..nv).collect();
        for &e in &boundary {
            let [a, b] = topo.edges()[e];
            union(&mut parent, a as usize, b as usize);
        }
        let mut seen_root = vec![false; nv];
        let mut boundary_loops = 0;
        for &e in &boundary {
            let a = topo.edges()[e][0] as usize;
            let r = find(&mut parent, a);
            if !seen_root[r] {
                seen_root[r] = true;
                boundary_loops += 1;
                if let Some(c) = comp(a as u32) {
                    comps[c].boundary_loops += 1;
                }
            }
        }

        // A component's genus is defined when it is manifold and consistently oriented.
        let mut bad_component = vec![false; num_components];
        for &e in non_manifold_edges.iter().chain(&inconsistent) {
            if let Some(c) = comp(topo.edges()[e][0]) {
                bad_component[c] = true;
            }
        }
        for &v in &non_manifold_vertices {
            if let Some(c) = comp(v as u32) {
                bad_component[c] = true;
            }
        }
        for (c, r) in comps.iter_mut().enumerate() {
            r.euler = r.vertices as i64 - r.edges as i64 + r.faces as i64;
            let twice_genus = 2 - r.euler - r.boundary_loops as i64;
            if !bad_component[c] && twice_genus >= 0 && twice_genus % 2 == 0 {
                r.genus = Some(twice_genus / 2);
            }
        }

        // Geometry.
        let mut degenerate_faces = 0;
        let mut zero_area_faces = 0;
        for (f, t) in mesh.triangles.iter().enumerate() {
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                degenerate_faces += 1;
                zero_area_faces += 1;
                continue;
            }
            let [a, b, c] = mesh.corners(f);
            let longest = norm(sub(b, a)).max(norm(sub(c, b))).max(norm(sub(a, c)));
            if norm(cross(sub(b, a), sub(c, a))) <= ZERO_AREA_RELATIVE * longest * longest {
                zero_area_faces += 1;
            }
        }
        let min_angle_deg = min_angle_degrees(mesh);
        let mean_edge_length = if topo.num_edges() == 0 {
            0.0
        } else {
            let total: f64 = topo
                .edges()
                .iter()
                .map(|&[a, b]| norm(sub(mesh.positions[a as usize], mesh.positions[b as usize])))
                .sum();
            total / topo.num_edges() as f64
        };
        let unreferenced_vertices = component_of.iter().filter(|c| c.is_none()).count();
        let duplicate_vertices = count_duplicate_positions(&mesh.positions);
        let (bbox_min, bbox_max) = mesh.bounding_box().unwrap_or(([0.0; 3], [0.0; 3]));

        let watertight = !mesh.triangles.is_empty()
            && (0..topo.num_edges()).all(|e| topo.edge_faces(e).len() == 2);
        let manifold = non_manifold_edges.is_empty() && non_manifold_vertices.is_empty();
        let oriented = inconsistent.is_empty();
        let signed_volume = mesh.signed_volume();
        let diagonal = norm(sub(bbox_max, bbox_min));
        let max_abs_coordinate = mesh
            .positions
            .iter()
            .flatten()
            .fold(0.0f64, |m, c| m.max(c.abs()));
        // Flat: no component encloses a volume (components of opposite orientation
        // may cancel in the total, so each is judged alone).
        let flat = watertight
            && max_abs_coordinate <= MAX_COORDINATE
            && comps
                .iter()
                .all(|c| c.signed_volume.abs() <= FLAT_RELATIVE * diagonal.powi(3));
        let outward = (watertight && manifold && oriented && !flat && signed_volume.is_finite())
            .then_some(signed_volume > 0.0);

        MeshReport {
            vertices: nv,
            faces: mesh.num_triangles(),
            edges: topo.num_edges(),
            components: num_components,
            genus: comps.iter().map(|c| c.genus).collect(),
            euler: nv as i64 - topo.num_edges() as i64 + mesh.num_triangles() as i64,
            watertight,
            manifold,
            oriented,
            outward,
            inward_components: None,
            self_intersections: None,
            flat,
            max_abs_coordinate,
            signed_volume,
            area: mesh.area(),
            boundary_edges: boundary.len(),
            boundary_loops,
            non_manifold_edges: non_manifold_edges.len(),
            non_manifold_vertices: non_manifold_vertices.len(),
            inconsistent_edges: inconsistent.len(),
            unreferenced_vertices,
            duplicate_vertices,
            degenerate_faces,
            zero_area_faces,
            min_angle_deg,
            mean_edge_length,
            bbox_min,
            bbox_max,
            bbox_diagonal: diagonal,
            component_details: comps,
        }
    }

    /// True when the mesh is what the method needs: watertight, manifold, consistently
    /// and outward oriented.
    pub fn is_valid_solid(&self) -> bool {
        self.watertight && self.manifold && self.oriented && self.outward == Some(true)
    }

    /// One line per problem found, empty for a clean closed manifold outward mesh.
    pub fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        let mut say = |cond: bool, text: String| {
            if cond {
                out.push(text);
            }
        };
        say(self.faces == 0, "no triangles".into());
        let too_large = self.max_abs_coordinate > MAX_COORDINATE;
        say(
            too_large,
            format!(
                "coordinates up to {:.3e} are too large (above {MAX_COORDINATE:.0e} products of three overflow): scale the mesh down",
                self.max_abs_coordinate
            ),
        );
        say(
            self.boundary_edges > 0,
            format!(
                "open: {} boundary edges in {} loops",
                self.boundary_edges, self.boundary_loops
            ),
        );
        say(
            self.non_manifold_edges > 0,
            format!(
                "non-manifold: {} edges with 3 or more faces",
                self.non_manifold_edges
            ),
        );
        say(
            self.non_manifold_vertices > 0,
            format!(
                "non-manifold: {} vertices where several fans meet",
                self.non_manifold_vertices
            ),
        );
        say(
            self.inconsistent_edges > 0,
            format!(
                "not consistently oriented: {} edges",
                self.inconsistent_edges
            ),
        );
        say(
            self.flat && self.faces > 0,
            if self.bbox_diagonal == 0.0 {
                "encloses no volume: all vertices are at one point".into()
            } else {
                "encloses no volume: the surface is flat (a doubled sheet)".into()
            },
        );
        match self.inward_components {
            Some(k) if k > 0 && k < self.components => say(
                true,
                format!(
                    "{k} of {} components face into the solid they bound: flip them",
                    self.components
                ),
            ),
            _ => say(
                self.outward == Some(false),
                "oriented inward (negative volume): flip the faces".into(),
            ),
        }
        say(
            self.self_intersections.is_some_and(|n| n > 0),
            format!(
                "crosses itself: {} pairs of triangles intersect",
                self.self_intersections.unwrap_or(0)
            ),
        );
        say(
            self.components > 1,
            format!("{} connected components", self.components),
        );
        say(
            self.unreferenced_vertices > 0,
            format!("{} unreferenced vertices", self.unreferenced_vertices),
        );
        say(
            self.duplicate_vertices > 0,
            format!(
                "{} vertices duplicate another's position",
                self.duplicate_vertices
            ),
        );
        say(
            self.zero_area_faces > 0 && !too_large && !self.flat,
            format!(
                "{} zero-area faces ({} repeat a vertex)",
                self.zero_area_faces, self.degenerate_faces
            ),
        );
        out
    }
}

impl fmt::Display for MeshReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "vertices {}  faces {}  edges {}  euler {}",
            self.vertices, self.faces, self.edges, self.euler
        )?;
        let genus: Vec<String> = self
            .genus
            .iter()
            .map(|g| g.map_or("?".to_string(), |g| g.to_string()))
            .collect();
        writeln!(
            f,
            "components {}  genus [{}]",
            self.components,
            genus.join(", ")
        )?;
        let flag = |b: bool| if b { "yes" } else { "no" };
        writeln!(
            f,
            "watertight {}  manifold {}  oriented {}  outward {}",
            flag(self.watertight),
            flag(self.manifold),
            flag(self.oriented),
            self.outward.map_or("n/a", flag)
        )?;
        writeln!(
            f,
            "bbox [{}, {}, {}] .. [{}, {}, {}]  diagonal {}",
            num(self.bbox_min[0]),
            num(self.bbox_min[1]),
            num(self.bbox_min[2]),
            num(self.bbox_max[0]),
            num(self.bbox_max[1]),
            num(self.bbox_max[2]),
            num(self.bbox_diagonal)
        )?;
        writeln!(
            f,
            "area {}  signed volume {}  mean edge {}  min angle {:.3} deg",
            num(self.area),
            num(self.signed_volume),
            num(self.mean_edge_length),
            self.min_angle_deg
        )?;
        let problems = self.problems();
        if problems.is_empty() {
            write!(f, "valid: closed, manifold, outward-oriented")
        } else {
            write!(f, "problems:")?;
            for p in problems {
                write!(f, "\n  - {p}")?;
            }
            Ok(())
        }
    }
}

/// A number for a person: six decimals in the everyday range, else scientific
/// notation (never a 300-digit number).
fn num(x: f64) -> String {
    if x == 0.0 || (1e-4..1e7).contains(&x.abs()) {
        format!("{x:.6}")
    } else {
        format!("{x:.6e}")
    }
}

/// Vertices whose exact position (with −0 read as +0) equals an earlier vertex's.
fn count_duplicate_positions(positions: &[[f64; 3]]) -> usize {
    let key = |p: &[f64; 3]| p.map(|c| if c == 0.0 { 0u64 } else { c.to_bits() });
    let mut seen: HashSet<[u64; 3]> = HashSet::with_capacity(positions.len());
    positions.iter().filter(|p| !seen.insert(key(p))).count()
}

/// Smallest corner angle over the triangles that are not zero-area, in degrees.
fn min_angle_degrees(mesh: &SurfaceMesh) -> f64 {
    // The smallest angle has the largest cosine.
    let mut max_cos: Option<f64> = None;
    for f in 0..mesh.num_triangles() {
        let p = mesh.corners(f);
        for i in 0..3 {
            let u = sub(p[(i + 1) % 3], p[i]);
            let w = sub(p[(i + 2) % 3], p[i]);
            let denom = norm(u) * norm(w);
            if denom > 0.0 && norm(cross(u, w)) > ZERO_AREA_RELATIVE * denom {
                let c = dot(u, w) / denom;
                max_cos = Some(max_cos.map_or(c, |m| m.max(c)));
            }
        }
    }
    max_cos.map_or(0.0, |c| c.clamp(-1.0, 1.0).acos().to_degrees())
}
