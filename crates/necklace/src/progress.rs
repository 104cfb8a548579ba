//! Progress reports from long stages: a stage says when it starts (with its amount of
//! work, when known), how much it has done, and when it ends. The library only calls
//! the trait; the command-line tool draws bars from it. The default, [`Silent`], does
//! nothing. Calls may come from several threads at once (hence `Sync`); the order of
//! `advance` calls from parallel work is not deterministic, but nothing computed depends
//! on it.
//!
//! Parts of a run that go on at the same time (the pipeline's two sides) report through
//! a [`Lane`] each: the same calls, tagged with the lane's number, and the stage named
//! with the lane's label ("volume mesh (outside)").

/// Receives progress reports. An implementation says what to do on each lane; a
/// stage that knows nothing of lanes calls the plain methods, which report on lane 0.
pub trait Progress: Sync {
    /// A stage named `stage` starts on lane `lane`, with `total` units of work (0 when
    /// unknown).
    fn start_lane(&self, lane: usize, stage: &str, total: u64);
    /// `units` more units of lane `lane`'s current stage are done.
    fn advance_lane(&self, lane: usize, units: u64);
    /// Lane `lane`'s current stage has ended.
    fn finish_lane(&self, lane: usize);

    /// A stage named `stage` starts, with `total` units of work (0 when unknown).
    fn start(&self, stage: &str, total: u64) {
        self.start_lane(0, stage, total);
    }
    /// `units` more units of the current stage are done.
    fn advance(&self, units: u64) {
        self.advance_lane(0, units);
    }
    /// The current stage has ended.
    fn finish(&self) {
        self.finish_lane(0);
    }
}

/// Reports nowhere.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Progress for Silent {
    fn start_lane(&self, _lane: usize, _stage: &str, _total: u64) {}
    fn advance_lane(&self, _lane: usize, _units: u64) {}
    fn finish_lane(&self, _lane: usize) {}
}

/// One of several parts of a run that report at the same time: every call goes to
/// `to` on lane `lane` (whatever lane the caller names), and each stage is named
/// `"{stage} ({label})"`.
pub struct Lane<'a> {
    /// Where the reports go.
    pub to: &'a dyn Progress,
    /// The lane's number (0, 1, …), the same for all its calls.
    pub lane: usize,
    /// What the lane works on, added to its stages' names.
    pub label: &'a str,
}

impl Progress for Lane<'_> {
    fn start_lane(&self, _lane: usize, stage: &str, total: u64) {
        self.to
            .start_lane(self.lane, &format!("{stage} ({})", self.label), total);
    }
    fn advance_lane(&self, _lane: usize, units: u64) {
        self.to.advance_lane(self.lane, units);
    }
    fn finish_lane(&self, _lane: usize) {
        self.to.finish_lane(self.lane);
    }
}
