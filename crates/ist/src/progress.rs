//! Progress of the library's long stages on stderr: bars (indicatif) on a terminal, plain
//! stage lines otherwise, nothing with `--quiet`.
//!
//! Why plain lines: indicatif draws nothing when stderr is not a terminal, so a build run
//! from a script, CI or `ist build ... 2> build.log` would be silent for minutes. A line
//! when each stage starts and ends (with the seconds since the command started) tells a
//! log reader where a slow or stuck build is, without the carriage-return noise of bars.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use innersphere::progress::Progress;
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::Instant;

/// How progress is shown.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Mode {
    Quiet,
    Bars,
    Lines,
}

/// Draws one bar per stage on a terminal's stderr, prints one line per stage start and end
/// when stderr is not a terminal, or nothing when quiet.
pub struct Bars {
    mode: Mode,
    started: Instant,
    bar: Mutex<Option<ProgressBar>>,
    /// The running stage's name and start (plain-line mode).
    stage: Mutex<Option<(String, Instant)>>,
}

impl Bars {
    /// Progress on stderr unless `quiet`: bars on a terminal, plain lines otherwise.
    pub fn new(quiet: bool) -> Self {
        let mode = if quiet {
            Mode::Quiet
        } else if std::io::stderr().is_terminal() {
            Mode::Bars
        } else {
            Mode::Lines
        };
        Bars {
            mode,
            started: Instant::now(),
            bar: Mutex::new(None),
            stage: Mutex::new(None),
        }
    }

    /// Seconds since the command started, right-aligned for a column of lines.
    fn stamp(&self) -> String {
        format!("[{:7.2} s]", self.started.elapsed().as_secs_f64())
    }
}

impl Progress for Bars {
    fn start(&self, stage: &str, total: u64) {
        match self.mode {
            Mode::Quiet => {}
            Mode::Lines => {
                eprintln!("{} {stage} ...", self.stamp());
                if let Ok(mut s) = self.stage.lock() {
                    *s = Some((stage.to_string(), Instant::now()));
                }
            }
            Mode::Bars => {
                let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
                bar.set_style(
                    ProgressStyle::with_template(
                        "{msg:>24} [{bar:40}] {percent:>3}% {elapsed_precise}",
                    )
                    .expect("valid template")
                    .progress_chars("=> "),
                );
                bar.set_message(stage.to_string());
                if let Ok(mut b) = self.bar.lock() {
                    *b = Some(bar);
                }
            }
        }
    }
    fn advance(&self, n: u64) {
        if self.mode != Mode::Bars {
            return;
        }
        if let Ok(b) = self.bar.lock() {
            if let Some(b) = b.as_ref() {
                b.inc(n);
            }
        }
    }
    fn finish(&self) {
        match self.mode {
            Mode::Quiet => {}
            Mode::Lines => {
                if let Some((stage, t)) = self.stage.lock().ok().and_then(|mut s| s.take()) {
                    eprintln!(
                        "{} {stage}: done in {:.2} s",
                        self.stamp(),
                        t.elapsed().as_secs_f64()
                    );
                }
            }
            Mode::Bars => {
                if let Ok(mut b) = self.bar.lock() {
                    if let Some(b) = b.take() {
                        b.finish_and_clear();
                    }
                }
            }
        }
    }
}
