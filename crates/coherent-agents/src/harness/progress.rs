//! What a benchmark run reports as it goes, and the progress lines printed for it.

use std::time::{Duration, Instant};

use coherent_core::text::shown;

use crate::harness::results::ResultLine;
use crate::records::transcript::Status;

/// What the harness reports as it goes.
#[derive(Debug)]
pub enum Event<'a> {
    /// Before the first episode: how many to run, how many were already done.
    Start { to_run: usize, skipped: usize },
    /// An episode ended and its line is on disk.
    Finished(&'a ResultLine),
}

/// Progress lines: on a terminal one line redrawn in place, otherwise one line per
/// finished episode.
#[derive(Debug)]
pub struct Progress {
    terminal: bool,
    start: Instant,
    to_run: usize,
    done: usize,
    successes: usize,
    counted: usize,
}

impl Progress {
    pub fn new(terminal: bool) -> Progress {
        Progress {
            terminal,
            start: Instant::now(),
            to_run: 0,
            done: 0,
            successes: 0,
            counted: 0,
        }
    }

    /// The text to print for `event` (for a terminal, with a carriage return and no
    /// newline), or `None`.
    pub fn line(&mut self, event: &Event<'_>) -> Option<String> {
        match event {
            Event::Start { to_run, skipped } => {
                self.to_run = *to_run;
                self.start = Instant::now();
                Some(format!(
                    "{to_run} episodes to run, {skipped} already finished in the results file\n"
                ))
            }
            Event::Finished(line) => {
                self.done += 1;
                if line.is_final() {
                    self.counted += 1;
                    self.successes += usize::from(line.success);
                }
                let sr = if self.counted == 0 {
                    "-".to_owned()
                } else {
                    format!("{:.3}", self.successes as f64 / self.counted as f64)
                };
                let elapsed = self.start.elapsed();
                let left = self.to_run.saturating_sub(self.done);
                let eta = elapsed.mul_f64(left as f64 / self.done as f64);
                let width = self.to_run.to_string().len();
                let head = format!(
                    "[{:>width$}/{}] SR {sr} | ETA {}",
                    self.done,
                    self.to_run,
                    clock(eta)
                );
                Some(if self.terminal {
                    format!(
                        "\r\x1b[2K{head} | last: {} {} task {} seed {} {}",
                        shown(&line.method),
                        shown(&line.scene),
                        line.task_id,
                        line.seed,
                        status_word(line.status)
                    )
                } else {
                    format!(
                        "{head} | {} {} task {} seed {}: {} in {} steps (GT {}), {} LLM calls, {:.1} s\n",
                        shown(&line.method),
                        shown(&line.scene),
                        line.task_id,
                        line.seed,
                        status_word(line.status),
                        line.steps,
                        line.gt_steps.map_or("-".to_owned(), |g| g.to_string()),
                        line.llm_calls,
                        line.wall_ms / 1e3
                    )
                })
            }
        }
    }
}

fn status_word(s: Status) -> &'static str {
    match s {
        Status::Success => "success",
        Status::Failure => "failure",
        Status::BackendError => "backend error",
        Status::Interrupted => "interrupted",
        Status::Error => "error",
    }
}

/// `1h02m03s`, `2m03s`, `3s`.
fn clock(d: Duration) -> String {
    let s = d.as_secs();
    match (s / 3600, s / 60 % 60, s % 60) {
        (0, 0, sec) => format!("{sec}s"),
        (0, m, sec) => format!("{m}m{sec:02}s"),
        (h, m, sec) => format!("{h}h{m:02}m{sec:02}s"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clock_text() {
        assert_eq!(clock(Duration::from_secs(3)), "3s");
        assert_eq!(clock(Duration::from_secs(123)), "2m03s");
        assert_eq!(clock(Duration::from_secs(3723)), "1h02m03s");
    }
}
