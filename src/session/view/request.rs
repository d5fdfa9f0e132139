//! What a front end asks to see ([`ViewRequest`]): files named by a user (a transcript,
//! two of one task, a results file, the folder a results file is or will be in), an
//! episode in memory, results lines in memory; read here, within the request's limits,
//! and told apart here (a transcript or a results file, by its first line), whichever
//! front end asks. It comes back as one page, as files written, or as a server.

use std::path::{Path, PathBuf};

use coherent_agents::bench::{ReadLimits, ResultLine, read_results_within};
use coherent_core::Task;
use coherent_core::files::Opens;

use super::episode::Given;
use super::pages::{Tell, compare_html, episode_html, results_html};
use super::read::{Holds, holds, read_episode};
use super::serve::Server;
use super::site::{self, Site};
use crate::session::{Error, Result};

/// Something to show.
#[derive(Debug)]
pub enum Source {
    /// A file: a transcript or a results file, told apart by its first line; to serve,
    /// also the folder a results file is (or will be) in.
    File(PathBuf),
    /// An episode in memory (Python's `Episode`).
    Episode(Box<Given>),
    /// Results lines in memory (a results DataFrame), their index titled `name`.
    Lines {
        name: String,
        lines: Vec<ResultLine>,
    },
}

/// What a front end asks to see: `source` alone, or `other` beside it (two episodes of
/// one task, stepping together); every file read within `limits`.
#[derive(Debug)]
pub struct ViewRequest {
    pub source: Source,
    pub other: Option<Source>,
    pub limits: ReadLimits,
}

/// What [`ViewRequest::write`] wrote.
#[derive(Debug)]
pub enum Written {
    /// The page of an episode, or of two side by side; each transcript whose last line
    /// was cut, with the line's number.
    Page {
        path: PathBuf,
        cut: Vec<(PathBuf, usize)>,
    },
    /// A results file's index and its episodes' pages.
    Site(Site),
}

/// An episode as read, and the transcript it was read from (none in memory).
type Episode = (Box<Given>, Option<PathBuf>);

/// Results lines as read, the file they were read from (or their name), and whether
/// that is a file on disk.
type Results = (PathBuf, Vec<ResultLine>, bool);

/// A request, read: what its page shows.
enum Viewed {
    Episode(Episode),
    /// Two episodes of one task.
    Compare(Episode, Episode),
    Results(Results),
}

impl ViewRequest {
    /// The page, in memory: an episode's, two side by side, or a results file's index
    /// (without pages of its episodes, which [`ViewRequest::write`] makes).
    pub fn page(self, tell: Tell<'_>) -> Result<String> {
        match self.read()? {
            Viewed::Episode((given, _)) => episode_html(&given, tell),
            Viewed::Compare((a, _), (b, _)) => compare_html(&a, &b, tell),
            Viewed::Results((file, lines, _)) => results_html(&file, &lines, &[], None),
        }
    }

    /// Writes the page of an episode, or of two side by side, to `out` (by default
    /// beside the first transcript: `A.html`, `A-vs-B.html`), or a results file's
    /// index and a page per episode into the folder `out` (by default beside it:
    /// `RESULTS.view/`).
    pub fn write(self, out: Option<PathBuf>, tell: Tell<'_>) -> Result<Written> {
        let limits = self.limits;
        let beside = |file: Option<&PathBuf>, make: &dyn Fn(&Path) -> PathBuf| {
            out.clone()
                .or_else(|| file.map(|f| make(f)))
                .ok_or_else(|| {
                    Error::Invalid(
                        "an episode in memory has no file to write beside: name the page".into(),
                    )
                })
        };
        let (path, html, cut) = match self.read()? {
            Viewed::Episode((given, file)) => {
                let path = beside(file.as_ref(), &|f| f.with_extension("html"))?;
                let html = episode_html(&given, tell)?;
                (path, html, cut_of([(&given, &file)]))
            }
            Viewed::Compare((a, fa), (b, fb)) => {
                let path = beside(fa.as_ref(), &|f| side_by_side(f, fb.as_deref()))?;
                let html = compare_html(&a, &b, tell)?;
                (path, html, cut_of([(&a, &fa), (&b, &fb)]))
            }
            Viewed::Results((file, lines, true)) => {
                let dir = out.unwrap_or_else(|| file.with_extension("view"));
                return site::write(&file, &lines, &dir, limits, tell).map(Written::Site);
            }
            Viewed::Results((file, ..)) => {
                return Err(Error::Invalid(format!(
                    "{}: results in memory have no transcripts to write pages of",
                    file.display()
                )));
            }
        };
        site::write_page(&path, &html)?;
        Ok(Written::Page { path, cut })
    }

    /// Serves the one results file that `source` names, or that is (or will be) in the
    /// folder it names, on `127.0.0.1:port` (0: any free port).
    pub fn serve(self, port: u16) -> Result<Server> {
        match (self.source, self.other) {
            (Source::File(path), None) => Server::bind(&path, port, self.limits),
            _ => Err(Error::Invalid(
                "only a results file, or the folder it is in, is served".into(),
            )),
        }
    }

    /// Reads what the request names and checks that it can be shown together.
    fn read(self) -> Result<Viewed> {
        let limits = self.limits;
        let first = read(self.source, limits)?;
        let Some(other) = self.other else {
            return Ok(match first {
                Read::Episode(episode) => Viewed::Episode(episode),
                Read::Results(results) => Viewed::Results(results),
            });
        };
        let second = read(other, limits)?;
        match (first, second) {
            (Read::Episode((a, fa)), Read::Episode((b, fb))) => {
                one_task((&a, fa.as_deref()), (&b, fb.as_deref()))?;
                Ok(Viewed::Compare((a, fa), (b, fb)))
            }
            (Read::Results((file, ..)), _) | (_, Read::Results((file, ..))) => {
                Err(Error::Invalid(format!(
                    "{}: side by side shows two episodes, and these are results",
                    file.display()
                )))
            }
        }
    }
}

/// A source, read.
enum Read {
    Episode(Episode),
    Results(Results),
}

/// What `source` holds; a file named by a user is read as every command reads one (a
/// device or a pipe up to its limit).
fn read(source: Source, limits: ReadLimits) -> Result<Read> {
    match source {
        Source::Episode(given) => Ok(Read::Episode((given, None))),
        Source::Lines { name, lines } => Ok(Read::Results((PathBuf::from(name), lines, false))),
        Source::File(path) => match holds(&path, limits, Opens::Anything)? {
            Holds::Transcript => {
                let given = read_episode(&path, limits.transcript_bytes, Opens::Anything)?;
                Ok(Read::Episode((Box::new(given), Some(path))))
            }
            Holds::Results => {
                let lines = read_results_within(&path, limits.results_bytes)?.lines;
                Ok(Read::Results((path, lines, true)))
            }
        },
    }
}

/// Refuses two episodes of different tasks side by side: their rounds would be
/// compared as if one task's, and their first difference would mean nothing.
fn one_task(
    (a, file_a): (&Given, Option<&Path>),
    (b, file_b): (&Given, Option<&Path>),
) -> Result<()> {
    let (ta, tb) = (&a.task, &b.task);
    let same = ta.meta.scene == tb.meta.scene
        && ta.meta.task_id == tb.meta.task_id
        && ta.nodes == tb.nodes
        && ta.init_edges == tb.init_edges
        && ta.goal == tb.goal;
    if same {
        return Ok(());
    }
    let named = |file: Option<&Path>, which: &str| {
        file.map_or_else(|| which.to_owned(), |f| f.display().to_string())
    };
    let (na, nb) = (
        named(file_a, "the first episode"),
        named(file_b, "the second episode"),
    );
    let task = |t: &Task| format!("{} task {}", t.meta.scene, t.meta.task_id);
    let what = if task(ta) == task(tb) {
        format!("two different versions of {}", task(ta))
    } else {
        format!("{} and {}", task(ta), task(tb))
    };
    Err(Error::Invalid(format!(
        "{na} and {nb} are episodes of different tasks ({what}): side by side shows two \
         episodes of one task"
    )))
}

/// The transcripts of `pages` whose last line was cut, with its number.
fn cut_of<const N: usize>(pages: [(&Given, &Option<PathBuf>); N]) -> Vec<(PathBuf, usize)> {
    pages
        .into_iter()
        .filter_map(|(given, file)| Some((file.clone()?, given.cut?)))
        .collect()
}

/// `A-vs-B.html` beside `a`.
fn side_by_side(a: &Path, b: Option<&Path>) -> PathBuf {
    let stem = |p: &Path| {
        p.file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned())
    };
    let other = b.map_or_else(|| "episode".to_owned(), stem);
    a.with_file_name(format!("{}-vs-{other}.html", stem(a)))
}
