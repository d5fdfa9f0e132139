//! What a benchmark run reports as it goes, and the progress it prints for it: a bar
//! redrawn in place (a terminal, a notebook) or a line per finished episode (a log),
//! each with the episodes done, their rate and the time left.

use std::time::{Duration, Instant};

use coherent_core::text::shown;

use crate::harness::results::ResultLine;
use crate::records::transcript::{Status, headline};

/// What the harness reports as it goes.
#[derive(Debug)]
pub enum Event<'a> {
    /// Before the first episode: how many to run, how many were already done.
    Start { to_run: usize, skipped: usize },
    /// An episode ended and its line is on disk.
    Finished(&'a ResultLine),
    /// A model call has been running for `waited` (told every second or so while one is
    /// slow): `text` says for whom (`waiting 12s for the assigner`).
    Waiting { waited: Duration, text: &'a str },
}

/// How progress is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// One line redrawn in place (a carriage return, no newline): a terminal, a notebook.
    Bar,
    /// One line per finished episode: a log file, a pipe.
    Lines,
}

/// The bar's width in characters.
const BAR: usize = 24;

/// A run's progress, as text to print.
#[derive(Debug)]
pub struct Progress {
    style: Style,
    start: Instant,
    to_run: usize,
    done: usize,
    successes: usize,
    counted: usize,
    /// The wait last told in a line of its own ([`Style::Lines`]), in seconds.
    told: u64,
}

/// Whether a wait of `waited` seconds is worth a line of its own in a log when one of
/// `told` seconds was told last: after 5, 15 and 30 s, then every minute.
pub fn worth_a_line(waited: u64, told: u64) -> bool {
    let mark = |s: u64| match s {
        0..5 => 0,
        5..15 => 5,
        15..30 => 15,
        30..60 => 30,
        s => s / 60 * 60,
    };
    mark(waited) > mark(told)
}

impl Progress {
    pub fn new(style: Style) -> Progress {
        Progress {
            style,
            start: Instant::now(),
            to_run: 0,
            done: 0,
            successes: 0,
            counted: 0,
            told: 0,
        }
    }

    pub fn style(&self) -> Style {
        self.style
    }

    /// The text to print for `event` (for [`Style::Bar`], starting with a carriage
    /// return and without a newline, except an episode's error, which stays on a line of
    /// its own), or `None`.
    pub fn line(&mut self, event: &Event<'_>) -> Option<String> {
        match event {
            Event::Start { to_run, skipped } => {
                self.to_run = *to_run;
                self.start = Instant::now();
                Some(format!(
                    "{} episodes: {skipped} already finished in the results file, {to_run} to run\n",
                    to_run + skipped
                ))
            }
            Event::Waiting { waited, text } => {
                let secs = waited.as_secs();
                match self.style {
                    Style::Bar => Some(format!(
                        "\r\x1b[2K{} | {text}",
                        self.head(self.start.elapsed())
                    )),
                    Style::Lines if worth_a_line(secs, self.told) => {
                        self.told = secs;
                        Some(format!("{text}\n"))
                    }
                    Style::Lines => None,
                }
            }
            Event::Finished(line) => {
                self.done += 1;
                self.told = 0;
                if line.is_final() {
                    self.counted += 1;
                    self.successes += usize::from(line.success);
                }
                let head = self.head(self.start.elapsed());
                let episode = line.episode();
                let said = line.error.as_deref().unwrap_or("");
                let error = match line.status {
                    Status::Error => Some(format!(
                        "{episode}: error: {}; traceback in {}",
                        shown(&headline(said)),
                        shown(&line.transcript)
                    )),
                    // Why it could not go on (a robot, no transcript).
                    _ if line.failed_with_error() => Some(format!(
                        "{episode}: {}: {}",
                        status_word(line.status),
                        shown(&headline(said))
                    )),
                    _ => None,
                };
                Some(match (self.style, error) {
                    // An error must outlive the bar's next redraw.
                    (Style::Bar, Some(error)) => format!("\r\x1b[2K{error}\n{head}"),
                    (Style::Bar, None) => format!(
                        "\r\x1b[2K{head} | last: {episode} {}",
                        status_word(line.status)
                    ),
                    (Style::Lines, Some(error)) => format!("{head} | {error}\n"),
                    (Style::Lines, None) => format!(
                        "{head} | {episode}: {} in {} steps (GT {}), {} LLM calls, {:.1} s\n",
                        status_word(line.status),
                        line.steps,
                        line.gt_steps.map_or("-".to_owned(), |g| g.to_string()),
                        line.llm_calls,
                        line.wall_ms / 1e3
                    ),
                })
            }
        }
    }

    /// The bar (or count), the rate, the time left and the success rate so far, after
    /// `elapsed` of the run.
    fn head(&self, elapsed: Duration) -> String {
        let (done, total) = (self.done, self.to_run.max(self.done));
        let width = total.to_string().len();
        let counts = format!("{done:>width$}/{total} episodes");
        let secs = elapsed.as_secs_f64();
        let rate = if done == 0 || secs <= 0.0 {
            "-".to_owned()
        } else if done as f64 >= secs {
            format!("{:.1} episodes/s", done as f64 / secs)
        } else {
            format!("{:.1} s/episode", secs / done as f64)
        };
        let left = match done {
            0 => "-".to_owned(),
            _ => clock(elapsed.mul_f64((total - done) as f64 / done as f64)),
        };
        let sr = if self.counted == 0 {
            "-".to_owned()
        } else {
            format!("{:.3}", self.successes as f64 / self.counted as f64)
        };
        let tail = format!("{counts}, {rate}, {left} left | SR {sr}");
        match self.style {
            Style::Bar => {
                let filled = (BAR * done).checked_div(total).unwrap_or(BAR);
                format!(
                    "{:>3}% |{}{}| {tail}",
                    (100 * done).checked_div(total).unwrap_or(100),
                    "#".repeat(filled),
                    " ".repeat(BAR - filled)
                )
            }
            Style::Lines => tail,
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
        Status::Conceded => "conceded",
    }
}

/// `1h02m03s`, `2m03s`, `3s`.
pub fn clock(d: Duration) -> String {
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

    #[test]
    fn the_bar_shows_counts_rate_and_time_left() {
        let mut p = Progress::new(Style::Bar);
        p.to_run = 8;
        p.done = 2;
        let head = p.head(Duration::from_secs(4));
        assert_eq!(
            head,
            " 25% |######                  | 2/8 episodes, 2.0 s/episode, 12s left | SR -"
        );
        p.done = 8;
        assert!(p.head(Duration::from_secs(2)).starts_with("100% |####"));
    }

    #[test]
    fn a_slow_call_is_told_in_a_log_after_5_15_and_30_s_then_every_minute() {
        let told: Vec<u64> = (0..200)
            .filter(|&s| worth_a_line(s, s.saturating_sub(1)))
            .collect();
        assert_eq!(told, [5, 15, 30, 60, 120, 180]);
        let mut p = Progress::new(Style::Lines);
        let at = |p: &mut Progress, s| {
            p.line(&Event::Waiting {
                waited: Duration::from_secs(s),
                text: "waiting for the assigner",
            })
        };
        assert_eq!(at(&mut p, 3), None);
        assert_eq!(at(&mut p, 6).as_deref(), Some("waiting for the assigner\n"));
        assert_eq!(at(&mut p, 7), None);
        assert!(at(&mut p, 16).is_some());
    }

    #[test]
    fn the_counts_of_the_start_add_up() {
        let mut p = Progress::new(Style::Lines);
        let text = p.line(&Event::Start {
            to_run: 27,
            skipped: 5,
        });
        assert_eq!(
            text.as_deref(),
            Some("32 episodes: 5 already finished in the results file, 27 to run\n")
        );
    }
}
