//! One operation of the repair (issue 41, in progress; `docs/design-repair.md`): the
//! surface cut along a band round one neck loop and the two boundaries closed by caps,
//! which removes the loop's class. A handle loop's caps span the neck inside the solid
//! (the solid is cut through); a tunnel loop's span the hole outside it (the hole is
//! plugged). The choice of loops, the checks and `necklace repair` follow.

use crate::error::{Error, ErrorKind, Result};
use crate::geom::{add, scale, sub};
use crate::loops::{NeckLoop, SurfacePoint};
use crate::mesh::{remove_unreferenced, SurfaceMesh, Topology};
use crate::segment::{segment, CurvePoint};
use crate::surgery::{cap, offset_curves, CapOptions, OnSurface};

/// What [`cut_along_loop`] did.
#[derive(Debug, Clone, PartialEq)]
pub struct Cut {
    /// The surface with the band removed and the caps in.
    pub mesh: SurfaceMesh,
    /// The distance of each side of the band from the loop.
    pub delta: f64,
    /// The two caps' areas.
    pub cap_areas: [f64; 2],
    /// The enclosed volume's change (negative for a cut, positive for a plug).
    pub volume_change: f64,
}

/// Remove the class of `neck` (found on `surface`): the band between the curves at
/// `band` × its radius on either side is cut out and each boundary closed by a cap
/// started on the cone from the loop's saddle, moved with the boundary.
pub fn cut_along_loop(surface: &SurfaceMesh, neck: &NeckLoop, band: f64) -> Result<Cut> {
    // 1. The band's two curves.
    let topology = Topology::new(surface);
    let curve = loop_on_surface(neck);
    let delta = band * neck.radius;
    let offsets = offset_curves(surface, &topology, &curve, delta)?;

    // 2. The surface cut along them; the band is the annulus between them.
    let curves: Vec<Vec<CurvePoint>> = offsets
        .curves
        .iter()
        .map(|c| {
            c.iter()
                .map(|p| match *p {
                    OnSurface::Vertex(v) => CurvePoint::Vertex(v),
                    OnSurface::Edge { edge, t } => CurvePoint::Edge { edge, t },
                })
                .collect()
        })
        .collect();
    let cut = segment(surface, &curves)?;
    let band_segment = cut
        .segments
        .iter()
        .filter(|s| s.euler == 0 && s.boundaries == 2 && s.loops.len() == 2)
        .min_by(|a, b| a.area.total_cmp(&b.area))
        .ok_or_else(|| {
            Error::new(
                ErrorKind::InvalidMesh,
                "the band round the loop is not an annulus between its two curves",
            )
        })?
        .id as u32;
    let kept: Vec<[u32; 3]> = cut
        .mesh
        .triangles
        .iter()
        .zip(&cut.segment_of)
        .filter(|(_, s)| **s != band_segment)
        .map(|(t, _)| *t)
        .collect();

    // 3. A cap on each boundary left.
    let cycles = boundary_cycles(&kept)?;
    if cycles.len() != 2 {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            format!(
                "cutting the band out left {} boundaries, not 2",
                cycles.len()
            ),
        ));
    }
    let loop_centre = centroid(&neck.points);
    let mut positions = cut.mesh.positions.clone();
    let mut triangles = kept;
    let mut cap_areas = [0.0; 2];
    for (k, cycle) in cycles.iter().enumerate() {
        // The cap runs each boundary edge the other way from the surface beside it.
        let ids: Vec<u32> = std::iter::once(cycle[0])
            .chain(cycle[1..].iter().rev().copied())
            .collect();
        let boundary: Vec<[f64; 3]> = ids.iter().map(|&v| positions[v as usize]).collect();
        let apex = add(neck.saddle, sub(centroid(&boundary), loop_centre));
        let disk = cap(&boundary, apex, &CapOptions::default())?;
        cap_areas[k] = disk.area;
        let first = positions.len() as u32;
        let n = ids.len() as u32;
        positions.extend(&disk.mesh.positions[ids.len()..]);
        triangles.extend(disk.mesh.triangles.iter().map(|t| {
            t.map(|v| {
                if v < n {
                    ids[v as usize]
                } else {
                    first + v - n
                }
            })
        }));
    }
    let (mesh, _) = remove_unreferenced(&SurfaceMesh {
        positions,
        triangles,
    });
    let volume_change = mesh.signed_volume() - surface.signed_volume();
    Ok(Cut {
        mesh,
        delta,
        cap_areas,
        volume_change,
    })
}

/// A loop's points on its surface, as the `surgery` stage takes them.
pub fn loop_on_surface(neck: &NeckLoop) -> Vec<OnSurface> {
    neck.surface_points
        .iter()
        .map(|p| match *p {
            SurfacePoint::Vertex { vertex } => OnSurface::Vertex(vertex),
            SurfacePoint::Edge { edge, t } => OnSurface::Edge { edge, t },
        })
        .collect()
}

fn centroid(points: &[[f64; 3]]) -> [f64; 3] {
    let sum = points.iter().fold([0.0; 3], |s, p| add(s, *p));
    scale(sum, 1.0 / points.len().max(1) as f64)
}

/// The boundary cycles of `triangles`: each as its vertices in the order of the
/// triangles' own half-edges along it.
fn boundary_cycles(triangles: &[[u32; 3]]) -> Result<Vec<Vec<u32>>> {
    use std::collections::{BTreeMap, HashSet};
    let half: HashSet<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
        .collect();
    let mut next: BTreeMap<u32, u32> = BTreeMap::new();
    for &(a, b) in &half {
        if !half.contains(&(b, a)) && next.insert(a, b).is_some() {
            return Err(Error::new(
                ErrorKind::InvalidMesh,
                format!("vertex {a} starts two boundary edges: the band's curves touch"),
            ));
        }
    }
    let mut cycles = Vec::new();
    let mut done: HashSet<u32> = HashSet::new();
    for &start in next.keys() {
        if done.contains(&start) {
            continue;
        }
        let mut cycle = vec![start];
        done.insert(start);
        let mut v = next[&start];
        while v != start {
            if !done.insert(v) {
                return Err(Error::new(
                    ErrorKind::InvalidMesh,
                    "a boundary of the cut does not close",
                ));
            }
            cycle.push(v);
            v = *next.get(&v).ok_or_else(|| {
                Error::new(
                    ErrorKind::InvalidMesh,
                    "a boundary of the cut does not close",
                )
            })?;
        }
        cycles.push(cycle);
    }
    Ok(cycles)
}
