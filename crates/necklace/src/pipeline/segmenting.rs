//! The loops put to use: the surface cut along them (`necklace segment`).

use crate::error::Result;
use crate::loops::{NeckLoop, SurfacePoint};
use crate::mesh::{orient_consistently, SurfaceMesh};
use crate::segment::{segment, CurvePoint, Segmentation};

/// Cut `surface` along `loops` into segments (the `segment` stage on the loops' surface
/// points). The loops must be on `surface` itself: [`find_necks`](super::find_necks)
/// gives their points on the input's vertices and edges, which is what a `loops.json`
/// holds. The faces are first turned to agree with their neighbours (vertices keep
/// their indices), so that the volumes have one sign.
pub fn segment_along_loops(surface: &SurfaceMesh, loops: &[&NeckLoop]) -> Result<Segmentation> {
    let curves: Vec<Vec<CurvePoint>> = loops
        .iter()
        .map(|l| {
            l.surface_points
                .iter()
                .map(|p| match *p {
                    SurfacePoint::Vertex { vertex } => CurvePoint::Vertex(vertex),
                    SurfacePoint::Edge { edge, t } => CurvePoint::Edge { edge, t },
                })
                .collect()
        })
        .collect();
    let (oriented, _) = orient_consistently(surface);
    segment(&oriented, &curves)
}
