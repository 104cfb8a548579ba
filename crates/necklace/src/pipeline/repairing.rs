//! Repair: handles and tunnels removed along their neck loops (the plan:
//! `docs/design-repair.md`).
//!
//! One operation ([`cut_along_loop`]) cuts the surface along a band round one neck loop and
//! closes the two boundaries with caps, which removes the loop's class. A handle loop's
//! caps span the neck inside the solid (the solid is cut through); a tunnel loop's span the
//! hole outside it (the hole is plugged). Its steps: `surgery::refine_near` where the loop
//! is coarse (until it crosses edges no longer than a quarter of its radius),
//! `surgery::offset_curves`, `segment` along both curves, the band's segment cut out, and
//! `surgery::cap` on each boundary.
//!
//! [`repair`] reads as the recipe:
//! 1. The input step (welding, orientation); refuse what cannot be repaired (open,
//!    crossing itself, a target genus above the surface's) before any loop is sought;
//!    then `find_necks`.
//! 2. The candidates: the loops of the kinds asked for that do not separate the
//!    surface (and, with a length bound, the shorter ones), shortest first (a cap's area grows with its loop's length squared,
//!    so this is cheapest first).
//! 3. One at a time: the operation (the surface refined near a coarse loop; its caps
//!    faired to the least area, or harmonic, then cones from the saddle, where those
//!    cross the surface), then its checks — a valid closed solid, the same components,
//!    the genus one lower (a class that depends on removed ones would cut a part off or
//!    enclose a cavity), no crossings (of the caps' triangles: the rest lies in the
//!    input's, which did not cross). A failed check skips the loop with its reason; a
//!    kept one replaces the surface, and the other candidates are carried onto it where
//!    the cut left their edges alone. One that crosses the band is skipped with that
//!    reason (reported unless the genus asked for is reached without it).
//! 4. Another `find_necks` run while the genus is above the target, or, with a length
//!    bound, for loops the cuts disturbed elsewhere; at most `max_loop_runs` in all.

use std::collections::HashSet;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::NeckOptions;
use crate::distance::{crossings_among, SurfaceDistance};
use crate::error::{Error, ErrorKind, Result};
use crate::geom::{add, closest_on_segment, norm, scale, sub};
use crate::loops::{NeckLoop, SurfacePoint};
use crate::mesh::{remove_unreferenced, MeshReport, Side, SurfaceMesh, Topology};
use crate::progress::{Progress, Silent};
use crate::segment::{segment, CurvePoint};
use crate::surgery::{cap, offset_curves, refine_near, CapOptions, Fairing, OnSurface, Refined};

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
    /// For each vertex of the surface cut, its index in `mesh` (`u32::MAX`: removed with
    /// the band).
    pub vertex_map: Vec<u32>,
    /// The caps' vertices off their boundaries (the new points of the surface).
    pub cap_points: Vec<[f64; 3]>,
    /// The caps' triangles are `mesh.triangles[caps_from..]`; the others lie in the
    /// input's triangles.
    pub caps_from: usize,
    /// How the caps were faired.
    pub fairing: Fairing,
    /// The surface was refined within this distance of the loop (0: not refined).
    pub refined_within: f64,
}

/// The band's width a coarse loop's surface is refined for, as a fraction of the
/// loop's radius (the refinement reaches three times this from the loop).
const MIN_BAND: f64 = 0.125;

/// Each side of the band lies at least this fraction of the mean length of the edges
/// the loop crosses from it. (At half an edge, bands on the coarse wires of a wire
/// sphere were wider than a wire, and no window could be plugged.)
const MIN_BAND_EDGES: f64 = 0.1;

/// A loop of fewer points than this is coarse: its surface is refined before the cut (a
/// boot's eyelet crosses 15 edges, each twice its radius). A finer loop is cut on the
/// surface as it is: refining a wire sphere's wires, whose loops cross 55–62 edges up
/// to three times their radius long, multiplies the cut's triangles and its caps' size.
const COARSE_LOOP: usize = 24;

/// Remove the class of `neck` (found on `surface`): where the loop is coarse (fewer
/// than 24 points) the surface near it is refined until the loop crosses
/// edges no longer than a quarter of its radius; the
/// band between the curves at `band` × its radius (at least a tenth of the mean length
/// of the edges it crosses) on either side is cut out and each boundary closed by a cap
/// started on the cone from the loop's saddle, moved with the boundary, and faired as
/// `fairing` says.
pub fn cut_along_loop(
    surface: &SurfaceMesh,
    neck: &NeckLoop,
    band: f64,
    fairing: Fairing,
) -> Result<Cut> {
    // 1. A coarse loop: the surface near it refined until the loop crosses edges no
    // longer than a quarter of its radius. Then the band's two curves.
    let coarse = neck.surface_points.len() < COARSE_LOOP;
    let refined_within = if coarse {
        3.0 * band.max(MIN_BAND) * neck.radius
    } else {
        0.0
    };
    let refined = if coarse {
        refine_near(
            surface,
            &Topology::new(surface),
            &loop_on_surface(neck),
            neck.radius / 4.0,
            refined_within,
        )?
    } else {
        Refined {
            mesh: surface.clone(),
            curve: loop_on_surface(neck),
            splits: 0,
        }
    };
    let (curve, input) = (refined.curve, surface);
    let surface = &refined.mesh;
    let topology = Topology::new(surface);
    // At least a tenth of an edge: a band much narrower than the triangles it crosses
    // leaves curves too close to the loop's vertices to be told apart.
    let edges: Vec<f64> = curve
        .iter()
        .filter_map(|p| match *p {
            OnSurface::Edge { edge: [a, b], .. } => Some(norm(sub(
                surface.positions[a as usize],
                surface.positions[b as usize],
            ))),
            OnSurface::Vertex(_) => None,
        })
        .collect();
    let mean_edge = edges.iter().sum::<f64>() / edges.len().max(1) as f64;
    let delta = (band * neck.radius).max(MIN_BAND_EDGES * mean_edge);
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
        .ok_or_else(|| Error::new(ErrorKind::InvalidMesh, NO_ANNULUS))?
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
    let mut cap_points = Vec::new();
    let caps_from = triangles.len();
    for (k, cycle) in cycles.iter().enumerate() {
        // The cap runs each boundary edge the other way from the surface beside it.
        let ids: Vec<u32> = std::iter::once(cycle[0])
            .chain(cycle[1..].iter().rev().copied())
            .collect();
        let boundary: Vec<[f64; 3]> = ids.iter().map(|&v| positions[v as usize]).collect();
        let apex = add(neck.saddle, sub(centroid(&boundary), loop_centre));
        let options = CapOptions {
            fairing,
            ..CapOptions::default()
        };
        let disk = cap(&boundary, apex, &options)?;
        cap_areas[k] = disk.area;
        let first = positions.len() as u32;
        let n = ids.len() as u32;
        positions.extend(&disk.mesh.positions[ids.len()..]);
        cap_points.extend(&disk.mesh.positions[ids.len()..]);
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
    let (mesh, kept) = remove_unreferenced(&SurfaceMesh {
        positions,
        triangles,
    });
    // The refined surfaces keep the input's vertices first, with their indices.
    let mut vertex_map = vec![u32::MAX; input.positions.len()];
    for (new, &old) in kept.iter().enumerate() {
        if let Some(slot) = vertex_map.get_mut(old as usize) {
            *slot = new as u32;
        }
    }
    let volume_change = mesh.signed_volume() - input.signed_volume();
    Ok(Cut {
        mesh,
        delta,
        cap_areas,
        volume_change,
        vertex_map,
        cap_points,
        caps_from,
        fairing,
        refined_within,
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

/// What [`repair`] removes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RepairTarget {
    /// Classes until the surface has this genus (default 0), cheapest first.
    Genus(usize),
    /// Every loop shorter than this, whatever genus results (topological noise).
    MaxLength(f64),
}

/// Options of [`repair`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RepairOptions {
    /// What to remove (default genus 0).
    pub target: RepairTarget,
    /// Only handles (`Inside`: cuts) or only tunnels (`Outside`: plugs); default both.
    pub only: Option<Side>,
    /// Each side of the band a cut removes lies this fraction of the loop's radius from
    /// it, at least a tenth of an edge (default 0.15: a narrower gap between a cut's caps
    /// makes the output hard to mesh for a later `find_necks`; at 0.05 the skull's
    /// took over 10 minutes instead of 15 s).
    pub band: f64,
    /// The loops' options.
    pub necks: NeckOptions,
    /// Most `find_necks` runs (default 4): loops a cut disturbed are found again by the
    /// next run.
    pub max_loop_runs: usize,
}

impl Default for RepairOptions {
    fn default() -> Self {
        RepairOptions {
            target: RepairTarget::Genus(0),
            only: None,
            band: 0.15,
            necks: NeckOptions::default(),
            max_loop_runs: 4,
        }
    }
}

/// The loop an operation is about.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RepairLoop {
    /// `handle` (the solid cut through) or `tunnel` (the hole plugged).
    #[serde(
        serialize_with = "Side::serialize_as_neck",
        deserialize_with = "Side::deserialize_from_neck"
    )]
    pub kind: Side,
    /// The loop's length.
    pub loop_length: f64,
    /// Its centre.
    pub center: [f64; 3],
}

impl From<&NeckLoop> for RepairLoop {
    fn from(neck: &NeckLoop) -> RepairLoop {
        RepairLoop::of(neck)
    }
}

impl RepairLoop {
    fn of(neck: &NeckLoop) -> RepairLoop {
        RepairLoop {
            kind: neck.kind,
            loop_length: neck.length,
            center: neck.center,
        }
    }
}

/// One kept operation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RepairOperation {
    /// Its loop.
    #[serde(flatten)]
    pub neck: RepairLoop,
    /// The band's width (twice the distance of each side from the loop).
    pub band_width: f64,
    /// The two caps' area.
    pub cap_area: f64,
    /// How the caps were faired: `minimal_area`, or `harmonic` or `cone` where the
    /// faired ones crossed the surface.
    pub caps: Fairing,
    /// The enclosed volume's change.
    pub volume_change: f64,
    /// The largest distance from a cap's vertex to the input surface: how far the
    /// surface moved.
    pub max_displacement: f64,
    /// The `find_necks` run that found the loop (1: the first).
    pub run: usize,
    /// The loop's points (on the surface it was found on).
    pub points: Vec<[f64; 3]>,
}

/// A loop not removed, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RepairSkip {
    /// Its loop.
    #[serde(flatten)]
    pub neck: RepairLoop,
    /// Why, one line.
    pub reason: String,
}

/// What [`repair`] did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RepairReport {
    /// Genus before and after (summed over the components).
    pub genus: [i64; 2],
    /// Enclosed volume before and after.
    pub volume: [f64; 2],
    /// The operations kept, in order.
    pub operations: Vec<RepairOperation>,
    /// The loops not removed, with reasons.
    pub skipped: Vec<RepairSkip>,
    /// `find_necks` runs.
    pub loop_runs: usize,
    /// Hausdorff distance between the input and the output (over their vertices).
    pub hausdorff: f64,
    /// What the caller should know: a target not reached, with the genus reached.
    pub warnings: Vec<String>,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// Remove handles and tunnels of `surface` along their neck loops (see the module doc).
/// Returns the repaired surface and the report.
pub fn repair(
    surface: &SurfaceMesh,
    options: &RepairOptions,
) -> Result<(SurfaceMesh, RepairReport)> {
    repair_with_progress(surface, options, &Silent)
}

/// [`repair`], reporting each `find_necks` run's stages to `progress`.
pub fn repair_with_progress(
    surface: &SurfaceMesh,
    options: &RepairOptions,
    progress: &dyn Progress,
) -> Result<(SurfaceMesh, RepairReport)> {
    let started = Instant::now();
    check_options(options)?;
    // 1. What can be repaired, refused before any loop is sought; then the loops.
    let prepared = super::prepare_input_with(surface.clone(), &options.necks.input)?;
    let genus_before = solid_genus(&prepared.mesh_report)?;
    if let RepairTarget::Genus(g) = options.target {
        if g as i64 > genus_before {
            return Err(Error::invalid_argument(format!(
                "--genus {g}: the surface has genus {genus_before}; repair only removes handles and tunnels"
            )));
        }
    }
    if !prepared.crossing_faces.is_empty() {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            format!(
                "the surface crosses itself ({} triangles): repair needs a surface that does not",
                prepared.crossing_faces.len()
            ),
        ));
    }
    let first = super::find_necks_with_progress(&prepared.mesh, &options.necks, progress)?;
    let input = first.surface.clone();
    let input_distance = SurfaceDistance::without_winding(&input);
    let components = MeshReport::new(&input).components;
    let done = |genus: i64| matches!(options.target, RepairTarget::Genus(g) if genus <= g as i64);

    let mut current = input.clone();
    let mut genus = genus_before;
    let mut candidates = select(first.loops, options, 1);
    let mut operations = Vec::new();
    let mut skipped: Vec<RepairSkip> = Vec::new();
    // Loops that crossed a band cut before them: reported unless the genus asked for
    // was reached without them.
    let mut crossed: Vec<RepairSkip> = Vec::new();
    let mut runs = 1;
    loop {
        // 3. One operation at a time.
        let mut kept_this_run = 0;
        let mut disturbed = 0;
        let mut queue = std::mem::take(&mut candidates).into_iter();
        while let Some((neck, run)) = queue.next() {
            if done(genus) {
                break;
            }
            let outcome = operate(&current, &neck, options.band, components, genus - 1);
            match outcome {
                Ok(cut) => {
                    operations.push(RepairOperation {
                        neck: RepairLoop::of(&neck),
                        band_width: 2.0 * cut.delta,
                        cap_area: cut.cap_areas[0] + cut.cap_areas[1],
                        caps: cut.fairing,
                        volume_change: cut.volume_change,
                        max_displacement: input_distance
                            .distances(&cut.cap_points)
                            .into_iter()
                            .fold(0.0, f64::max),
                        run,
                        points: neck.points.clone(),
                    });
                    genus -= 1;
                    kept_this_run += 1;
                    // The others carried onto the cut surface. One that reaches the
                    // band crosses the loop just cut: skipped (its class is gone when it
                    // crossed it an odd number of times). Others the cut disturbed wait
                    // for the next run.
                    let edges = edge_set(&cut.mesh);
                    let reach = cut.refined_within + cut.delta;
                    let mut carried = Vec::new();
                    for (other, r) in queue {
                        if let Some(moved) = carry(&other, &cut.vertex_map, &edges) {
                            carried.push((moved, r));
                        } else if distance_between(&other.points, &neck.points) <= reach {
                            skip(
                                &mut crossed,
                                &other,
                                format!(
                                    "it crosses the band of the {} loop of length {:.4e} removed before it: its class went with it (crossing it an odd number of times) or waits for a later loop run",
                                    neck.kind.neck_name(),
                                    neck.length
                                ),
                            );
                        } else {
                            disturbed += 1;
                        }
                    }
                    queue = carried.into_iter();
                    current = cut.mesh;
                }
                Err(reason) => skip(&mut skipped, &neck, reason),
            }
        }
        // 4. Another run for the loops the cuts disturbed.
        // (With a length bound, only loops a cut disturbed can still be short.)
        let bound = matches!(options.target, RepairTarget::MaxLength(_));
        if done(genus)
            || runs >= options.max_loop_runs
            || kept_this_run == 0
            || bound && disturbed == 0
        {
            break;
        }
        let again = super::find_necks_with_progress(&current, &options.necks, progress)?;
        runs += 1;
        current = again.surface;
        candidates = select(again.loops, options, runs);
        if candidates.is_empty() {
            break;
        }
    }
    if !done(genus) {
        for c in crossed {
            skip(&mut skipped, c.neck, c.reason);
        }
    }
    let mut warnings = Vec::new();
    if let RepairTarget::Genus(g) = options.target {
        if genus > g as i64 {
            warnings.push(format!(
                "genus {genus} reached, not {g}: {} loops could not be removed (see skipped) after {runs} loop runs",
                skipped.len()
            ));
        }
    }
    let hausdorff = hausdorff(&input, &input_distance, &current);
    let report = RepairReport {
        genus: [genus_before, genus],
        volume: [input.signed_volume(), current.signed_volume()],
        operations,
        skipped,
        loop_runs: runs,
        hausdorff,
        warnings,
        seconds: started.elapsed().as_secs_f64(),
    };
    Ok((current, report))
}

fn check_options(options: &RepairOptions) -> Result<()> {
    if !(options.band > 0.0 && options.band <= 0.5) {
        return Err(Error::invalid_argument(format!(
            "--band {}: it must lie in (0, 0.5] (a fraction of the loop's radius)",
            options.band
        )));
    }
    if let RepairTarget::MaxLength(l) = options.target {
        if !(l > 0.0 && l.is_finite()) {
            return Err(Error::invalid_argument(format!(
                "--max-length {l}: it must be a positive length"
            )));
        }
    }
    if options.max_loop_runs == 0 {
        return Err(Error::invalid_argument("max_loop_runs must be at least 1"));
    }
    Ok(())
}

/// The genus of a closed solid, summed over its components; an error otherwise.
fn solid_genus(report: &MeshReport) -> Result<i64> {
    if !report.is_valid_solid() {
        return Err(Error::new(
            ErrorKind::InvalidMesh,
            format!(
                "repair needs a closed, manifold, oriented surface: {}",
                report.problems().join("; ")
            ),
        ));
    }
    report
        .genus
        .iter()
        .map(|g| g.ok_or_else(|| Error::new(ErrorKind::InvalidMesh, "a component has no genus")))
        .sum()
}

/// Step 2: the loops to remove (not separating ones), shortest first, each with the run that found it.
fn select(loops: Vec<NeckLoop>, options: &RepairOptions, run: usize) -> Vec<(NeckLoop, usize)> {
    let mut chosen: Vec<(NeckLoop, usize)> = loops
        .into_iter()
        .filter(|l| options.only.is_none_or(|side| l.kind == side))
        // A separating loop bounds a part: it is no class to remove.
        .filter(|l| !l.separating)
        .filter(|l| match options.target {
            RepairTarget::MaxLength(max) => l.length < max,
            RepairTarget::Genus(_) => true,
        })
        .map(|l| (l, run))
        .collect();
    chosen.sort_by(|a, b| a.0.length.total_cmp(&b.0.length));
    chosen
}

/// Record that `neck` is not removed, and why; the same loop found again by a later
/// run is reported once.
fn skip(skipped: &mut Vec<RepairSkip>, neck: impl Into<RepairLoop>, reason: String) {
    let neck = neck.into();
    let same = |s: &RepairSkip| {
        s.neck.kind == neck.kind
            && (s.neck.loop_length - neck.loop_length).abs() <= 1e-9 * neck.loop_length
    };
    if !skipped.iter().any(same) {
        skipped.push(RepairSkip { neck, reason });
    }
}

/// The least distance from a point of `a` to the closed polyline `b`.
fn distance_between(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let n = b.len();
    a.iter()
        .flat_map(|&p| {
            (0..n).map(move |k| norm(sub(p, closest_on_segment(p, b[k], b[(k + 1) % n]))))
        })
        .fold(f64::MAX, f64::min)
}

/// Step 3: the cut along `neck`, checked; where its faired caps cross the surface,
/// the harmonic caps, then the cones from the saddle, are tried (a cap that follows
/// the membrane's cone bends less far from the neck); where the band's curves are not
/// found or do not bound an annulus (a tunnel round a window of thin wires: the band
/// is wider than a wire), the band is narrowed to a half, then a quarter.
fn operate(
    surface: &SurfaceMesh,
    neck: &NeckLoop,
    band: f64,
    components: usize,
    genus: i64,
) -> std::result::Result<Cut, String> {
    let mut outcome = Err(String::new());
    'bands: for narrowed in [band, band / 2.0, band / 4.0] {
        for fairing in [Fairing::MinimalArea, Fairing::Harmonic, Fairing::Cone] {
            outcome = cut_along_loop(surface, neck, narrowed, fairing)
                .map_err(|e| e.message().to_string())
                .and_then(|cut| checked(cut, components, genus));
            match &outcome {
                Err(reason) if reason.starts_with(CROSSING) => continue,
                Err(reason) if reason.starts_with(NO_CURVE) || reason.starts_with(NO_ANNULUS) => {
                    continue 'bands
                }
                _ => break 'bands,
            }
        }
        break;
    }
    outcome
}

/// The start of the reason a band's curves were not found (`surgery::offset_curves`).
const NO_CURVE: &str = "no closed curve at distance";

/// The reason the band's curves do not bound an annulus.
const NO_ANNULUS: &str = "the band round the loop is not an annulus between its two curves";

/// The start of the reason a cut is refused for caps that cross the surface.
const CROSSING: &str = "its caps cross the surface";

/// Step 3's checks: the cut surface is a valid solid of the same components and genus
/// `genus`, and does not cross itself.
fn checked(cut: Cut, components: usize, genus: i64) -> std::result::Result<Cut, String> {
    let report = MeshReport::new(&cut.mesh);
    if !report.is_valid_solid() {
        return Err(format!(
            "the cut leaves an invalid surface: {}",
            report.problems().join("; ")
        ));
    }
    if report.components != components {
        return Err(format!(
            "the cut leaves {} components, not {components}: its class is a sum of removed ones (it would cut a part off or enclose a cavity)",
            report.components
        ));
    }
    let found: i64 = report.genus.iter().flatten().sum();
    if found != genus {
        return Err(format!("the cut leaves genus {found}, not {genus}"));
    }
    // The rest lies in the input's triangles (split in their planes), which did not
    // cross: only the caps can.
    let caps: Vec<u32> = (cut.caps_from as u32..cut.mesh.triangles.len() as u32).collect();
    let crossings = crossings_among(&cut.mesh, &caps);
    if !crossings.is_empty() {
        return Err(format!(
            "{CROSSING} ({} pairs of triangles), faired, harmonic or as cones",
            crossings.len()
        ));
    }
    Ok(cut)
}

fn edge_set(mesh: &SurfaceMesh) -> HashSet<[u32; 2]> {
    mesh.triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| [t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])]))
        .collect()
}

/// `neck` on the cut surface, when every point of it is on a vertex or an edge the cut
/// kept.
fn carry(neck: &NeckLoop, map: &[u32], edges: &HashSet<[u32; 2]>) -> Option<NeckLoop> {
    let moved = |v: u32| map.get(v as usize).copied().filter(|&m| m != u32::MAX);
    let points: Option<Vec<SurfacePoint>> = neck
        .surface_points
        .iter()
        .map(|p| match *p {
            SurfacePoint::Vertex { vertex } => {
                moved(vertex).map(|vertex| SurfacePoint::Vertex { vertex })
            }
            SurfacePoint::Edge { edge: [a, b], t } => {
                let e = [moved(a)?, moved(b)?];
                edges
                    .contains(&[e[0].min(e[1]), e[0].max(e[1])])
                    .then_some(SurfacePoint::Edge { edge: e, t })
            }
        })
        .collect();
    let mut out = neck.clone();
    out.surface_points = points?;
    Some(out)
}

/// The largest distance from a vertex of either surface to the other (`to_a`: the
/// distance to `a`).
fn hausdorff(a: &SurfaceMesh, to_a: &SurfaceDistance, b: &SurfaceMesh) -> f64 {
    let ab = SurfaceDistance::without_winding(b).distances(&a.positions);
    let ba = to_a.distances(&b.positions);
    ab.into_iter().chain(ba).fold(0.0, f64::max)
}
