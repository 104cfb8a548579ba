//! How the components of a surface nest: which component directly encloses which,
//! by winding numbers. The input step orients each component by its depth (a cavity
//! faces into the solid around it), and the volume stage predicts each side's topology
//! from it. Entry point: [`nesting`].

use super::SurfaceDistance;
use crate::mesh::{MeshReport, SurfaceMesh, Topology};

/// The component directly enclosing each component of the surface (`None` for the
/// outermost), by the winding number of each component's triangles at points of the
/// others. `None` when two components cross (a component partly inside another).
pub fn nesting(surface: &SurfaceMesh, report: &MeshReport) -> Option<Vec<Option<usize>>> {
    let n = report.component_details.len();
    if n == 1 {
        return Some(vec![None]);
    }
    let (component_of, _) = Topology::new(surface).components(surface);
    let mut triangles: Vec<Vec<[u32; 3]>> = vec![Vec::new(); n];
    let mut vertices: Vec<Vec<u32>> = vec![Vec::new(); n];
    for t in &surface.triangles {
        if let Some(c) = component_of[t[0] as usize] {
            triangles[c as usize].push(*t);
        }
    }
    for (v, c) in component_of.iter().enumerate() {
        if let Some(c) = c {
            vertices[*c as usize].push(v as u32);
        }
    }
    let boxes: Vec<([f64; 3], [f64; 3])> = vertices
        .iter()
        .map(|vs| {
            let mut lo = [f64::INFINITY; 3];
            let mut hi = [f64::NEG_INFINITY; 3];
            for &v in vs {
                let p = surface.positions[v as usize];
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            (lo, hi)
        })
        .collect();
    let volume = |i: usize| report.component_details[i].signed_volume.abs();
    let mut parent = vec![None; n];
    let mut distances: Vec<Option<SurfaceDistance>> = vec![None; n];
    for i in 0..n {
        for j in 0..n {
            let (bi, bj) = (boxes[i], boxes[j]);
            let overlap = (0..3).all(|k| bi.0[k] <= bj.1[k] && bj.0[k] <= bi.1[k]);
            if i == j || !overlap || volume(j) <= volume(i) {
                continue;
            }
            let dj = distances[j].get_or_insert_with(|| {
                SurfaceDistance::new(&SurfaceMesh {
                    positions: surface.positions.clone(),
                    triangles: triangles[j].clone(),
                })
            });
            // Up to 16 vertices spread over component i: all in or all out of j.
            let step = (vertices[i].len() / 16).max(1);
            let inside: Vec<bool> = vertices[i]
                .iter()
                .step_by(step)
                .map(|&v| dj.winding_number(surface.positions[v as usize]).abs() > 0.5)
                .collect();
            if inside.iter().all(|&x| x) {
                // The smallest enclosing component is the direct parent.
                if parent[i].is_none_or(|p: usize| volume(j) < volume(p)) {
                    parent[i] = Some(j);
                }
            } else if inside.iter().any(|&x| x) {
                return None;
            }
        }
    }
    Some(parent)
}
