//! One side of a surface up to its selected 2-saddles, as `necklace critical` runs it:
//! the input step, the volume mesh, the exact distance field, and `morse::analyze`
//! ([`find_critical_points`]); and what the surface's topology predicts for the Morse
//! sum.

use serde::Serialize;

use super::{prepare_input_with, volume_field, InputOptions, PreparedSurface};
use crate::distance::SurfaceDistance;
use crate::error::Result;
use crate::mesh::{MeshReport, Side, SurfaceMesh};
use crate::morse::{self, MorseOptions, MorseResult};
use crate::volume::{
    survey_surface, volume_mesh_surveyed, VolumeOptions, VolumeReport, VolumeResult,
};

/// What [`find_critical_points`] computed.
#[derive(Debug, Clone)]
pub struct CriticalRun {
    /// The input as prepared (notes and warnings included).
    pub prepared: PreparedSurface,
    /// The volume mesh of the side.
    pub volume: VolumeResult,
    /// Smoothing, per-level counts and checks, selected and rejected 2-saddles.
    pub result: MorseResult,
}

impl CriticalRun {
    /// What `necklace critical --json` prints.
    pub fn report(&self) -> CriticalReport<'_> {
        CriticalReport {
            side: self.volume.side,
            volume: self.volume.report(),
            surface_morse_expected: surface_morse_expected(
                &self.prepared.mesh_report,
                self.volume.side,
            ),
            morse: &self.result,
        }
    }
}

/// One side of a surface up to its selected 2-saddles: check the options, prepare the
/// input ([`prepare_input_with`]), survey the surface and mesh the side
/// (`volume::survey_surface`, `volume::volume_mesh_surveyed`), then
/// [`critical_points`].
pub fn find_critical_points(
    mesh: SurfaceMesh,
    side: Side,
    input_options: &InputOptions,
    volume_options: &VolumeOptions,
    options: &MorseOptions,
) -> Result<CriticalRun> {
    options.check()?;
    let prepared = prepare_input_with(mesh, input_options)?;
    let start = std::time::Instant::now();
    let (surface, distance) = (&prepared.mesh, &prepared.distance);
    let survey = survey_surface(surface, distance, &prepared.mesh_report, volume_options)?;
    let mut volume = volume_mesh_surveyed(surface, distance, &survey, side)?;
    // The volume stage of one side: its survey and its meshing.
    volume.seconds = start.elapsed().as_secs_f64();
    let result = critical_points_with(&prepared.distance, &volume, options)?;
    Ok(CriticalRun {
        prepared,
        volume,
        result,
    })
}

/// The critical points of one side: the distance field of `volume`'s mesh to
/// `surface`, smoothed, classified, tracked, and its neck 2-saddles selected
/// (`morse::analyze`).
pub fn critical_points(
    surface: &SurfaceMesh,
    volume: &VolumeResult,
    options: &MorseOptions,
) -> Result<MorseResult> {
    critical_points_with(&SurfaceDistance::new(surface), volume, options)
}

/// [`critical_points`] with the surface's distance structure built by the caller.
pub fn critical_points_with(
    distance: &SurfaceDistance,
    volume: &VolumeResult,
    options: &MorseOptions,
) -> Result<MorseResult> {
    let field = volume_field(distance, volume);
    morse::analyze(&volume.mesh, &field, &morse_options_for(options, volume))
}

/// The Morse options for one volume mesh: the scale space starts at twice its lattice
/// spacing unless the caller chose a smallest scale.
pub fn morse_options_for(options: &MorseOptions, volume: &VolumeResult) -> MorseOptions {
    let mut options = *options;
    if options.min_scale.is_none() {
        options.min_scale = Some(2.0 * volume.h);
    }
    options
}

/// The Morse sum a surface's topology predicts for one side (see
/// [`CriticalReport::surface_morse_expected`]).
pub fn surface_morse_expected(report: &MeshReport, side: Side) -> Option<i64> {
    let mut sum = i64::from(side == Side::Outside);
    for component in &report.component_details {
        sum += component.genus? - 1;
    }
    Some(sum)
}

/// What `necklace critical --json` prints: the volume mesh's summary and the Morse
/// stage's result, with what the input surface's topology predicts for the Morse sum.
#[derive(Debug, Clone, Serialize)]
pub struct CriticalReport<'a> {
    /// Which side.
    pub side: Side,
    /// The volume mesh the field lives on.
    pub volume: VolumeReport,
    /// `Σ_i (g_i − 1)` inside, one more outside, over the input surface's components:
    /// the Morse sum when the volume mesh has the surface's topology (`None` when a
    /// component's genus is unknown). Each step's `morse_expected` comes from the mesh
    /// itself; the two differ when the mesher changed the topology (see `volume`).
    pub surface_morse_expected: Option<i64>,
    /// Smoothing, per-step counts and checks, selected and rejected 2-saddles.
    #[serde(flatten)]
    pub morse: &'a MorseResult,
}
