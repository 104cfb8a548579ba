//! Progress bars on stderr (indicatif) for the library's progress reports: one bar per
//! lane (the two sides of a run go on at the same time, one line each), showing its
//! current stage; a spinner when the amount of work is unknown. Hidden when stderr is
//! not a terminal or with `--quiet`.

use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::Duration;

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use necklace::progress::Progress;

/// Draws each lane's current stage.
pub struct Bars {
    visible: bool,
    lines: MultiProgress,
    current: Mutex<BTreeMap<usize, ProgressBar>>,
}

impl Bars {
    /// Bars drawn only when `wanted` and stderr is a terminal.
    pub fn new(wanted: bool) -> Bars {
        Bars {
            visible: wanted && std::io::stderr().is_terminal(),
            lines: MultiProgress::with_draw_target(ProgressDrawTarget::stderr()),
            current: Mutex::new(BTreeMap::new()),
        }
    }
}

/// A bar for a stage of `total` units, or a spinner when `total` is 0.
fn bar(stage: &str, total: u64) -> ProgressBar {
    let bar = if total == 0 {
        let bar = ProgressBar::new_spinner();
        bar.enable_steady_tick(Duration::from_millis(120));
        bar.set_style(
            ProgressStyle::with_template("{spinner} {msg} {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        bar
    } else {
        let bar = ProgressBar::new(total);
        bar.set_style(
            ProgressStyle::with_template("{msg:42} [{bar:30}] {pos}/{len} {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar
    };
    bar.set_message(stage.to_string());
    bar
}

impl Progress for Bars {
    fn start_lane(&self, lane: usize, stage: &str, total: u64) {
        if !self.visible {
            return;
        }
        let bar = self.lines.add(bar(stage, total));
        if let Ok(mut current) = self.current.lock() {
            if let Some(old) = current.insert(lane, bar) {
                old.finish_and_clear();
                self.lines.remove(&old);
            }
        }
    }

    fn advance_lane(&self, lane: usize, units: u64) {
        if let Ok(current) = self.current.lock() {
            if let Some(bar) = current.get(&lane) {
                bar.inc(units);
            }
        }
    }

    fn finish_lane(&self, lane: usize) {
        if let Ok(mut current) = self.current.lock() {
            if let Some(bar) = current.remove(&lane) {
                bar.finish_and_clear();
                self.lines.remove(&bar);
            }
        }
    }
}

impl Bars {
    /// A bar over `total` meshes of a batch, with done, failed and the ETA; `None` when
    /// bars are hidden.
    pub fn batch(&self, total: u64) -> Option<ProgressBar> {
        if !self.visible {
            return None;
        }
        let bar = ProgressBar::new(total);
        bar.set_style(
            ProgressStyle::with_template("{msg:24} [{bar:30}] {pos}/{len} {elapsed} eta {eta}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        Some(self.lines.add(bar))
    }
}
