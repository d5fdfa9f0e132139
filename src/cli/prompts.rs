//! `coherent prompts export DIR`: the built-in prompt templates as files, to edit and
//! pass back with `--prompts DIR` (docs/prompts.md lists each template's placeholders).

use std::path::PathBuf;

use clap::{Args, Subcommand};

use crate::session::prompts::PromptSource;
use crate::session::{Error, prompts as session_prompts};

#[derive(Args)]
pub(crate) struct PromptsArgs {
    #[command(subcommand)]
    command: PromptsCommand,
}

#[derive(Subcommand)]
enum PromptsCommand {
    /// Write every built-in template into DIR (made when missing), one file each.
    Export {
        dir: PathBuf,
        /// Overwrite templates already in DIR.
        #[arg(long)]
        force: bool,
        /// The set to write: `paper-layout` (the built-in templates in the paper's
        /// layout) or a folder, with the built-in templates for the files it lacks.
        #[arg(long, value_name = "SET")]
        prompts: Option<PathBuf>,
    },
}

pub(crate) fn prompts(args: &PromptsArgs) -> Result<u8, Error> {
    match &args.command {
        PromptsCommand::Export {
            dir,
            force,
            prompts,
        } => {
            let from = prompts
                .as_deref()
                .map_or(PromptSource::Builtin, PromptSource::from_arg);
            let written = session_prompts::export(dir, *force, from)?;
            println!(
                "wrote {} templates to {}; edit them and pass --prompts {} to run or bench",
                written.len(),
                dir.display(),
                dir.display()
            );
            Ok(0)
        }
    }
}
