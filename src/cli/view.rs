//! `coherent view`: episodes and benchmark results as pages in the browser (made by
//! [`crate::session::view`]).

use std::path::{Path, PathBuf};

use crate::session::engine::{
    DEFAULT_MAX_RESULTS_BYTES, DEFAULT_MAX_TRANSCRIPT_BYTES, MIB, ReadLimits, shown,
};
use clap::Args;

use crate::session::view::{self, Holds, Shown, serve};

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
    /// Serve a results file, or the folder that holds it, on 127.0.0.1: the index
    /// follows the file as a benchmark writes it.
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

pub(crate) fn view(args: &ViewArgs) -> Result<u8, String> {
    let limits = ReadLimits {
        results_bytes: args.max_results_mib.saturating_mul(MIB),
        transcript_bytes: args.max_transcript_mib.saturating_mul(MIB),
    };
    if let Some(dir) = &args.serve {
        let results = serve::results_in(dir, limits)?;
        let server = serve::Server::bind(&results, args.port, limits)?;
        println!(
            "serving {} on http://{}/ (Ctrl-C stops)",
            shown(&results.display().to_string()),
            server.address()?
        );
        server.run()?;
        return Ok(0);
    }
    match args.files.as_slice() {
        [one] => match view::holds(one, limits)? {
            Holds::Transcript => {
                let (task, t) = view::read_episode(one, limits.transcript_bytes)?;
                let html = view::episode_html(&Shown {
                    task: &task,
                    transcript: &t,
                    cost_usd: None,
                })?;
                let out = args
                    .out
                    .clone()
                    .unwrap_or_else(|| one.with_extension("html"));
                view::write(&out, &html)?;
                println!("wrote {}", shown(&out.display().to_string()));
            }
            Holds::Results => {
                let dir = args
                    .out
                    .clone()
                    .unwrap_or_else(|| one.with_extension("view"));
                let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
                let site = view::results_site(one, &dir, threads, limits)?;
                for why in &site.missing {
                    eprintln!("warning: no page for {why}");
                }
                println!(
                    "wrote {} and {} episode pages",
                    shown(&site.index.display().to_string()),
                    site.pages
                );
            }
        },
        [a, b] => {
            for path in [a, b] {
                if view::holds(path, limits)? != Holds::Transcript {
                    return Err(format!(
                        "{}: side by side shows two transcripts, and this is a results file",
                        shown(&path.display().to_string())
                    ));
                }
            }
            let (task_a, ta) = view::read_episode(a, limits.transcript_bytes)?;
            let (task_b, tb) = view::read_episode(b, limits.transcript_bytes)?;
            let html = view::compare_html(
                &Shown {
                    task: &task_a,
                    transcript: &ta,
                    cost_usd: None,
                },
                &Shown {
                    task: &task_b,
                    transcript: &tb,
                    cost_usd: None,
                },
            )?;
            let out = args.out.clone().unwrap_or_else(|| side_by_side(a, b));
            view::write(&out, &html)?;
            println!("wrote {}", shown(&out.display().to_string()));
        }
        _ => return Err("give one transcript, two, or a results file".into()),
    }
    Ok(0)
}

/// `A-vs-B.html` beside `a`.
fn side_by_side(a: &Path, b: &Path) -> PathBuf {
    let stem = |p: &Path| {
        p.file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned())
    };
    a.with_file_name(format!("{}-vs-{}.html", stem(a), stem(b)))
}
