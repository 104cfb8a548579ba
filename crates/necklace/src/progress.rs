//! Progress reports from long stages: a stage says when it starts (with its amount of
//! work, when known), how much it has done, and when it ends. The library only calls
//! the trait; the command-line tool draws bars from it. The default, [`Silent`], does
//! nothing. Calls may come from several threads at once (hence `Sync`); the order of
//! `advance` calls from parallel work is not deterministic, but nothing computed depends
//! on it.

/// Receives progress reports.
pub trait Progress: Sync {
    /// A stage named `stage` starts, with `total` units of work (0 when unknown).
    fn start(&self, stage: &str, total: u64);
    /// `units` more units of the current stage are done.
    fn advance(&self, units: u64);
    /// The current stage has ended.
    fn finish(&self);
}

/// Reports nowhere.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Progress for Silent {
    fn start(&self, _stage: &str, _total: u64) {}
    fn advance(&self, _units: u64) {}
    fn finish(&self) {}
}
