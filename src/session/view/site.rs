//! A results file's pages on disk: `index.html` and a page per episode under
//! `episodes/`, as many written at once as there are cores.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use coherent_agents::bench::{ReadLimits, ResultLine};
use coherent_core::files::Opens;

use super::pages::{Progress, Tell, episode_html, results_html};
use super::read::read_episode;
use super::results;
use crate::session::{Error, Result};

/// What [`write()`] wrote.
#[derive(Debug)]
pub struct Site {
    pub index: PathBuf,
    pub pages: usize,
    /// Episodes without a page (`method scene task N seed S`), and why (a transcript
    /// missing or unreadable).
    pub missing: Vec<(String, Error)>,
}

/// Writes the index of `lines`, read from the results file `results`, to
/// `dir/index.html` and each episode's page under `dir/episodes/`, reading each
/// transcript within `limits`.
pub fn write(
    results: &Path,
    lines: &[ResultLine],
    dir: &Path,
    limits: ReadLimits,
    tell: Tell<'_>,
) -> Result<Site> {
    let names = results::page_names(lines);
    let written: Vec<Mutex<Option<Result<()>>>> = lines.iter().map(|_| Mutex::new(None)).collect();
    let next = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let (Some(line), Some(name)) = (lines.get(i), names.get(i)) else {
                        break;
                    };
                    let done = line_html(results, line, limits.transcript_bytes, Opens::Anything)
                        .and_then(|html| write_page(&dir.join(name), &html));
                    if let Ok(mut slot) = written[i].lock() {
                        *slot = Some(done);
                    }
                    let done = finished.fetch_add(1, Ordering::Relaxed) + 1;
                    tell(Progress::Pages {
                        done,
                        of: lines.len(),
                    });
                }
            });
        }
    });
    let outcome: Vec<Result<()>> = written
        .into_iter()
        .map(|m| {
            m.into_inner()
                .ok()
                .flatten()
                .unwrap_or_else(|| Err(Error::Internal("a page's thread ended without it".into())))
        })
        .collect();
    let links: Vec<Option<String>> = names
        .into_iter()
        .zip(&outcome)
        .map(|(name, o)| o.is_ok().then_some(name))
        .collect();
    let index = dir.join("index.html");
    write_page(&index, &results_html(results, lines, &links, None)?)?;
    let pages = outcome.iter().filter(|o| o.is_ok()).count();
    let missing = lines
        .iter()
        .zip(outcome)
        .filter_map(|(l, o)| o.err().map(|why| (l.episode(), why)))
        .collect();
    Ok(Site {
        index,
        pages,
        missing,
    })
}

/// The page of a results line's episode, from its transcript (of at most `max_bytes`,
/// opened only as `opens` allows), priced as the line.
pub(super) fn line_html(
    results: &Path,
    line: &ResultLine,
    max_bytes: u64,
    opens: Opens,
) -> Result<String> {
    let path = results::transcript_of(results, line).ok_or_else(|| Error::File {
        file: results.display().to_string(),
        line: None,
        message: format!("the transcript {} is not there", line.transcript),
    })?;
    let mut given = read_episode(&path, max_bytes, opens)?;
    given.cost_usd = line.cost_usd;
    episode_html(&given, &|_| {})
}

/// Writes `text` to `path`, making its folder.
pub(super) fn write_page(path: &Path, text: &str) -> Result<()> {
    let failed = |at: &Path, e: std::io::Error| Error::File {
        file: at.display().to_string(),
        line: None,
        message: e.to_string(),
    };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| failed(dir, e))?;
    }
    std::fs::write(path, text).map_err(|e| failed(path, e))
}
