//! `coherent export`: tasks written in another format, PDDL (docs/pddl.md) or the
//! paper's own env lists (docs/task-format.md).

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use super::pddl;
use crate::session::engine::{Limits, Task, shown};
use crate::session::{Error, check};

/// The formats `coherent export` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// A PDDL domain per rule set and a PDDL problem per task.
    Pddl,
    /// The paper's released format: a JSON list of tasks per scene, `<scene>.json`
    /// (heights as labels), which the authors' code runs and `coherent import` reads back.
    Original,
}

#[derive(Args)]
pub struct ExportArgs {
    /// Original env files, native task files or folders of them; `native`: the project's
    /// own benchmark, compiled in.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Only these task ids (repeatable).
    #[arg(long = "task")]
    pub tasks: Vec<i64>,
    /// What to write.
    #[arg(long, value_enum)]
    pub format: Format,
    /// Folder to write the files into.
    #[arg(short, long)]
    pub out: PathBuf,
    /// With `--format pddl`: also write each task's optimal plan as
    /// `<scene>_task-<id>.plan`, a PDDL plan.
    #[arg(long)]
    pub plans: bool,
}

/// Writes the files: exit 1 when a task could not be written in the format (or, with
/// `--plans`, has no plan).
pub fn export(tasks: &[Task], args: &ExportArgs, limits: &Limits) -> Result<u8, Error> {
    match args.format {
        Format::Pddl => pddl::export(tasks, &args.out, args.plans, limits),
        Format::Original if args.plans => Err(Error::Invalid(
            "--plans writes PDDL plans: it goes with --format pddl".into(),
        )),
        Format::Original => {
            let written = check::export_original(tasks, &args.out)?;
            println!(
                "wrote {} tasks in {} files of the original format to {}",
                tasks.len(),
                written.len(),
                shown(&args.out.display().to_string())
            );
            Ok(0)
        }
    }
}
