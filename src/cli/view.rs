//! `coherent view`: episodes and benchmark results as pages in the browser (asked of
//! [`crate::session::view`] with one [`ViewRequest`]).

use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use clap::Args;

use crate::session::Error;
use crate::session::engine::{
    DEFAULT_MAX_RESULTS_BYTES, DEFAULT_MAX_TRANSCRIPT_BYTES, MIB, ReadLimits, shown, shown_lines,
};
use crate::session::view::{Progress, Source, ViewRequest, Written};

#[derive(Args)]
pub(crate) struct ViewArgs {
    /// A transcript (its episode's page), two transcripts of one task (side by side),
    /// or a results file of `coherent bench` (an index and a page per episode).
    #[arg(required_unless_present = "serve", num_args = 1..=2)]
    files: Vec<PathBuf>,
    /// The page to write (a transcript; by default beside it, ending in .html), or the
    /// folder (a results file; by default beside it, ending in .view).
    #[arg(short, long)]
    out: Option<PathBuf>,
    /// Serve a results file, or the folder that holds it (or will), on 127.0.0.1: the
    /// index follows the file as a benchmark writes it.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["files", "out"])]
    serve: Option<PathBuf>,
    /// The port to serve on (0: any free one).
    #[arg(long, default_value_t = 0, requires = "serve")]
    port: u16,
    /// The most a results file may hold, in MiB.
    #[arg(long, value_name = "MIB", default_value_t = DEFAULT_MAX_RESULTS_BYTES / MIB)]
    max_results_mib: u64,
    /// The most each transcript may hold, in MiB.
    #[arg(long, value_name = "MIB", default_value_t = DEFAULT_MAX_TRANSCRIPT_BYTES / MIB)]
    max_transcript_mib: u64,
}

pub(crate) fn view(args: ViewArgs) -> Result<u8, Error> {
    let limits = ReadLimits {
        results_bytes: args.max_results_mib.saturating_mul(MIB),
        transcript_bytes: args.max_transcript_mib.saturating_mul(MIB),
    };
    if let Some(path) = args.serve {
        let request = ViewRequest {
            source: Source::File(path.clone()),
            other: None,
            limits,
        };
        let server = request.serve(args.port)?;
        let serving = match server.results()? {
            Some(file) => file.display().to_string(),
            None => format!("{} (no results file yet)", path.display()),
        };
        println!(
            "serving {} on http://{}/ (Ctrl-C stops)",
            shown(&serving),
            server.address()?
        );
        server.run()?;
        return Ok(0);
    }
    let mut files = args.files.into_iter().map(Source::File);
    let source = files
        .next()
        .ok_or_else(|| Error::Invalid("give one transcript, two, or a results file".into()))?;
    let request = ViewRequest {
        source,
        other: files.next(),
        limits,
    };
    let told = Told::new(std::io::stderr().is_terminal());
    let written = request.write(args.out, &|p| told.tell(p));
    told.clear();
    let path = |p: &std::path::Path| shown(&p.display().to_string()).into_owned();
    match written? {
        Written::Page { path: page, cut } => {
            for (file, line) in cut {
                eprintln!(
                    "warning: {}: line {line} is cut short (the episode's process stopped or \
                     the disk filled while writing it): the rounds before it are shown",
                    path(&file)
                );
            }
            println!("wrote {}", path(&page));
        }
        Written::Site(site) => {
            for (episode, why) in &site.missing {
                eprintln!(
                    "warning: no page for {}: {}",
                    shown_lines(episode),
                    shown_lines(&why.to_string())
                );
            }
            println!(
                "wrote {} and {} episode pages",
                path(&site.index),
                site.pages
            );
        }
    }
    Ok(0)
}

/// How far a view is, on stderr when it is a terminal: one line, redrawn at most ten
/// times a second, cleared at the end. A long episode takes seconds to follow, a
/// results file's pages minutes.
struct Told {
    terminal: bool,
    /// When the line was last drawn.
    last: Mutex<Option<Instant>>,
}

impl Told {
    fn new(terminal: bool) -> Told {
        Told {
            terminal,
            last: Mutex::new(None),
        }
    }

    fn tell(&self, progress: Progress) {
        if !self.terminal {
            return;
        }
        let (done, of, what) = match progress {
            Progress::Rounds { done, of } => (done, of, "rounds followed"),
            Progress::Pages { done, of } => (done, of, "episode pages written"),
        };
        let Ok(mut last) = self.last.lock() else {
            return;
        };
        let now = Instant::now();
        if last.is_some_and(|t| now - t < Duration::from_millis(100)) && done < of {
            return;
        }
        *last = Some(now);
        eprint!("\r\x1b[2Kviewing: {done}/{of} {what}");
    }

    /// Clears the line, if one was drawn.
    fn clear(&self) {
        if self.last.lock().is_ok_and(|last| last.is_some()) {
            eprint!("\r\x1b[2K");
        }
    }
}
